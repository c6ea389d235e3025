"""Slider: ranges clamped to the field type, step snapping, rate limiting, publish and subscribe against
the robot, types learned from the robot, a numeric field inside a larger message."""

import math

import pytest
from rcon_widgets_std.common import RateLimiter
from rcon_widgets_std.slider import (
    PUBLISH_CONTINUOUS,
    SliderModel,
    SliderSettings,
    number_range,
)
from rcon_widgets_std.stepper import StepperSettings
from std_testkit import bridge, build

from rcon_core.msgs import TypeRegistry
from rcon_core.testing import ManualClock, until


@pytest.mark.parametrize(
    "type_,lo,hi",
    [("std_msgs/Int8", -128, 127), ("std_msgs/UInt8", 0, 255), ("std_msgs/Int16", -32768, 32767),
     ("std_msgs/UInt16", 0, 65535), ("std_msgs/Int32", -(2**31), 2**31 - 1), ("std_msgs/UInt32", 0, 2**32 - 1),
     ("std_msgs/Int64", -(2**63), 2**63 - 1), ("std_msgs/UInt64", 0, 2**64 - 1),
     ("std_msgs/Float32", -3.4028234663852886e38, 3.4028234663852886e38),
     ("std_msgs/Float64", -1e300, 1e300)],
)
def test_range_is_clamped_to_every_standard_numeric_type_and_such_settings_are_refused(type_, lo, hi):
    """The range a saved layout asks for is still clamped to what the field holds (nothing beyond it is
    ever sent), but such settings are refused with a sentence (issue 21.4: 999999999999 was accepted)."""
    m = build(SliderModel, SliderSettings(minimum=-1e300, maximum=1e300, step=1), "/n", type_, "publish", "data")
    r = m.range
    assert (r.minimum, r.maximum) == (lo, hi)
    assert r.clamped == (type_ != "std_msgs/Float64")
    assert r.integer == ("Int" in type_)
    assert m.problems()[0] == "minimum -1e+300 is out of any sane range (at most ±1e+09): a slip of a finger?"
    top = r.coerce(1e301)
    assert top == hi and (isinstance(top, int) if r.integer else isinstance(top, float))


@pytest.mark.parametrize("type_,path,maximum,problem", [
    ("std_msgs/Int8", "data", 500, "maximum 500 is beyond what a int8 holds (-128..127)"),
    ("std_msgs/UInt8", "data", 256, "maximum 256 is beyond what a uint8 holds (0..255)"),
    ("geometry_msgs/Twist", "linear.x", 999999999999,
     "maximum 1e+12 is out of any sane range (at most ±1e+09): a slip of a finger?"),
    ("geometry_msgs/Twist", "linear.x", 1000, "maximum 1000 is beyond what any safety envelope allows on linear "
                                              "(±100 m/s)"),
    ("geometry_msgs/TwistStamped", "twist.angular.z", 60, "maximum 60 is beyond what any safety envelope allows "
                                                          "on angular (±50 rad/s)"),
    ("std_msgs/Float32", "data", 2e9, "maximum 2e+09 is out of any sane range (at most ±1e+09): a slip of a finger?"),
])
def test_numeric_settings_outside_the_fields_sane_range_are_refused(type_, path, maximum, problem):
    """issue 21.4: a slider's maximum typed as 999999999999 on /cmd_vel linear.x was accepted."""
    m = build(SliderModel, SliderSettings(minimum=0, maximum=maximum, step=1), "/n", type_, "publish", path)
    assert m.problems() == [problem]
    ok = build(SliderModel, SliderSettings(minimum=0, maximum=50 if "Twist" in type_ else 127, step=1), "/n",
               type_, "publish", path)
    assert ok.problems() == []
    # what the add panel and Configure ask before placing or saving (no model yet): the settings against the
    # binding say the same, beside the settings' own problems (each said once)
    types = TypeRegistry.standard()
    settings = SliderSettings(minimum=0, maximum=maximum, step=1)
    assert settings.problems() + settings.binding_problems(m.binding, types) == [problem]
    assert ok.settings.binding_problems(ok.binding, types) == []
    stepper = StepperSettings(minimum=0, maximum=maximum, step=1)
    assert stepper.problems() + stepper.binding_problems(m.binding, types) == [problem]


def test_the_settings_against_a_binding_say_nothing_until_the_binding_and_its_type_are_known():
    from rcon_core.plugins import Binding

    settings = SliderSettings(minimum=0, maximum=500, step=1)
    types = TypeRegistry.standard()
    assert settings.binding_problems(Binding("/gear", "std_msgs/Int8", "publish", ("data",)), None) == []
    assert settings.binding_problems(Binding(role="publish"), types) == []  # no topic chosen yet
    assert settings.binding_problems(Binding("/gear", "lab_msgs/Gear", "publish", ("data",)), types) == []
    assert settings.binding_problems(Binding("/gear", "std_msgs/Int8", "publish", ("data",)), types) == [
        "maximum 500 is beyond what a int8 holds (-128..127)"]


