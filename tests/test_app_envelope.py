"""Issue 21.4, in the real window against the sim: each robot's safety envelope.

A Compound slider's maximum typed as 999999999999 was accepted, and one tap published
``linear.x: 43099999999.96`` to ``/cmd_vel``. Now: the envelope is set in its own dialog (Canvas ▾ → Safety
envelope…, the PIN first while the operator lock is on), saved with the workspace and applied on the robot's
link, so a command beyond it never reaches the robot whoever sends it -- the teleop pad, a Slider, a
Compound, a Text Field or a raw node of the link; each widget says what was actually sent. Configure
refuses the absurd maximum and asks before saving a limit beyond the envelope.
"""

from __future__ import annotations

import json

import pytest
from app_helpers import TIMEOUT_MS, all_sent, compound_in_operate, snap, snap_with, tap, window_session
from qtpy import QtCore, QtWidgets
from qtpy.QtTest import QTest

from rcon_core.bridge.envelope import Envelope
from rcon_core.canvas import Binding, Geometry
from rcon_core.plugins import Role

pytest.importorskip("rcon_widgets_std")
pytest.importorskip("rcon_widgets_sensors")
from rcon_widgets_std.compound import ChildSpec, CompoundSettings  # noqa: E402

pytestmark = pytest.mark.usefixtures("qapp")
LIMITS = Envelope(max_linear=1.0, max_angular=0.5)


@pytest.fixture
def window(qtbot, tmp_path, sim_thread, plugins):
    yield from window_session(qtbot, tmp_path / "config", plugins, url=sim_thread.url, wait_connected=True,
                              topics=("/cmd_vel",))


def envelope_dialog(window, qtbot):
    qtbot.waitUntil(lambda: window.envelope.dialog is not None
                    and window.envelope.dialog.isVisible(), timeout=TIMEOUT_MS)
    return window.envelope.dialog


def type_into(edit: QtWidgets.QLineEdit, text: str) -> None:
    edit.setFocus()
    edit.selectAll()
    QTest.keyClick(edit, QtCore.Qt.Key.Key_Delete)
    QTest.keyClicks(edit, text)


def set_envelope(window, envelope: Envelope) -> None:
    import attrs

    first = window.doc.workspace.robots[0]
    window.doc.set_robots([attrs.evolve(first, envelope=envelope), *window.doc.workspace.robots[1:]])


def place(window, qtbot, kind, binding, rect, settings, title="w"):
    inst = window.doc.add_widget(window.controller.canvas.id, kind, binding, Geometry(*rect),
                                 window.plugins.widget(kind).settings_to_dict(
                                     window.plugins.widget(kind).make_settings(settings)), title)
    return inst.id


def pad_says(qtbot, pad, ok) -> None:
    """Wait until the pad's status line passes ``ok``; on a timeout say what it read."""
    try:
        qtbot.waitUntil(lambda: ok(pad.status_text()), timeout=TIMEOUT_MS)
    except Exception:
        raise AssertionError(f"the pad says {pad.status_text()!r} ({pad.model.state})") from None


def hosted_view(window, qtbot, wid):
    hosted = window.host.hosted[wid]
    qtbot.waitUntil(lambda: hosted.view is not None and hosted.view.isVisible(), timeout=TIMEOUT_MS)
    return hosted


