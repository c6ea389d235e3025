"""Views of Label, Slider, Switch and Button offscreen: what they show for realistic states, user input
reaching the robot through the model, and a screenshot of each."""

import pytest
from qtpy import QtCore, QtGui, QtWidgets
from rcon_widgets_std.button import ButtonModel, ButtonSettings, CallStatus
from rcon_widgets_std.button_view import ButtonView
from rcon_widgets_std.label import LabelModel, LabelSettings
from rcon_widgets_std.label_view import LabelView
from rcon_widgets_std.slider import SliderModel, SliderSettings
from rcon_widgets_std.slider_view import SliderView
from rcon_widgets_std.switch import SwitchModel, SwitchSettings, SwitchValue
from rcon_widgets_std.switch_view import SwitchView
from std_qtkit import LiveBridge, shoot
from std_testkit import build

from rcon_core.app.theme import stylesheet
from rcon_core.msgs import TypeRegistry
from rcon_core.testing import ManualClock, RecordingPort, until_sync


@pytest.fixture
def live(sim_url):
    bridge = LiveBridge(sim_url)
    yield bridge
    bridge.close()


def test_label_view_value_age_and_stale(qtbot, tmp_path):
    clock = ManualClock()
    m = build(LabelModel, LabelSettings(decimals=1, units="%", scale=100, stale_after=3), "/battery",
              "sensor_msgs/BatteryState", "subscribe", "percentage", clock=clock, port=RecordingPort())
    m.start()  # staleness only counts while running
    view = LabelView(m)
    m.on_message({"percentage": 0.873})
    clock.now += 1.2
    view.refresh(m.state)
    assert view.value.text() == "87.3 %" and view.age.text() == "1.2 s ago"
    shoot(qtbot, view, "Battery", (200, 130), "label", tmp_path)
    clock.now += 5
    view.refresh(m.state)
    assert view.age.text().startswith("STALE")


def test_label_view_value_is_not_selectable_and_copies_through_its_menu(qtbot):
    m = build(LabelModel, LabelSettings(decimals=3, units="m"), "/depth", "sensor_msgs/Range", "subscribe", "range")
    view = LabelView(m)
    qtbot.addWidget(view)
    m.on_message({"range": 7.1234})
    view.refresh(m.state)
    assert not isinstance(view.value, QtWidgets.QLabel)  # no text document laid out per value
    assert view.contextMenuPolicy() == QtCore.Qt.ContextMenuPolicy.ActionsContextMenu
    assert [a.text() for a in view.actions()] == ["Copy value"]
    view.copy_action.trigger()
    assert QtWidgets.QApplication.clipboard().text() == "7.123 m"


@pytest.mark.parametrize("width", [240, 150, 110, 80])
def test_label_view_shrinks_a_long_value_to_fit_and_never_clips(qtbot, width):
    clock = ManualClock()
    m = build(LabelModel, LabelSettings(decimals=-1, stale_after=3), "/x", "std_msgs/Float64", "subscribe", "data",
              clock=clock, port=RecordingPort())
    m.start()
    host = QtWidgets.QWidget()
    host.setStyleSheet(stylesheet(touch=48))
    qtbot.addWidget(host)
    view = LabelView(m, host)
    view.setGeometry(0, 0, width, 90)
    host.show()
    m.on_message({"data": 0.846331})
    clock.now += 12.5
    view.refresh(m.state)
    QtWidgets.QApplication.processEvents()
    font, shown = view.value.fitted()
    room = view.value.contentsRect().width()
    assert QtGui.QFontMetricsF(font).horizontalAdvance(shown) <= room
    if width >= 110:
        assert shown == "0.846331"  # shrinking was enough: nothing cut
    else:
        assert shown == "0.846331" or shown.endswith("…")  # elided only as a last resort, visibly
    assert font.pixelSize() <= 30 and (width < 240 or font.pixelSize() == 30)
    # the age caption: fits, or is visibly elided (QLabel alone cut it on both sides)
    assert view.age.text() == "STALE · 12.5 s ago"
    img = view.grab(view.age.geometry()).toImage()  # the caption over the view's white background
    ink = [x for x in range(img.width()) for y in range(img.height()) if QtGui.QColor(img.pixel(x, y)).value() < 200]
    assert ink and min(ink) > 0 and max(ink) < img.width() - 1, "caption text runs into the edges"


