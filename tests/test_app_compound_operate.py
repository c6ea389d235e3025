"""Operating a placed Compound: it publishes what its children show, never a default in their place.

A Compound on ``/cmd_vel`` with a Slider on ``linear.x`` and a Text Field on ``angular``, in Operate
mode, against the embedded robot: the operator types in the text child and taps the Compound's Publish
(the text child has no Send of its own: nothing reaches the robot until Publish).
"""

from __future__ import annotations

import pytest
from app_helpers import entry_point_plugins, snap, tap, window_session
from qtpy import QtWidgets
from qtpy.QtTest import QTest

from rcon_core.canvas import Geometry
from rcon_core.plugins import Binding, PluginManager, Role

pytest.importorskip("rcon_widgets_std")
from rcon_widgets_std.compound import ChildSpec, CompoundSettings  # noqa: E402

pytestmark = pytest.mark.usefixtures("qapp")


@pytest.fixture(scope="module")
def plugins() -> PluginManager:
    return entry_point_plugins()


@pytest.fixture
def window(qtbot, tmp_path, sim_thread, plugins):
    yield from window_session(qtbot, tmp_path / "config", plugins, url=sim_thread.url, wait_connected=True,
                              topics=("/cmd_vel",))


def place_compound(window, qtbot, plugins):
    settings = CompoundSettings(children=[
        ChildSpec("std.slider", "linear.x", {"minimum": 0.5, "maximum": 2.0, "step": 0.5}),
        ChildSpec("std.textfield", "angular")])
    inst = window.doc.add_widget(window.controller.canvas.id, "std.compound",
                                 Binding("/cmd_vel", "geometry_msgs/Twist", Role.PUBLISH),
                                 Geometry(16, 16, *settings.preferred_size()),
                                 plugins.widget("std.compound").settings_to_dict(settings), "Drive")
    if not window.controller.canvas.locked:
        window.lock_button.click()  # Operate mode: the widgets take touches
    hosted = window.host.hosted[inst.id]
    qtbot.waitUntil(lambda: hosted.view is not None and len(getattr(hosted.view, "child_views", [])) == 2,
                    timeout=10_000)
    view = hosted.view
    (_c1, slider), (_c2, text) = view.child_views
    qtbot.waitUntil(lambda: text.edit.isVisible() and slider.slider.isVisible(), timeout=5_000)
    return hosted, view, slider, text


def type_into(edit: QtWidgets.QLineEdit, text: str) -> None:
    edit.setFocus()
    edit.selectAll()
    QTest.keyClicks(edit, text)


def test_publish_sends_the_text_child_as_typed_not_a_default(window, sim_thread, qtbot, plugins):
    hosted, view, slider, text = place_compound(window, qtbot, plugins)
    # inside a Compound the text child has no Send of its own and never says "sent"
    assert not getattr(text, "button", None) or not text.button.isVisible()
    slider.slider.setValue(slider._position(1.5))
    type_into(text.edit, "{z: 0.3}")
    qtbot.waitUntil(lambda: "will send" in text.status.text(), timeout=5_000)
    assert "sent:" not in text.status.text()
    snap(window, "compound-will-send")
    tap(view.button)
    got = sim_thread.wait_for_published_sync("/cmd_vel", lambda m: m["angular"]["z"] == 0.3, timeout=10)
    assert got["linear"]["x"] == 1.5 and got["angular"] == {"x": 0.0, "y": 0.0, "z": 0.3}
    qtbot.waitUntil(lambda: "published" in view.status.text(), timeout=5_000)
    assert "sent:" not in text.status.text()


def test_invalid_or_empty_text_child_blocks_the_publish_and_is_named(window, sim_thread, qtbot, plugins):
    hosted, view, slider, text = place_compound(window, qtbot, plugins)
    before = len(sim_thread.published("/cmd_vel"))
    tap(view.button)  # nothing typed yet: no default angular in its place
    qtbot.waitUntil(lambda: "child 2 (Text Field) on angular" in view.status.text(), timeout=5_000)
    assert "nothing typed" in view.status.text() and "published" not in view.status.text().replace(
        "not published", "")
    type_into(text.edit, "{z: fast}")
    qtbot.waitUntil(lambda: "angular.z" in text.status.text(), timeout=5_000)  # said at once, in the child
    tap(view.button)
    qtbot.waitUntil(lambda: "angular.z" in view.status.text(), timeout=5_000)
    assert view.status.text().startswith("not published: child 2 (Text Field) on angular")
    snap(window, "compound-blocked")
    # the robot got nothing; fixing the text and tapping Publish sends it
    type_into(text.edit, "{z: -0.5}")
    tap(view.button)
    got = sim_thread.wait_for_published_sync("/cmd_vel", lambda m: m["angular"]["z"] == -0.5, timeout=10)
    assert got["angular"] == {"x": 0.0, "y": 0.0, "z": -0.5}
    assert got["linear"]["x"] == slider.model.state.value >= 0.5  # what the untouched slider shows, not 0
    assert len(sim_thread.published("/cmd_vel")) == before + 1
