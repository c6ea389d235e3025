"""Issue 21.12 and 22.20, in the real window against the sim: what the operator reads is what is so.

A Label on ``/battery`` showed 0.85 (BatteryState.percentage is 0..1); "as received" rounded 43.6532117 to
43.6532; the pad's axis labels read ``↑ linear.x`` / ``-angular.z →``; a Compound's stepper read "not set"
but the compound sent 0.0; ``1e5`` typed as a parameter was refused as "got a string" and ``1.0e+400``
became ``.inf`` without a word; the face of a Hold-to-send button was cut ("✗ hold 1…").
"""

from __future__ import annotations

import pytest
from app_helpers import TIMEOUT_MS, compound_in_operate, snap, tap, window_session
from qtpy import QtCore, QtWidgets
from qtpy.QtTest import QTest

from rcon_core.canvas import Binding, Geometry
from rcon_core.plugins import Role
from rcon_core.testing import qt_flushed

pytest.importorskip("rcon_widgets_std")
pytest.importorskip("rcon_widgets_sensors")
from rcon_widgets_std.compound import ChildSpec, CompoundSettings  # noqa: E402

pytestmark = pytest.mark.usefixtures("qapp")


@pytest.fixture
def window(qtbot, tmp_path, sim_thread, plugins):
    yield from window_session(qtbot, tmp_path / "config", plugins, url=sim_thread.url, wait_connected=True,
                              topics=("/battery",))


def place(window, kind, binding, size, settings=None, title="w", at=(16, 16)):
    spec = window.plugins.widget(kind)
    inst = window.doc.add_widget(window.controller.canvas.id, kind, binding, Geometry(*at, *size),
                                 spec.settings_to_dict(spec.make_settings(settings or {})), title)
    return inst.id


def operate(window, qtbot, wid):
    if not window.controller.canvas.locked:
        window.lock_button.click()
    hosted = window.host.hosted[wid]
    qtbot.waitUntil(lambda: hosted.view is not None and hosted.view.isVisible(), timeout=TIMEOUT_MS)
    return hosted


def test_a_label_placed_on_the_battery_shows_percent(window, qtbot, sim_thread, plugins):
    """The add panel's own Label on /battery (its proposed field, percentage), with its default settings."""
    panel = window.add_panel
    panel.start_from_topic("/battery", "sensor_msgs/BatteryState")
    panel.choose_role(Role.SUBSCRIBE)
    kinds = [panel.candidates.item(i).data(QtCore.Qt.ItemDataRole.UserRole).spec.kind
             for i in range(panel.candidates.count())]
    panel.choose_candidate(kinds.index("std.label"))
    tap(panel.place_button)
    wid = window.controller.canvas.widgets[-1].id
    assert window.controller.canvas.widgets[-1].binding.field_paths == ("percentage",)
    hosted = operate(window, qtbot, wid)
    qtbot.waitUntil(lambda: hosted.view.value.text().endswith(" %"), timeout=TIMEOUT_MS)
    shown = float(hosted.view.value.text().removesuffix(" %"))
    assert abs(shown - sim_thread.robot.battery_fraction * 100) < 2 and shown > 1
    snap(window, "label-battery-percent")


def test_as_received_shows_the_value_as_received(window, qtbot, sim_thread):
    wid = place(window, "std.label", Binding("/gps/fix", "sensor_msgs/NavSatFix", Role.SUBSCRIBE, ("latitude",)),
                (256, 112), {"decimals": -1})
    hosted = operate(window, qtbot, wid)
    qtbot.waitUntil(lambda: hosted.model.state.message is not None, timeout=TIMEOUT_MS)
    latitude = hosted.model.state.message["latitude"]
    window.host.refresh()
    qtbot.waitUntil(lambda: hosted.view.value.text() not in ("–", ""), timeout=TIMEOUT_MS)
    text = hosted.view.value.text()
    assert float(text) == pytest.approx(latitude, abs=1e-12) and len(text.replace("-", "").replace(".", "")) > 6


def test_the_pads_axes_say_forward_and_turn_with_the_field_in_small_print(window, qtbot):
    wid = place(window, "sensors.teleop", Binding("/cmd_vel", "geometry_msgs/Twist", Role.PUBLISH), (272, 320))
    pad = operate(window, qtbot, wid).view
    window.host.refresh()
    pad.grab()  # painted
    assert pad.axis_labels == ("↑ forward", "linear.x", "turn right →", "-angular.z")
    snap(window, "pad-axis-words")


