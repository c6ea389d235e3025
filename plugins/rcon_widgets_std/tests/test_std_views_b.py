"""Views of Text Field, Stepper, Text View and Compound offscreen: realistic states, user input reaching
the robot, a screenshot of each."""

import pytest
from rcon_widgets_std.compound import ChildSpec, CompoundModel, CompoundSettings
from rcon_widgets_std.compound_view import CompoundView
from rcon_widgets_std.stepper import StepperModel, StepperSettings
from rcon_widgets_std.stepper_view import StepperView
from rcon_widgets_std.textfield import TextFieldModel, TextFieldSettings
from rcon_widgets_std.textfield_view import TextFieldView
from rcon_widgets_std.textview import TextViewModel, TextViewSettings
from rcon_widgets_std.textview_view import TextViewView
from std_qtkit import LiveBridge, shoot
from std_testkit import STD, build

from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import Binding, WidgetContext
from rcon_core.testing import until_sync


@pytest.fixture
def live(sim_url):
    bridge = LiveBridge(sim_url)
    yield bridge
    bridge.close()


def live_model(cls, settings, live, binding, node, types=None):
    return cls(settings, binding, live.node(node), types=types or TypeRegistry.standard(),
               dispatch=live.thread.call, context=WidgetContext(STD))


def test_textfield_view_sends_and_reports_errors(qtbot, live, sim_thread, tmp_path):
    m = live_model(TextFieldModel, TextFieldSettings(), live,
                   Binding("/cmd_vel", "geometry_msgs/Twist", "publish"), "tf")
    live.thread.call(m.start).result(5)
    view = TextFieldView(m)
    qtbot.addWidget(view)
    view.edit.setText("linear: {x: slow}")
    view.button.click()
    until_sync(lambda: m.state.error, what="the error", qtbot=qtbot)
    view.refresh(m.state)
    assert view.status.text().startswith("not sent: linear.x:")
    view.edit.setText("{linear: {x: 0.4}, angular: {z: 0.2}}")
    view.edit.returnPressed.emit()
    until_sync(lambda: any(msg["linear"]["x"] == 0.4 for msg in sim_thread.published("/cmd_vel")),
               what="the twist on /cmd_vel", qtbot=qtbot)
    until_sync(lambda: m.state.value is not None, what="sent", qtbot=qtbot)
    view.refresh(m.state)
    assert view.status.text().startswith("sent:")
    shoot(qtbot, view, "Command", (320, 130), "textfield", tmp_path)
    live.thread.call(m.stop).result(5)


def test_textfield_view_shows_raw_data(qtbot):
    m = build(TextFieldModel, TextFieldSettings(), "/imu/data", "sensor_msgs/Imu", "subscribe", "angular_velocity")
    view = TextFieldView(m)
    qtbot.addWidget(view)
    m.on_message({"angular_velocity": {"x": 0.01, "y": -0.02, "z": 0.3}})
    view.refresh(m.state)
    assert view.text.toPlainText() == "x: 0.01\ny: -0.02\nz: 0.3" and view.text.isReadOnly()


def test_stepper_view_buttons_publish(qtbot, live, sim_thread, tmp_path):
    m = live_model(StepperModel, StepperSettings(minimum=0, maximum=2, step=0.25, initial=1.0, units="m/s",
                                                 rate_hz=20), live,
                   Binding("/speed_limit", "std_msgs/Float64", "publish", "data"), "st")
    live.thread.call(m.start).result(5)
    view = StepperView(m)
    qtbot.addWidget(view)
    assert view.value.text() == "not set"  # nothing sent: no number that could pass for the robot's limit
    view.plus.click()  # the first step starts from the start value, 1.00
    view.plus.click()
    assert view.value.text() == "1.50 m/s"
    until_sync(lambda: sim_thread.robot.speed_limit == 1.5, what="the robot's limit", qtbot=qtbot)
    for _ in range(5):
        view.plus.click()
    assert view.value.text() == "2.00 m/s" and not view.plus.isEnabled() and view.minus.isEnabled()
    view.refresh(m.state)
    shoot(qtbot, view, "Speed limit", (240, 120), "stepper", tmp_path)
    live.thread.call(m.stop).result(5)