# ----------------------------------------------------------------------------------------- the dialog
def test_the_envelope_is_set_in_its_dialog_refuses_absurd_limits_and_is_saved_and_applied(window, qtbot, tmp_path):
    robot = window.doc.workspace.robots[0]
    window.canvas_actions["envelope"].trigger()
    dialog = envelope_dialog(window, qtbot)
    linear, angular = dialog.fields[0]
    type_into(linear, "999999999999")
    tap(dialog.ok_button)
    assert dialog.isVisible() and dialog.problem.text() == (  # refused, said, nothing changed
        f"{robot.label}, maximum linear speed: 999999999999 is more than 100 m/s, the most an envelope may allow "
        "(a slip of a finger?)")
    assert window.doc.workspace.robots[0].envelope is None
    snap_with(window, dialog, "envelope-refused")
    type_into(linear, "1")
    type_into(angular, "0.5")
    tap(dialog.ok_button)
    qtbot.waitUntil(lambda: not dialog.isVisible(), timeout=TIMEOUT_MS)
    assert window.doc.workspace.robots[0].envelope == LIMITS
    assert window.link.client.envelope == LIMITS  # applied on the robot's link at once
    window.controller.saver.flush()
    saved = json.loads((tmp_path / "config" / "workspace.json").read_text())
    assert [r["envelope"] for r in saved["robots"] if r["id"] == robot.id] == [{"max_linear": 1.0, "max_angular": 0.5}]
    window.doc.undo()  # one undo step
    assert window.doc.workspace.robots[0].envelope is None and window.link.client.envelope is None


def test_while_the_operator_lock_is_on_the_envelope_needs_the_pin(window, qtbot):
    from test_app_operator_lock import pin_dialog, set_pin_and_lock, type_pin

    set_pin_and_lock(window, qtbot, "2468")
    window.canvas_actions["envelope"].trigger()
    pin = pin_dialog(window, qtbot)
    assert "change the safety envelope" in pin.findChild(type(pin.message), "pinPrompt").text()
    assert window.envelope.dialog is None
    type_pin(pin, "2468", pad=True)
    tap(pin.ok)
    dialog = envelope_dialog(window, qtbot)  # the right PIN opens it
    dialog.set_limits(window.doc.workspace.robots[0].id, "0.8", "")
    tap(dialog.ok_button)
    qtbot.waitUntil(lambda: window.doc.workspace.robots[0].envelope == Envelope(0.8, None), timeout=TIMEOUT_MS)