def test_a_compound_stepper_shows_what_the_compound_sends(window, qtbot, sim_thread):
    settings = CompoundSettings(children=[ChildSpec("std.stepper", "data", {"minimum": 0.0, "maximum": 3.0,
                                                                            "step": 0.5, "initial": 1.5})])
    wid = place(window, "std.compound", Binding("/speed_limit", "std_msgs/Float64", Role.PUBLISH),
                settings.preferred_size(), window.plugins.widget("std.compound").settings_to_dict(settings))
    _hosted, compound = compound_in_operate(qtbot, window, wid, 1)
    [(_child, stepper)] = compound.child_views
    qtbot.waitUntil(lambda: compound.button.isVisible() and stepper.plus.isVisible(), timeout=TIMEOUT_MS)
    assert stepper.value.text() == "1.50"  # what the compound will send, not "not set"
    tap(compound.button)
    got = sim_thread.wait_for_published_sync("/speed_limit", timeout=10)
    assert got["data"] == 1.5
    tap(stepper.plus)
    assert stepper.value.text() == "2.00"
    tap(compound.button)
    sim_thread.wait_for_published_sync("/speed_limit", lambda m: m["data"] == 2.0, timeout=10)


def test_numbers_typed_into_the_parameters_editor(window, qtbot, sim_thread):
    panel = window.params_panel
    window.side.setCurrentWidget(panel)
    qtbot.waitUntil(lambda: panel.item("/kingfisher/max_speed") is not None and not panel.busy, timeout=TIMEOUT_MS)
    item = panel.item("/kingfisher/max_speed")
    panel.tree.scrollTo(panel.tree.indexFromItem(item))
    QTest.mouseClick(panel.tree.viewport(), QtCore.Qt.MouseButton.LeftButton, QtCore.Qt.KeyboardModifier.NoModifier,
                     panel.tree.visualRect(panel.tree.indexFromItem(item)).center())
    qtbot.waitUntil(panel.editor.isVisible, timeout=TIMEOUT_MS)
    edit = panel.edit_value
    edit.setFocus()
    edit.selectAll()
    QTest.keyClicks(edit, "1.0e+400")
    tap(panel.set_button)
    assert panel.edit_problem.text() == "Not set: 1.0e+400 is too large for a number (it would become infinity)"
    edit.selectAll()
    QTest.keyClicks(edit, "1e0")
    tap(panel.set_button)  # read as the float 1.0, asked before it is set
    qtbot.waitUntil(lambda: getattr(window, "confirm_dialog", None) is not None
                    and window.confirm_dialog.isVisible(), timeout=TIMEOUT_MS)
    assert "1.0" in window.confirm_dialog.informativeText() and "string" not in panel.edit_problem.text()
    tap(window.confirm_dialog.findChild(QtWidgets.QPushButton, "confirmYes"))
    qtbot.waitUntil(lambda: sim_thread.params_tree.get("/kingfisher/max_speed") == 1.0, timeout=TIMEOUT_MS)


@pytest.mark.parametrize("kind,binding,settings", [
    ("std.button", Binding("/lights/set", "std_srvs/SetBool", Role.CALL), {"payload": "data: false",
                                                                            "hold_to_send": True}),
    ("std.switch", Binding("/lights/set", "std_srvs/SetBool", Role.CALL, ("request.data",)),
     {"hold_to_send": True, "state_topic": "/lights/state"}),
])
def test_a_short_press_on_hold_to_send_says_so_in_full_at_the_default_size(window, qtbot, plugins, kind, binding,
                                                                           settings):
    wid = place(window, kind, binding, plugins.widget(kind).default_size, settings)
    view = operate(window, qtbot, wid).view
    qt_flushed(qtbot)
    tap(view.button)  # a short press: nothing is sent, the face says why
    qtbot.waitUntil(lambda: view.face.flashing is not None, timeout=TIMEOUT_MS)
    shown = view.button.text()
    assert "…" not in shown and shown.startswith("✗ hold 1 s"), shown
    snap(window, f"hold-to-send-{kind}")
