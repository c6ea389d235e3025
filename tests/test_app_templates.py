"""issue 15.7 in the window: Canvas ▾ → New canvas from template lists the example canvases installed
plugins offer, and picking one adds it as a new canvas (one undo step), driven offscreen."""

from __future__ import annotations

import pytest
from app_helpers import entry_point_plugins, tap, window_session

from rcon_core.canvas import Binding, Document, Workspace, export_canvas
from rcon_core.plugins import hookimpl

pytest.importorskip("rcon_widgets_std")
pytestmark = pytest.mark.usefixtures("qapp")


class StationTemplate:
    def __init__(self, path):
        self.path = path

    @hookimpl
    def rcon_canvas_templates(self, registry):
        registry.add("Battery station", self.path, description="the battery and the speed limit")


@pytest.fixture
def window(qtbot, tmp_path):
    doc = Document(Workspace.new("Station"))
    doc.add_widget(doc.current.id, "std.label", Binding("/battery", "sensor_msgs/BatteryState", "subscribe",
                                                        ["percentage"]))
    doc.add_widget(doc.current.id, "std.slider", Binding("/speed_limit", "std_msgs/Float64", "publish", ["data"]),
                   settings={"minimum": 0.0, "maximum": 2.0})
    export_canvas(doc.current, tmp_path / "station.json")
    pm = entry_point_plugins()
    pm.register(StationTemplate(tmp_path / "station.json"), name="lab")
    yield from window_session(qtbot, tmp_path / "config", pm)


def test_new_canvas_from_template(window, qtbot):
    menu = window.menu_button.menu()
    [sub] = [a.menu() for a in menu.actions() if a.menu() is not None and a.menu().objectName() == "canvas_templates"]
    assert sub.title() == "New canvas from template"
    titles = [a.text() for a in menu.actions()]
    assert titles.index("New canvas from template") == titles.index("New canvas") + 1
    [action] = sub.actions()
    assert action.text() == "Battery station" and action.isEnabled()
    before = [c.name for c in window.controller.workspace.canvases]
    action.trigger()
    canvases = window.controller.workspace.canvases
    assert len(canvases) == len(before) + 1
    added = window.controller.canvas
    assert added is canvases[-1] and added.name == "Station"
    assert [w.kind for w in added.widgets] == ["std.label", "std.slider"]
    qtbot.waitUntil(lambda: len(window.controller.surface.frames) == 2, timeout=10_000)
    tap(window.canvas_buttons["undo"])  # one undo step takes it back
    assert [c.name for c in window.controller.workspace.canvases] == before


def test_without_templates_the_entry_says_so(qtbot, tmp_path):
    for win in window_session(qtbot, tmp_path / "config", entry_point_plugins()):
        [action] = win.template_menu.actions()
        assert action.text() == "No installed package offers one" and not action.isEnabled()