# --------------------------------------------------------------------- nothing beyond reaches the robot
def test_no_publisher_gets_a_command_beyond_the_envelope_to_the_robot_and_each_says_what_was_sent(
        window, qtbot, sim_thread, monkeypatch):
    from rcon_widgets_std import slider as slider_mod

    monkeypatch.setattr(slider_mod, "_LAST_VALUES", {})  # nothing sent in this session (other tests send some)
    sim = sim_thread
    set_envelope(window, LIMITS)
    qtbot.waitUntil(lambda: window.link.client.envelope == LIMITS, timeout=TIMEOUT_MS)
    twist = Binding("/cmd_vel", "geometry_msgs/Twist", Role.PUBLISH)
    pad_id = place(window, qtbot, "sensors.teleop", twist, (16, 16, 272, 320), {"max_linear": 2.0, "max_angular": 2.0})
    slider_id = place(window, qtbot, "std.slider", Binding("/cmd_vel", "geometry_msgs/Twist", Role.PUBLISH,
                                                           ("linear.x",)), (304, 16, 256, 112),
                      {"minimum": 0.0, "maximum": 5.0, "step": 0.5, "follow_topic": False, "units": "m/s"})
    text_id = place(window, qtbot, "std.textfield", twist, (304, 144, 256, 112), {})
    compound_settings = CompoundSettings(children=[
        ChildSpec("std.slider", "linear.x", {"minimum": 0.5, "maximum": 5.0, "step": 0.5}),
        ChildSpec("std.textfield", "angular")])
    compound_id = place(window, qtbot, "std.compound", twist,
                        (576, 16, *compound_settings.preferred_size()), {}, "Compound")
    window.doc.reconfigure_widget(compound_id, settings=window.plugins.widget("std.compound").settings_to_dict(
        compound_settings))
    _hosted, compound = compound_in_operate(qtbot, window, compound_id, 2)  # Operate mode: views take taps
    pad = hosted_view(window, qtbot, pad_id).view
    slider = hosted_view(window, qtbot, slider_id).view
    text = hosted_view(window, qtbot, text_id).view

    def received(pred):
        return sim.wait_for_published_sync("/cmd_vel", pred, timeout=10)

    # the pad: pushed past its edge it would send 2 m/s; it sends (and says) 1
    pad_says(qtbot, pad, lambda text: text == "touch to drive ≤ 1 m/s, 0.5 rad/s (safety envelope)")
    centre, radius = pad.pad()
    c = centre.toPoint()
    QTest.mousePress(pad, QtCore.Qt.MouseButton.LeftButton, pos=c)
    QTest.mouseMove(pad, c - QtCore.QPoint(0, int(radius * 1.5)))
    received(lambda m: m["linear"]["x"] == 1.0)
    pad_says(qtbot, pad, lambda text: "linear.x +1.00" in text)
    snap(window, "envelope-pad")
    QTest.mouseRelease(pad, QtCore.Qt.MouseButton.LeftButton, pos=c)
    received(lambda m: m["linear"]["x"] == 0.0)

    # the slider: its range is held to the envelope and says so; its top sends 1
    assert slider.high.text() == "1.00 m/s · envelope" and "safety envelope" in slider.high.toolTip()
    slider.slider.setValue(slider.slider.maximum())
    received(lambda m: m["linear"]["x"] == 1.0 and m["angular"]["z"] == 0.0)

    # the text field: the very number; sent at the limit, said so
    text.edit.setText("{linear: {x: 43099999999.96}, angular: {z: -3}}")
    tap(text.button)
    received(lambda m: m["angular"]["z"] == -0.5)
    qtbot.waitUntil(lambda: text.status.text().startswith("sent, held to the safety envelope"), timeout=TIMEOUT_MS)
    assert "linear.x 4.31e+10 → 1" in text.status.text() and "angular.z -3 → -0.5" in text.status.text()

    # the compound: a slider child of 0.5..5 is held to 1; a text child's 9 rad/s is clamped and said
    (_c1, child_slider), (_c2, child_text) = compound.child_views
    assert child_slider.value.text() == "0.50"  # what the compound will send (its start value), not "not set"
    assert child_slider.high.text() == "1.00 · envelope"
    child_slider.slider.setValue(child_slider.slider.maximum())
    child_text.edit.setText("{z: 9}")
    qtbot.waitUntil(lambda: "will send" in child_text.status.text(), timeout=TIMEOUT_MS)
    tap(compound.button)
    got = received(lambda m: m["angular"]["z"] == 0.5)
    assert got["linear"]["x"] == 1.0
    qtbot.waitUntil(lambda: "held to the safety envelope: angular.z 9 → 0.5" in compound.status.text(),
                    timeout=TIMEOUT_MS)
    snap(window, "envelope-widgets")

    # a raw node of the robot's link (what a lab's plugin could reach): held all the same
    link = window.link

    def raw() -> None:
        link.client.node("raw").advertise("/cmd_vel", "geometry_msgs/Twist").publish(
            {"linear": {"x": -7.0}, "angular": {"z": 0.0}})

    link.thread.call(raw)
    received(lambda m: m["linear"]["x"] == -1.0)
    all_sent(qtbot, window, sim)
    commands = sim.published("/cmd_vel")
    assert len(commands) >= 6
    worst = max(max(abs(v) for v in m["linear"].values()) for m in commands)
    turn = max(max(abs(v) for v in m["angular"].values()) for m in commands)
    assert worst <= 1.0 and turn <= 0.5, (worst, turn)


# ------------------------------------------------------------------------------------------ Configure
def open_configure(window, qtbot, widget_id):
    frame = window.controller.surface.frames[widget_id]
    menu = frame.request_menu(frame.mapToGlobal(QtCore.QPoint(10, 10)))
    [configure] = [a for a in menu.actions() if a.objectName() == "configure"]
    configure.trigger()
    menu.close()
    dialog = window.configurer.dialog
    qtbot.waitUntil(dialog.isVisible, timeout=5_000)
    return dialog


def ok_of(dialog) -> QtWidgets.QPushButton:
    box = dialog.findChild(QtWidgets.QDialogButtonBox)
    return box.button(QtWidgets.QDialogButtonBox.StandardButton.Ok)


