"""Teleop pad rates and zeros on a clock the test moves (``ManualClock``), so counts are exact, not windows.

The pad's ticker and its ``send_times`` run on the manual clock; the port records what would go to the
robot. ``test_sensors_teleop_model.py`` drives the same model against the sim end to end.
"""

import pytest
from rcon_widgets_sensors.teleop import TeleopModel, TeleopSettings

from rcon_core.plugins import Binding, SharedResources, WidgetContext
from rcon_core.testing import ManualClock, RecordingPort

TWIST = "geometry_msgs/Twist"


def pad(port, clock, settings=None, context=None):
    return TeleopModel(settings or TeleopSettings(), Binding("/cmd_vel", TWIST, "publish"), port,
                       clock=clock, ticker_clock=clock, context=context)


def sent(port):
    return [msg for topic, msg in port.published if topic == "/cmd_vel"]


def is_zero(msg):
    return all(v == 0 for part in ("linear", "angular") for v in msg[part].values())


def test_held_pad_publishes_at_its_rate_then_one_zero_on_release():
    clock, port = ManualClock(), RecordingPort()
    model = pad(port, clock, TeleopSettings(rate_hz=20, max_linear=2.0))
    model.start()
    try:
        clock.advance(1.0)
        assert sent(port) == []  # idle: nothing at all, not even zeros
        model.set_axes(0.0, 0.5)  # half way up: linear.x = 2.0 * (0.5 - 0.1) / 0.9
        assert len(sent(port)) == 1  # the first command goes out at once, not on the first tick
        clock.advance(1.025)
        held = sent(port)
        assert len(held) == 21  # 20 Hz for a second: the first one plus 20 ticks
        assert all(m["linear"]["x"] == pytest.approx(2.0 * 0.4 / 0.9) and m["angular"]["z"] == 0.0
                   for m in held)
        gaps = [b - a for a, b in zip(model.send_times, model.send_times[1:], strict=False)]
        assert gaps == pytest.approx([0.05] * 20)  # steady
        assert model.state.value.active and model.state.value.sent == 21
        model.release()
        assert len(sent(port)) == 22 and is_zero(sent(port)[-1])  # the zero at the lift, not on a tick
        clock.advance(1.0)
        assert len(sent(port)) == 22 and clock.pending == 0  # then silence: no timer left
        model.release()  # releasing an idle pad sends nothing
        assert len(sent(port)) == 22
    finally:
        model.stop()


REASONS = {"release": "released", "on_focus_lost": "focus lost", "stop": "stopped", "link_down": "link down"}


def test_pads_on_two_robot_links_do_not_merge():
    """Each robot's pads form their own group (``WidgetContext.shared`` is per link): two streams."""
    clock, shared = ManualClock(), SharedResources()
    port_a, port_b = RecordingPort(), RecordingPort()
    a = pad(port_a, clock, TeleopSettings(horizontal="", vertical="linear.x", rate_hz=10), on_link(shared, "a"))
    b = pad(port_b, clock, TeleopSettings(horizontal="-angular.z", vertical="", rate_hz=10, dead_zone=0),
            on_link(shared, "b"))
    a.start()
    b.start()
    try:
        a.set_axes(0.0, 1.0)
        b.set_axes(0.5, 0.0)
        clock.advance(1.025)
        assert len(sent(port_a)) == 11 and len(sent(port_b)) == 11  # each its own stream, its own axes only
        assert sent(port_a)[-1]["linear"]["x"] == pytest.approx(1.0) and sent(port_a)[-1]["angular"]["z"] == 0
        assert sent(port_b)[-1]["angular"]["z"] == pytest.approx(-0.5) and sent(port_b)[-1]["linear"]["x"] == 0
    finally:
        a.stop()
        b.stop()


@pytest.mark.parametrize("let_go", list(REASONS))
def test_every_way_of_letting_go_sends_one_zero_at_once(let_go):
    clock, port = ManualClock(), RecordingPort()
    model = pad(port, clock, TeleopSettings(rate_hz=10))
    model.start()
    try:
        model.set_axes(0.0, 0.8)
        clock.advance(0.35)
        n = len(sent(port))
        assert n == 4 and not is_zero(sent(port)[-1])
        if let_go == "link_down":
            model.set_link(False)
        else:
            getattr(model, let_go)()
        assert len(sent(port)) == n + 1 and is_zero(sent(port)[-1])  # before any time passes
        clock.advance(1.0)
        assert len(sent(port)) == n + 1
        value = model.state.value
        assert value.reason == REASONS[let_go] and not value.active
        # a forced stop: locked until the finger lifts (focus lost too: the finger may still be on the pad)
        assert value.locked == (let_go in ("stop", "link_down", "on_focus_lost"))
    finally:
        model.stop()


def on_link(shared, link):
    """The context the canvas runtime gives a widget on robot link ``link`` (one store per runtime)."""
    return WidgetContext(link=link, resources=shared)


def test_two_pads_on_one_connection_merge_into_one_stream():
    clock, port, shared = ManualClock(), RecordingPort(), SharedResources()  # one link: one group
    linear = pad(port, clock, TeleopSettings(horizontal="", vertical="linear.x", rate_hz=10), on_link(shared, 1))
    angular = pad(port, clock, TeleopSettings(horizontal="-angular.z", vertical="", rate_hz=10, dead_zone=0),
                  on_link(shared, 1))
    linear.start()
    angular.start()
    try:
        linear.set_axes(0.0, 1.0)
        angular.set_axes(0.5, 0.0)  # right: turn right (negative yaw rate)
        clock.advance(1.025)
        msgs = sent(port)
        assert len(msgs) == 12, len(msgs)  # each pad's first at once, then one stream of 10 ticks, not two
        assert msgs[-1]["linear"]["x"] == pytest.approx(1.0) and msgs[-1]["angular"]["z"] == pytest.approx(-0.5)
        n = len(msgs)
        linear.release()  # only its own axis drops to zero; the other pad keeps driving
        clock.advance(0.5)
        later = sent(port)[n:]
        assert len(later) == 1 + 5  # the release, then the other pad's ticks
        assert all(m["linear"]["x"] == 0 and m["angular"]["z"] == pytest.approx(-0.5) for m in later)
        n = len(sent(port))
        angular.release()
        clock.advance(1.0)
        assert len(sent(port)) == n + 1 and is_zero(sent(port)[-1])
    finally:
        linear.stop()
        angular.stop()