def test_textview_view_rosout_levels_filter_and_chat(qtbot, live, sim_thread, tmp_path):
    m = live_model(TextViewModel, TextViewSettings(max_lines=200), live,
                   Binding("/rosout", "rosgraph_msgs/Log", "subscribe"), "tv")
    live.thread.call(m.start).result(5)
    view = TextViewView(m)
    until_sync(lambda: sim_thread.topic_subscriber_count("/rosout") >= 1, what="subscribed", qtbot=qtbot)
    for level, text in [("info", "Mission started"), ("debug", "Thruster PWM 1500/1500"),
                        ("warn", "Battery low: 18% (11.2 V); return to dock"), ("info", "Waypoint 3 reached"),
                        ("error", "Depth sensor timeout"), ("fatal", "Leak detected in the hull")]:
        sim_thread.run_sync(lambda lv=level, t=text: sim_thread.log("/vessel", lv, t))
    until_sync(lambda: m.state.value is not None and any("Leak" in x.text for x in m.state.value.lines),
               what="the log lines", qtbot=qtbot)
    view.refresh(m.state)
    text = view.history.toPlainText()
    assert "[ERROR] [/vessel] Depth sensor timeout" in text and "[WARN ]" in text
    shoot(qtbot, view, "Robot log", (520, 300), "textview", tmp_path)
    view.level.setCurrentText("error")
    view.refresh(m.state)
    shown = view.history.toPlainText()
    assert "Depth sensor timeout" in shown and "Leak" in shown and "Mission started" not in shown
    view.filter.setText("leak")
    view.refresh(m.state)
    assert "Leak" in view.history.toPlainText() and "Depth" not in view.history.toPlainText()
    live.thread.call(m.stop).result(5)


def test_textview_chat_input_line(qtbot, live, sim_thread):
    m = live_model(TextViewModel, TextViewSettings(), live,
                   Binding("/rcon_test/chat", "std_msgs/String", "publish"), "chat")
    live.thread.call(m.start).result(5)
    view = TextViewView(m)
    qtbot.addWidget(view)
    view.input.setText("hello from the console")
    view.input.returnPressed.emit()
    assert view.input.text() == ""
    until_sync(lambda: sim_thread.published("/rcon_test/chat"), what="the chat line", qtbot=qtbot)
    assert sim_thread.published("/rcon_test/chat")[-1] == {"data": "hello from the console"}
    live.thread.call(m.stop).result(5)


def test_compound_view_composes_and_publishes_an_imu(qtbot, live, sim_thread, tmp_path):
    settings = CompoundSettings(columns=2, send_text="Publish IMU", children=[
        ChildSpec("std.slider", "linear_acceleration.z", {"minimum": -20, "maximum": 20, "step": 0.1,
                                                          "units": "m/s²"}, "Accel z"),
        ChildSpec("std.slider", "angular_velocity.z", {"minimum": -2, "maximum": 2, "step": 0.05,
                                                       "units": "rad/s"}, "Gyro z"),
        ChildSpec("std.textfield", "orientation", {"placeholder": "{x: 0, y: 0, z: 0, w: 1}"}, "Orientation"),
    ])
    m = live_model(CompoundModel, settings, live, Binding("/rcon_test/imu", "sensor_msgs/Imu", "publish"), "cp",
                   types=TypeRegistry.empty())
    live.thread.call(m.start).result(5)
    until_sync(lambda: m.children, what="children", qtbot=qtbot)
    view = CompoundView(m)
    assert len(view.child_views) == 3
    accel = view.child_views[0][1]
    accel.slider.setValue(accel.position_of(9.8))
    view.child_views[2][1].edit.setText("{w: 1.0}")
    view.child_views[2][1].send()
    until_sync(lambda: m.state.value is not None and m.state.value.message["orientation"]["w"] == 1.0,
               what="composed", qtbot=qtbot)
    view.button.click()
    got = None

    def arrived():
        nonlocal got
        msgs = sim_thread.published("/rcon_test/imu")
        got = msgs[-1] if msgs else None
        return got is not None

    until_sync(arrived, what="the IMU message", qtbot=qtbot)
    assert got["linear_acceleration"]["z"] == 9.8 and got["orientation"]["w"] == 1.0
    view.refresh(m.state)
    assert view.status.text() == "✓ published"
    shoot(qtbot, view, "IMU (composed)", (440, 300), "compound", tmp_path)
    live.thread.call(m.stop).result(5)