def test_slider_view_drag_and_release_publish_through_the_bridge(qtbot, live, sim_thread, tmp_path):
    m = SliderModel(SliderSettings(minimum=0, maximum=2, step=0.1, units="m/s"),
                    build(SliderModel, None, "/speed_limit", "std_msgs/Float64", "publish", "data").binding,
                    live.node("slider"), types=TypeRegistry.standard(), dispatch=live.thread.call)
    live.thread.call(m.start).result(5)
    view = SliderView(m)
    assert view.slider.maximum() == 20 and view.low.text() == "0.00 m/s"
    view.slider.setSliderDown(True)
    view.slider.setValue(12)  # a drag: on-release mode publishes nothing yet
    assert view.value.text() == "1.20 m/s"
    view.slider.setSliderDown(False)  # the release
    until_sync(lambda: any(msg["data"] == 1.2 for msg in sim_thread.published("/speed_limit")),
               what="1.2 on /speed_limit", qtbot=qtbot)
    until_sync(lambda: sim_thread.robot.speed_limit == 1.2, what="the robot's limit", qtbot=qtbot)
    view.refresh(m.state)
    shoot(qtbot, view, "Speed limit", (260, 150), "slider", tmp_path)
    live.thread.call(m.stop).result(5)


def test_publish_slider_view_says_not_set_until_a_value_is_sent_or_heard(qtbot, live, sim_thread):
    m = SliderModel(SliderSettings(minimum=0.5, maximum=2, step=0.1, units="m/s"),
                    build(SliderModel, None, "/rcon_test/limit_v", "std_msgs/Float64", "publish", "data").binding,
                    live.node("slider-v"), types=TypeRegistry.standard(), dispatch=live.thread.call)
    live.thread.call(m.start).result(5)
    view = SliderView(m)
    qtbot.addWidget(view)
    view.refresh(m.state)
    assert view.value.text() == "not set" and view.slider.value() == 0  # no number passes for the robot's
    until_sync(lambda: sim_thread.topic_subscriber_count("/rcon_test/limit_v") >= 1,
               what="following", qtbot=qtbot)
    other = live.node("another-console")
    live.thread.call(lambda: other.advertise("/rcon_test/limit_v", "std_msgs/Float64").publish({"data": 1.5}))
    until_sync(lambda: m.state.value == 1.5, what="another console's value", qtbot=qtbot)
    view.refresh(m.state)
    assert view.value.text() == "1.50 m/s" and view.slider.value() == 10
    live.thread.call(m.stop).result(5)


def test_slider_view_subscribe_follows_and_cannot_be_moved(qtbot):
    m = build(SliderModel, SliderSettings(minimum=0, maximum=1), "/battery", "sensor_msgs/BatteryState",
              "subscribe", "percentage")
    view = SliderView(m)
    qtbot.addWidget(view)
    m.on_message({"percentage": 0.25})
    view.refresh(m.state)
    assert not view.slider.isEnabled() and view.slider.value() == 25 and view.value.text() == "0.25"


def test_switch_view_call_lights_and_show_state(qtbot, live, sim_thread, tmp_path):
    m = SwitchModel(SwitchSettings(state_topic="/lights/state", on_text="Lights on", off_text="Lights off"),
                    build(SwitchModel, None, "/lights/set", "std_srvs/SetBool", "call", "request.data").binding,
                    live.node("switch"), types=TypeRegistry.standard(), dispatch=live.thread.call)
    live.thread.call(m.start).result(5)
    view = SwitchView(m)
    qtbot.addWidget(view)
    until_sync(lambda: getattr(m.state.value, "on", None) is False, what="the latched state", qtbot=qtbot)
    view.refresh(m.state)
    assert view.button.text() == "○ Lights off" and not view.button.isChecked()
    view.button.click()
    # /lights/state may confirm "on" before the call's answer arrives: wait for the answer too (busy
    # over), not only the state, before reading the button's text
    until_sync(lambda: getattr(m.state.value, "on", None) is True and not m.state.value.busy,
               what="lights on, and the answer", qtbot=qtbot)
    view.refresh(m.state)
    assert view.button.isChecked() and view.button.text() == "● Lights on" and view.reply.text() == "lights on"
    assert sim_thread.robot.lights is True
    shoot(qtbot, view, "Lights", (180, 130), "switch", tmp_path)
    live.thread.call(m.stop).result(5)