def test_configure_refuses_a_maximum_of_999999999999_and_asks_before_a_limit_beyond_the_envelope(window, qtbot):
    set_envelope(window, LIMITS)
    wid = place(window, qtbot, "std.slider", Binding("/cmd_vel", "geometry_msgs/Twist", Role.PUBLISH,
                                                     ("linear.x",)), (16, 16, 256, 112),
                {"minimum": 0.0, "maximum": 1.0, "step": 0.1})
    dialog = open_configure(window, qtbot, wid)
    maximum = dialog.findChild(QtWidgets.QDoubleSpinBox, "setting_maximum")
    maximum.setValue(999999999999)
    tap(ok_of(dialog))
    problem = dialog.findChild(QtWidgets.QLabel, "configureProblem")
    assert dialog.isVisible() and "maximum 1e+12 is out of any sane range" in problem.text()
    assert window.controller.canvas.widget(wid).settings["maximum"] == 1.0  # nothing saved
    snap_with(window, dialog, "configure-refused")

    maximum.setValue(5.0)  # sane, but beyond the robot's envelope: asked first
    tap(ok_of(dialog))
    qtbot.waitUntil(lambda: window.configurer.beyond_dialog is not None
                    and window.configurer.beyond_dialog.isVisible(), timeout=TIMEOUT_MS)
    box = window.configurer.beyond_dialog
    assert "linear.x up to 5 m/s: the safety envelope holds it to 1 m/s" in box.informativeText()
    [cancel] = [b for b in box.buttons() if b.objectName() == "beyondEnvelopeCancel"]
    tap(cancel)
    assert dialog.isVisible() and window.controller.canvas.widget(wid).settings["maximum"] == 1.0
    tap(ok_of(dialog))
    qtbot.waitUntil(lambda: window.configurer.beyond_dialog.isVisible(), timeout=TIMEOUT_MS)
    box = window.configurer.beyond_dialog
    [save] = [b for b in box.buttons() if b.objectName() == "beyondEnvelopeSave"]
    tap(save)
    qtbot.waitUntil(lambda: not dialog.isVisible(), timeout=TIMEOUT_MS)
    assert window.controller.canvas.widget(wid).settings["maximum"] == 5.0


def test_a_compound_slider_child_of_999999999999_is_refused_in_configure(window, qtbot):
    """The issue's own path: a Compound's slider child whose maximum is typed as 999999999999."""
    settings = CompoundSettings(children=[ChildSpec("std.slider", "linear.x", {"minimum": 0.0, "maximum": 1.0})])
    wid = place(window, qtbot, "std.compound", Binding("/cmd_vel", "geometry_msgs/Twist", Role.PUBLISH),
                (16, 16, *settings.preferred_size()), {})
    window.doc.reconfigure_widget(wid, settings=window.plugins.widget("std.compound").settings_to_dict(settings))
    dialog = open_configure(window, qtbot, wid)
    editor = dialog.findChild(QtWidgets.QWidget, "setting_children")
    editor.edit_child(0)  # the child's own settings page, as its row's tap opens it
    maximum = editor.child_form.findChild(QtWidgets.QDoubleSpinBox, "setting_maximum")
    maximum.setValue(999999999999)
    qtbot.waitUntil(lambda: "out of any sane range" in editor.child_problems_label.text(), timeout=TIMEOUT_MS)
    tap(ok_of(dialog))
    problem = dialog.findChild(QtWidgets.QLabel, "configureProblem")
    qtbot.waitUntil(lambda: "out of any sane range" in problem.text(), timeout=TIMEOUT_MS)
    assert dialog.isVisible()
    child = window.controller.canvas.widget(wid).settings["children"][0]
    assert child["settings"]["maximum"] == 1.0


