"""issue 15.2: the window's type registry holds what installed plugins contribute, so the matcher, the add
panel and the children editor know a lab's own type (lab_msgs/Winch) without asking the robot."""

from __future__ import annotations

import pytest
from app_helpers import window_session

from rcon_core.matcher import match
from rcon_core.plugins import Binding, PluginManager, Role, hookimpl
from rcon_core.plugins.children import ChildCatalog

pytest.importorskip("rcon_widgets_std")
pytestmark = pytest.mark.usefixtures("qapp")


class WinchTypes:
    """A lab package that only contributes its message type."""

    @hookimpl
    def rcon_register_types(self, registry):
        registry.add_msg("lab_msgs/Winch", "float64 payout   # metres\nfloat64 tension\nbool braked\n")


@pytest.fixture
def window(qtbot, tmp_path):
    pm = PluginManager(environ={})
    pm.load_entry_points()
    pm.register(WinchTypes(), name="winch")
    yield from window_session(qtbot, tmp_path / "config", pm)  # no types given: the window builds them


def test_the_window_knows_plugin_types(window):
    assert window.types.has("lab_msgs/Winch")
    assert window.types.default("lab_msgs/Winch") == {"payout": 0.0, "tension": 0.0, "braked": False}


def test_the_matcher_binds_a_field_of_the_plugin_type(window):
    found = {m.spec.kind: m for m in match("lab_msgs/Winch", Role.SUBSCRIBE, window.types, window.plugins)}
    # structural matches need the definition: only the plugin's contribution gives it
    assert (found["std.label"].field_path, found["std.slider"].field_path, found["std.switch"].field_path) == (
        "payout", "payout", "braked")


def test_the_children_editor_offers_the_plugin_types_fields(window):
    catalog = ChildCatalog(window.types, window.plugins, Binding("/winch", "lab_msgs/Winch", "subscribe"))
    assert catalog.known()
    paths = [c.path for c in catalog.fields()]
    assert {"payout", "tension", "braked"} <= set(paths)


def test_a_widget_on_a_type_the_robot_lacks_shows_error_with_the_sentence(qtbot, tmp_path, sim_thread):
    """issue 15.3 in the window: the robot (the sim, which has no lab_msgs) cannot load the type; the frame
    says ERROR with the sentence instead of NO DATA."""
    from rcon_core.canvas import Canvas, Geometry, WidgetInstance, Workspace, new_id

    def layout() -> Workspace:
        canvas = Canvas(new_id("c"), "Lab")
        canvas.widgets.append(WidgetInstance(new_id("w"), "std.label",
                                             Binding("/winch", "lab_msgs/Winch", "subscribe", ("payout",)),
                                             Geometry(32, 32, 240, 120), {}, "Winch"))
        return Workspace([canvas], canvas.id)

    pm = PluginManager(environ={})
    pm.load_entry_points()
    pm.register(WinchTypes(), name="winch")
    for win in window_session(qtbot, tmp_path / "config", pm, url=sim_thread.url, demo=layout,
                              wait_connected=True):
        [frame] = win.controller.surface.frames.values()
        qtbot.waitUntil(lambda frame=frame: frame.badge.status == "ERROR", timeout=10_000)
        assert frame.badge.toolTip() == "the robot does not know lab_msgs/Winch (is its package installed there?)"
