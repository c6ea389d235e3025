"""Label: formatting (decimals, units, scale), whole messages, age and staleness; /battery end to end."""

import math

from rcon_widgets_std.common import format_value
from rcon_widgets_std.label import LabelModel, LabelSettings
from std_testkit import bridge, build

from rcon_core.msgs import TypeRegistry
from rcon_core.testing import ManualClock, until


def test_number_formatting_with_decimals_units_and_scale():
    m = build(LabelModel, LabelSettings(decimals=1, units="%", scale=100), "/battery",
              "sensor_msgs/BatteryState", "subscribe", "percentage")
    m.on_message({"percentage": 0.8766, "voltage": 12.0})
    assert m.state.value.text == "87.7 %" and m.state.value.numeric
    m.settings.decimals = -1
    m.on_message({"percentage": 0.5})
    assert m.state.value.text == "50 %"
    assert format_value(3, 2, "m") == "3.00 m"
    assert format_value(None) == "NaN"  # NaN arrives as null on the JSON wire
    assert format_value(math.inf, 2) == "inf"
    assert format_value(True) == "true"
    assert format_value({"secs": 3, "nsecs": 500_000_000}) == "3.500 s"


def test_as_received_shows_every_digit_of_the_value():
    """issue 22.20: "as received" rounded to 6 digits (43.6532117 -> 43.6532)."""
    m = build(LabelModel, LabelSettings(decimals=-1), "/gps/fix", "sensor_msgs/NavSatFix", "subscribe", "latitude")
    m.on_message({"latitude": 43.6532117})
    assert m.state.value.text == "43.6532117"
    m.on_message({"latitude": -79.38318429999999})
    assert m.state.value.text == "-79.3831843"  # every digit the double carries, not its last bit of noise
    m.on_message({"latitude": 12.0})
    assert m.state.value.text == "12"
    assert format_value(1234567.891, -1) == "1234567.891" and format_value(7, -1) == "7"


def test_a_battery_fraction_is_shown_in_percent():
    """issue 21.12: a Label on /battery showed 0.85 (BatteryState.percentage is 0..1)."""
    m = build(LabelModel, LabelSettings(), "/battery", "sensor_msgs/msg/BatteryState", "subscribe", "percentage")
    m.on_message({"percentage": 0.8534})
    assert m.state.value.text == "85 %" and m.state.value.raw == 85.34
    m.settings.decimals = 3
    m.on_message({"percentage": 0.8534})
    assert m.state.value.text == "85.3 %"
    m.settings.decimals = -1
    m.on_message({"percentage": 0.8534})
    assert m.state.value.text == "85.34 %"
    # the operator's own scale and units win (the demo's: scale 100, "%")
    own = build(LabelModel, LabelSettings(decimals=0, scale=100, units="%"), "/battery", "sensor_msgs/BatteryState",
                "subscribe", "percentage")
    own.on_message({"percentage": 0.85})
    assert own.state.value.text == "85 %"
    other = build(LabelModel, LabelSettings(), "/battery", "sensor_msgs/BatteryState", "subscribe", "voltage")
    other.on_message({"voltage": 12.6})
    assert other.state.value.text == "12.60"


def test_never_negative_zero_after_rounding():
    m = build(LabelModel, LabelSettings(decimals=2, units="rad/s"), "/imu/data", "sensor_msgs/Imu", "subscribe",
              "angular_velocity.z")
    m.on_message({"angular_velocity": {"z": -0.0012}})
    assert m.state.value.text == "0.00 rad/s"
    m.on_message({"angular_velocity": {"z": -0.0}})
    assert m.state.value.text == "0.00 rad/s"
    m.on_message({"angular_velocity": {"z": -0.006}})
    assert m.state.value.text == "-0.01 rad/s"  # a real negative value keeps its sign
    assert format_value(-0.0) == "0" and format_value(-1e-9, 3) == "0.000" and format_value(-2, 1) == "-2.0"
    assert format_value([-0.0001, 0.5], 1) == "[0.0, 0.5]"
    assert "-0.0" not in format_value({"x": -0.0, "y": 1.0})


def test_whole_message_and_long_arrays_are_summarised():
    m = build(LabelModel, LabelSettings(), "/scan", "sensor_msgs/LaserScan", "subscribe")
    m.on_message({"angle_min": -1.5, "ranges": [1.0] * 500, "header": {"frame_id": "laser"}})
    text = m.state.value.text
    assert "angle_min: -1.5" in text and "frame_id: laser" in text
    assert "492 more" in text and text.count("1.0") < 20
    m.on_message({"data": "YWJj" * 1000})
    assert len(m.state.value.text) < 100


def test_missing_field_is_an_error_not_a_crash():
    m = build(LabelModel, LabelSettings(), "/battery", "sensor_msgs/BatteryState", "subscribe", "percentage")
    m.on_message({"voltage": 12.0})
    assert "percentage" in m.state.error and m.state.value is None


class FakePort:
    def __init__(self):
        self.subscribed = []

    def subscribe(self, topic, callback, **options):
        self.subscribed.append(topic)
        return self

    def unsubscribe(self):
        self.subscribed.pop()


def test_age_and_stale_after_setting():
    clock = ManualClock()
    m = build(LabelModel, LabelSettings(stale_after=2.0), "/x", "std_msgs/Float64", "subscribe", "data",
              clock=clock)
    m.port = FakePort()
    m.start()
    assert m.port.subscribed == ["/x"]
    m.on_message({"data": 1.0})
    clock.now += 1.5
    st = m.state
    assert st.age == 1.5 and not st.stale
    clock.now += 1.0
    assert m.state.stale
    m.on_message({"data": 2.0})
    assert not m.state.stale and m.state.value.text == "2.00"
    m.stop()
    assert m.port.subscribed == []


def test_settings_problems():
    assert LabelSettings().problems() == []
    p = LabelSettings(decimals=20, stale_after=-1, scale=0).problems()
    assert any("decimals" in x for x in p) and any("stale" in x for x in p) and any("scale" in x for x in p)


async def test_battery_percentage_from_the_robot(sim):
    async with bridge(sim) as client:
        # a registry that knows nothing: a Label needs no definition to show what arrives
        m = build(LabelModel, LabelSettings(decimals=1, units="%", scale=100), "/battery",
                  "sensor_msgs/BatteryState", "subscribe", "percentage", client=client,
                  types=TypeRegistry.empty())
        m.start()
        await until(lambda: m.state.value is not None, what="a battery message")
        expected = sim.robot.battery_fraction * 100
        got = float(m.state.value.text.split()[0])
        assert abs(got - expected) < 2.0 and m.state.value.text.endswith("%")
        assert m.state.age is not None and not m.state.stale
        assert sim.topic_subscriber_count("/battery") >= 1
        m.stop()
        await until(lambda: sim.topic_subscriber_count("/battery") == 0, what="unsubscribe")