def test_a_widget_placed_beyond_the_envelope_is_kept_only_when_the_operator_says(window, qtbot):
    from app_helpers import choose_kind, tap_topic

    set_envelope(window, LIMITS)
    for answer, kept in (("beyondEnvelopeCancel", 0), ("beyondEnvelopeSave", 1)):
        tap_topic(window, "/cmd_vel")
        panel = choose_kind(window, Role.PUBLISH, "std.slider")
        panel.choose_field("linear.x")
        panel.form.editor("maximum").setValue(5.0)
        before = len(window.controller.canvas.widgets)
        tap(panel.place_button)
        qtbot.waitUntil(lambda: window.envelope.beyond_dialog is not None
                        and window.envelope.beyond_dialog.isVisible(), timeout=TIMEOUT_MS)
        box = window.envelope.beyond_dialog
        assert "linear.x up to 5 m/s: the safety envelope holds it to 1 m/s" in box.informativeText()
        assert len(window.controller.canvas.widgets) == before + 1
        [button] = [b for b in box.buttons() if b.objectName() == answer]
        tap(button)
        qtbot.waitUntil(lambda box=box: not box.isVisible(), timeout=TIMEOUT_MS)
        assert len(window.controller.canvas.widgets) == before + kept


def test_in_the_demo_the_speed_limit_slider_and_the_pad_agree_on_what_is_sent(qtbot, tmp_path, sim_thread, plugins,
                                                                              monkeypatch):
    """The pad read +1.67 while the boat was held at 0.47 m/s: now the pad follows the robot's speed limit
    (and the demo's envelope) and shows what it sends."""
    from app_helpers import open_window
    from rcon_widgets_std import slider as slider_mod

    from rcon_core.app.demo import DEMO_ENVELOPE, demo_workspace

    monkeypatch.setattr(slider_mod, "_LAST_VALUES", {})
    window = open_window(qtbot, tmp_path / "config", plugins, url=sim_thread.url,
                         demo=lambda: demo_workspace(plugins), wait_connected=True)
    try:
        assert window.doc.workspace.robots[0].envelope == DEMO_ENVELOPE
        qtbot.waitUntil(lambda: window.link.client.envelope == DEMO_ENVELOPE, timeout=TIMEOUT_MS)
        by_title = {w.title: window.host.hosted[w.id] for w in window.controller.canvas.widgets}
        limit_view = by_title["Speed limit"]
        pad_hosted = by_title["Drive"]
        # the demo's widgets run once the link is up (a model built before is replaced): wait for those
        qtbot.waitUntil(lambda: all(h.model is not None and h.model.running and not h.model.state.link_down
                                    and h.view is not None and h.view.isVisible() and h.view.model is h.model
                                    for h in (limit_view, pad_hosted)), timeout=TIMEOUT_MS)
        pad = pad_hosted.view
        pad_says(qtbot, pad, lambda text: text == "touch to drive ≤ 1.5 m/s (safety envelope)")
        track = limit_view.view.slider
        tap(track, QtCore.QPoint(track.width() // 3, track.height() // 2))  # about a third of 0..1.5 m/s
        qtbot.waitUntil(lambda: sim_thread.robot.speed_limit is not None, timeout=TIMEOUT_MS)
        limit = sim_thread.robot.speed_limit
        assert 0.2 < limit < 1.0
        pad_says(qtbot, pad, lambda text: f"≤ {limit:g} m/s (speed limit)" in text)
        centre, radius = pad.pad()
        c = centre.toPoint()
        QTest.mousePress(pad, QtCore.Qt.MouseButton.LeftButton, pos=c)
        QTest.mouseMove(pad, c - QtCore.QPoint(0, int(radius * 1.5)))  # past the edge
        got = sim_thread.wait_for_published_sync("/cmd_vel", lambda m: m["linear"]["x"] > 0.1, timeout=10)
        assert got["linear"]["x"] == pytest.approx(limit)  # sent: the robot's own limit, not the pad's 2 m/s
        pad_says(qtbot, pad, lambda text: f"linear.x +{limit:.2f}" in text)
        snap(window, "demo-pad-speed-limit")
        QTest.mouseRelease(pad, QtCore.Qt.MouseButton.LeftButton, pos=c)
        sim_thread.wait_for_published_sync("/cmd_vel", lambda m: m["linear"]["x"] == 0.0, timeout=10)
    finally:
        window.shutdown()