def test_switch_view_drops_an_old_reply_when_the_state_changes_elsewhere(qtbot, live, sim_thread):
    m = SwitchModel(SwitchSettings(state_topic="/lights/state"),
                    build(SwitchModel, None, "/lights/set", "std_srvs/SetBool", "call", "request.data").binding,
                    live.node("switch"), types=TypeRegistry.standard(), dispatch=live.thread.call)
    live.thread.call(m.start).result(5)
    view = SwitchView(m)
    qtbot.addWidget(view)
    until_sync(lambda: getattr(m.state.value, "on", None) is False, what="the latched state", qtbot=qtbot)
    view.button.click()
    until_sync(lambda: m.state.value.on is True and not m.state.value.busy, what="lights on", qtbot=qtbot)
    view.refresh(m.state)
    assert view.reply.text() == "lights on"
    other = live.node("another-console")  # someone else turns them off
    live.thread.run(other.call_service("/lights/set", {"data": False})).result(10)
    until_sync(lambda: m.state.value.on is False, what="the new state", qtbot=qtbot)
    view.refresh(m.state)
    assert view.button.text() == "○ Off" and view.reply.text() == "tap for On" and m.state.value.reply == ""
    live.thread.call(m.stop).result(5)


def test_switch_view_reply_never_overlaps_the_button(qtbot):
    m = build(SwitchModel, SwitchSettings(), "/lights/set", "std_srvs/SetBool", "call", "request.data")
    host = QtWidgets.QWidget()
    host.setStyleSheet(stylesheet(touch=48))  # the app's theme: touch-sized buttons
    qtbot.addWidget(host)
    view = SwitchView(m, host)
    m.set_value(SwitchValue(True, reply="lights on"))
    view.refresh(m.state)
    host.show()
    for height in (160, 110, 80, 60):
        view.setGeometry(0, 0, 140, height)
        QtWidgets.QApplication.processEvents()
        b, r = view.button.geometry(), view.reply.geometry()
        if view.reply.isVisible():
            assert r.top() >= b.bottom(), f"reply over the button at {height} px"
            assert view.button.toolTip() == ""
        else:
            assert view.button.toolTip() == "lights on", f"reply neither shown nor a tooltip at {height} px"
    view.setGeometry(0, 0, 140, 160)
    QtWidgets.QApplication.processEvents()
    assert view.reply.isVisible() and view.reply.text() == "lights on"
    view.setGeometry(0, 0, 140, 60)
    QtWidgets.QApplication.processEvents()
    assert not view.reply.isVisible()


def test_switch_view_busy_and_refused(qtbot):
    m = build(SwitchModel, SwitchSettings(), "/arm", "std_srvs/SetBool", "call", "request.data")
    view = SwitchView(m)
    qtbot.addWidget(view)
    m.set_value(SwitchValue(False, True, True))
    view.refresh(m.state)
    assert view.button.text() == "On…" and "asking" in view.reply.text()
    m.set_value(SwitchValue(False, False, None, "interlock open"))
    m.set_error("/arm refused: interlock open")
    view.refresh(m.state)
    assert view.button.text() == "○ Off" and "interlock open" in view.reply.text()


def test_button_view_progress_result_and_error(qtbot, live, sim_thread, tmp_path):
    m = ButtonModel(ButtonSettings(text="Dock"),
                    build(ButtonModel, None, "/dock", "std_srvs/Trigger", "call").binding,
                    live.node("button"), types=TypeRegistry.standard(), dispatch=live.thread.call)
    live.thread.call(m.start).result(5)
    view = ButtonView(m)
    qtbot.addWidget(view)
    assert view.button.text() == "Dock"
    view.button.pressed.emit()
    view.refresh(m.state)
    until_sync(lambda: m.state.value is not None and not m.state.value.busy, what="the answer", qtbot=qtbot)
    view.refresh(m.state)
    assert view.result.text().startswith("✓ dock")
    assert sim_thread.robot.docking or sim_thread.robot.docked
    shoot(qtbot, view, "Dock", (200, 130), "button", tmp_path)
    m.set_value(CallStatus("busy", "/dock"))
    view.refresh(m.state)
    assert view.result.text() == "calling /dock…"
    m.set_value(CallStatus("failed", "/dock", "already docked"))
    view.refresh(m.state)
    assert view.result.text() == "✗ already docked"
    live.thread.call(m.stop).result(5)