def test_step_snapping_and_integer_rounding():
    r = number_range(0.0, 1.0, 0.25, "float64")
    assert [r.coerce(v) for v in (-3, 0.1, 0.13, 0.62, 0.99, 7)] == [0.0, 0.0, 0.25, 0.5, 1.0, 1.0]
    ri = number_range(-10.4, 10.6, 2.6, "int8")  # integer fields: whole bounds, whole steps
    assert (ri.minimum, ri.maximum, ri.step) == (-10, 10, 3)
    assert ri.coerce(0.4) == -1 and isinstance(ri.coerce(0.4), int)
    assert ri.steps == 7


def test_problems_name_what_is_wrong():
    assert SliderSettings().problems() == []
    assert "less than maximum" in SliderSettings(minimum=2, maximum=1).problems()[0]
    assert "step must be more than 0" in SliderSettings(step=0).problems()[0]
    assert "larger than the range" in SliderSettings(step=5).problems()[0]
    assert "update rate" in SliderSettings(rate_hz=0).problems()[0]
    assert "finite" in SliderSettings(maximum=math.nan).problems()[0]
    assert "publish must be" in SliderSettings(publish_mode="sometimes").problems()[0]
    # the bound field must be a number
    m = build(SliderModel, SliderSettings(), "/battery", "sensor_msgs/BatteryState", "subscribe", "header.frame_id")
    assert "must be a number" in m.problems()[0]
    m = build(SliderModel, SliderSettings(), "/battery", "sensor_msgs/BatteryState", "subscribe", "percentagee")
    assert "no field 'percentagee'" in m.problems()[0]
    # a range with nothing a uint8 can hold: refused, its first end named
    m = build(SliderModel, SliderSettings(minimum=-10, maximum=-1, step=1), "/n", "std_msgs/UInt8", "publish", "data")
    assert m.problems()[0] == "minimum -10 is beyond what a uint8 holds (0..255)"


def test_rate_limiter_keeps_the_latest_and_never_loses_it():
    clock, sent, timers = ManualClock(), [], []
    lim = RateLimiter(sent.append, 10.0, schedule=lambda d, fn: timers.append((d, fn)), clock=clock)
    lim.offer(1)
    assert sent == [1]
    clock.now += 0.02
    lim.offer(2)
    lim.offer(3)
    assert sent == [1] and len(timers) == 1 and timers[0][0] == pytest.approx(0.08)
    clock.now += 0.08
    timers.pop()[1]()
    assert sent == [1, 3]
    lim.offer(4)  # too soon after 3: kept
    lim.now(5)  # a release goes out at once and drops the kept 4
    assert sent == [1, 3, 5]
    assert timers and (timers.pop()[1]() or sent == [1, 3, 5])  # the stale timer sends nothing


async def test_release_publishes_speed_limit_on_the_robot(sim):
    async with bridge(sim) as client:
        m = build(SliderModel, SliderSettings(minimum=0, maximum=2, step=0.05), "/speed_limit",
                  "std_msgs/Float64", "publish", "data", client=client)
        m.start()
        assert m.drag(0.5) == 0.5  # on-release mode: dragging publishes nothing
        assert m.release(0.73) == 0.75
        got = await sim.wait_for_published("/speed_limit", lambda msg: msg["data"] == 0.75, timeout=10)
        assert got == {"data": 0.75}
        await until(lambda: sim.robot.speed_limit == 0.75, what="the robot applying the limit")
        assert all(msg["data"] != 0.5 for msg in sim.published("/speed_limit"))
        assert m.state.value == 0.75
        m.stop()


async def test_continuous_mode_publishes_while_dragging_and_the_last_value_arrives(sim):
    async with bridge(sim) as client:
        m = build(SliderModel, SliderSettings(minimum=0, maximum=3, step=0.1, rate_hz=2,
                                              publish_mode=PUBLISH_CONTINUOUS),
                  "/speed_limit", "std_msgs/Float64", "publish", "data", client=client)
        m.start()
        for v in (0.1, 0.2, 0.3, 0.4, 1.2):
            m.drag(v)
        await sim.wait_for_published("/speed_limit", lambda msg: msg["data"] == 1.2, timeout=10)
        sent = [msg["data"] for msg in sim.published("/speed_limit")]
        assert sent[0] == 0.1 and sent[-1] == 1.2 and len(sent) < 5  # the drags in between coalesced
        m.stop()


