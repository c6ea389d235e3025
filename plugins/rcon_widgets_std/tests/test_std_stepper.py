"""Stepper: publish only, steps within min/max, rate-limited, values arrive on the robot."""

from rcon_widgets_std.stepper import StepperModel, StepperSettings
from std_testkit import bridge, build

from rcon_core.plugins import Role
from rcon_core.testing import ManualClock, until


def test_steps_stay_within_the_range_and_snap():
    sent = []
    m = build(StepperModel, StepperSettings(minimum=0, maximum=1, step=0.25, initial=0.5, rate_hz=100),
              "/n", "std_msgs/Float64", "publish", "data", clock=ManualClock())
    m.publish_value = lambda v: sent.append(v) or True
    assert m.current == 0.5 and m.state.value is None
    assert [m.up(), m.up(), m.up(), m.down()] == [0.75, 1.0, 1.0, 0.75]
    assert m.set_to(-4) == 0.0 and m.state.value == 0.0
    assert sent == [0.75, 1.0, 1.0, 0.75, 0.0]  # without a loop the limiter sends the kept value at once


def test_integer_field_and_problems():
    m = build(StepperModel, StepperSettings(minimum=-200, maximum=200, step=0.4), "/n", "std_msgs/Int8", "publish",
              "data")
    r = m.range
    assert (r.minimum, r.maximum, r.step) == (-128, 127, 1)  # a saved layout's range: clamped, and refused
    assert m.problems() == ["minimum -200 is beyond what a int8 holds (-128..127)",
                            "maximum 200 is beyond what a int8 holds (-128..127)"]
    m = build(StepperModel, StepperSettings(minimum=-100, maximum=100, step=0.4), "/n", "std_msgs/Int8", "publish",
              "data")
    assert m.range.step == 1 and m.problems() == []
    assert "outside" in StepperSettings(initial=20).problems()[0]
    assert "less than maximum" in StepperSettings(minimum=3, maximum=3).problems()[0]


def test_rate_limit_with_a_fake_clock():
    clock, sent, timers = ManualClock(), [], []
    m = build(StepperModel, StepperSettings(rate_hz=2), "/n", "std_msgs/Int32", "publish", "data", clock=clock,
              schedule=lambda delay, fn: timers.append(fn))
    m.publish_value = lambda v: sent.append(v) or True
    m.up()
    m.up()
    m.up()
    assert sent == [1] and m.state.value == 3 and len(timers) == 1
    clock.now += 0.5
    timers.pop()()
    assert sent == [1, 3]


async def test_stepper_sets_the_speed_limit_on_the_robot(sim):
    async with bridge(sim) as client:
        m = build(StepperModel, StepperSettings(minimum=0, maximum=3, step=0.5, initial=1.0, rate_hz=20),
                  "/speed_limit", "std_msgs/Float64", "publish", "data", client=client)
        assert Role.PUBLISH is m.binding.role
        m.start()
        m.up()
        m.up()
        await sim.wait_for_published("/speed_limit", lambda msg: msg["data"] == 2.0, timeout=10)
        await until(lambda: sim.robot.speed_limit == 2.0, what="the robot's limit")
        assert not m.state.stale  # no feedback expected: never stale
        m.stop()
