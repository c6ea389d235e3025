"""View behaviour a touch operator relies on: tapping a slider's track, seeing a button's or switch's
answer on the control itself, default sizes that fit what the widget shows."""

from __future__ import annotations

import pytest
from qtpy import QtCore, QtWidgets
from rcon_widgets_std.slider import SliderModel, SliderSettings
from rcon_widgets_std.slider_view import SliderView
from std_qtkit import LiveBridge, wait_until
from std_testkit import build

from rcon_core.msgs import TypeRegistry


@pytest.fixture
def live(sim_url):
    bridge = LiveBridge(sim_url)
    yield bridge
    bridge.close()


def _slider(live, mode: str, topic: str) -> SliderModel:
    m = SliderModel(SliderSettings(minimum=0, maximum=2, step=0.1, publish_mode=mode, follow_topic=False),
                    build(SliderModel, None, topic, "std_msgs/Float64", "publish", "data").binding,
                    live.node(f"slider-{mode}"), types=TypeRegistry.standard(), dispatch=live.thread.call)
    live.thread.call(m.start).result(5)
    return m


def _track_point(view: SliderView, fraction: float) -> QtCore.QPoint:
    """A point on the slider's track at ``fraction`` of its length (away from the handle at 0)."""
    s = view.slider
    opt = QtWidgets.QStyleOptionSlider()
    s.initStyleOption(opt)
    cc, style = QtWidgets.QStyle.ComplexControl.CC_Slider, s.style()
    groove = style.subControlRect(cc, opt, QtWidgets.QStyle.SubControl.SC_SliderGroove, s)
    handle = style.subControlRect(cc, opt, QtWidgets.QStyle.SubControl.SC_SliderHandle, s)
    span = groove.width() - handle.width()
    return QtCore.QPoint(round(groove.x() + handle.width() / 2 + span * fraction), s.height() // 2)


def _sent(sim_thread, topic: str, value: float) -> bool:
    return any(abs(msg["data"] - value) < 1e-9 for msg in sim_thread.published(topic))


def test_tapping_the_slider_track_jumps_there_and_publishes_on_release(qtbot, live, sim_thread):
    m = _slider(live, "release", "/rcon_test/tap_release")
    view = SliderView(m)
    qtbot.addWidget(view)
    view.resize(300, 120)
    view.show()
    qtbot.waitExposed(view)
    left = QtCore.Qt.MouseButton.LeftButton
    qtbot.mousePress(view.slider, left, pos=_track_point(view, 0.8))
    assert view.slider.value() == 16, "a tap moves to where it lands, not one page step"
    assert view.slider.isSliderDown() and view.value.text() == "1.60"
    qtbot.wait(300)
    assert not _sent(sim_thread, "/rcon_test/tap_release", 1.6), "on-release mode sent while the finger is down"
    qtbot.mouseRelease(view.slider, left, pos=_track_point(view, 0.8))
    wait_until(qtbot, lambda: _sent(sim_thread, "/rcon_test/tap_release", 1.6), what="1.6 sent on release")
    assert not view.slider.isSliderDown()
    live.thread.call(m.stop).result(5)


def test_tapping_the_slider_track_in_continuous_mode_publishes_while_held(qtbot, live, sim_thread):
    m = _slider(live, "continuous", "/rcon_test/tap_cont")
    view = SliderView(m)
    qtbot.addWidget(view)
    view.resize(300, 120)
    view.show()
    qtbot.waitExposed(view)
    left = QtCore.Qt.MouseButton.LeftButton
    qtbot.mousePress(view.slider, left, pos=_track_point(view, 0.3))
    assert view.slider.value() == 6
    wait_until(qtbot, lambda: _sent(sim_thread, "/rcon_test/tap_cont", 0.6), what="0.6 sent while held")
    assert view.slider.isSliderDown()
    qtbot.mouseRelease(view.slider, left, pos=_track_point(view, 0.3))
    live.thread.call(m.stop).result(5)


def test_tapping_the_slider_handle_itself_does_not_move_it(qtbot, live, sim_thread):
    m = _slider(live, "release", "/rcon_test/tap_handle")
    view = SliderView(m)
    qtbot.addWidget(view)
    view.resize(300, 120)
    view.show()
    qtbot.waitExposed(view)
    view.slider.setValue(10)
    left = QtCore.Qt.MouseButton.LeftButton
    qtbot.mousePress(view.slider, left, pos=_track_point(view, 0.5))
    qtbot.mouseRelease(view.slider, left, pos=_track_point(view, 0.5))
    assert view.slider.value() == 10
    live.thread.call(m.stop).result(5)