async def test_numeric_field_in_a_larger_message_cmd_vel(sim):
    async with bridge(sim) as client:
        m = build(SliderModel, SliderSettings(minimum=-1, maximum=1, step=0.1), "/cmd_vel",
                  "geometry_msgs/Twist", "publish", "angular.z", client=client)
        m.start()
        m.release(-0.3)
        got = await sim.wait_for_published("/cmd_vel", lambda msg: msg["angular"]["z"] == -0.3, timeout=10)
        assert got["linear"] == {"x": 0.0, "y": 0.0, "z": 0.0} and got["angular"]["x"] == 0.0
        m.stop()


async def test_subscribe_battery_percentage_with_a_type_learned_from_the_robot(sim):
    async with bridge(sim) as client:
        types = TypeRegistry.empty()
        m = build(SliderModel, SliderSettings(minimum=0, maximum=1), "/battery", "sensor_msgs/BatteryState",
                  "subscribe", "percentage", client=client, types=types)
        assert not m.types_ready
        m.start()
        await until(lambda: m.types_ready and isinstance(m.state.value, float), what="typedefs and a value")
        assert types.has("sensor_msgs/BatteryState")  # learned via /rosapi/message_details
        assert m.field_base == "float32" and m.range.clamped is False
        assert abs(m.state.value - sim.robot.battery_fraction) < 0.02
        assert m.problems() == []
        m.stop()


async def test_int8_slider_on_a_type_learned_from_the_robot_clamps_to_127(sim):
    async with bridge(sim) as client:
        m = build(SliderModel, SliderSettings(minimum=-500, maximum=500, step=1), "/rcon_test/level",
                  "std_msgs/Int8", "publish", "data", client=client, types=TypeRegistry.empty())
        m.start()
        await until(lambda: m.types_ready, what="typedefs")
        assert (m.range.minimum, m.range.maximum) == (-128, 127)
        assert m.release(400) == 127
        got = await sim.wait_for_published("/rcon_test/level", timeout=10)
        assert got == {"data": 127}
        m.stop()


async def test_publish_slider_says_not_set_then_sent_then_remembered(sim):
    async with bridge(sim) as client:
        settings = SliderSettings(minimum=0.5, maximum=2, step=0.1, follow_topic=False)
        m = build(SliderModel, settings, "/rcon_test/limit_a", "std_msgs/Float64", "publish", "data",
                  client=client, node="a")
        m.start()
        assert m.state.value is None  # nothing sent or heard: no value that could pass for the robot's
        assert m.resting == 0.5  # the handle rests at the start value 0 clamped to the minimum
        m.release(1.3)
        await sim.wait_for_published("/rcon_test/limit_a", lambda msg: msg["data"] == 1.3, timeout=10)
        assert m.state.value == 1.3
        m.stop()
        again = build(SliderModel, settings, "/rcon_test/limit_a", "std_msgs/Float64", "publish", "data",
                      client=client, node="a2")  # the canvas was switched away and back
        again.start()
        assert again.state.value == 1.3
        again.stop()
        other = build(SliderModel, SliderSettings(minimum=0, maximum=2, initial=0.8, follow_topic=False),
                      "/rcon_test/limit_b", "std_msgs/Float64", "publish", "data", client=client, node="b")
        other.start()
        assert other.state.value is None and other.resting == 0.8
        other.stop()


async def test_publish_slider_follows_what_others_publish_on_its_topic(sim):
    async with bridge(sim) as client:
        follow = build(SliderModel, SliderSettings(minimum=0, maximum=3, step=0.1), "/rcon_test/limit_c",
                       "std_msgs/Float64", "publish", "data", client=client, node="follow")
        deaf = build(SliderModel, SliderSettings(minimum=0, maximum=3, step=0.1, follow_topic=False),
                     "/rcon_test/limit_c", "std_msgs/Float64", "publish", "data", client=client, node="deaf")
        follow.start()
        deaf.start()
        await until(lambda: sim.topic_subscriber_count("/rcon_test/limit_c") >= 1, what="the follow subscription")
        stepper_console = client.node("another-console").advertise("/rcon_test/limit_c", "std_msgs/Float64")
        stepper_console.publish({"data": 2.25})
        await until(lambda: follow.state.value == 2.25, what="the other publisher's value")
        assert deaf.state.value is None
        echoes: list = []  # on the subscription the slider shares: its echo reaches the slider no later
        probe = client.node("probe")
        probe.subscribe("/rcon_test/limit_c", echoes.append)
        follow.release(1.0)  # and its own value still goes out and is shown
        await sim.wait_for_published("/rcon_test/limit_c", lambda msg: msg["data"] == 1.0, timeout=10)
        await until(lambda: {"data": 1.0} in echoes, what="the echo of the slider's own value")
        assert follow.state.value == 1.0
        probe.close()
        follow.stop()
        deaf.stop()
        await until(lambda: sim.topic_subscriber_count("/rcon_test/limit_c") == 0, what="unsubscribed on stop")


def test_start_value_must_be_a_number():
    assert SliderSettings(initial=float("nan")).problems() == ["start value must be a finite number, not nan"]
