"""Text Field: raw data of many types shown; typed YAML/JSON published as the topic's type; wrong text
publishes nothing and names the field."""


import pytest
from rcon_widgets_std.textfield import TextFieldModel, TextFieldSettings
from std_testkit import bridge, build

from rcon_core.msgs import MessageTextError, TypeRegistry
from rcon_core.testing import flushed, until


@pytest.mark.parametrize(
    "type_,path,msg,shown",
    [("std_msgs/String", "data", {"data": "hello"}, "hello"),
     ("std_msgs/Int32", "data", {"data": -7}, "-7"),
     ("std_msgs/Bool", "data", {"data": True}, "true"),
     ("sensor_msgs/Range", "range", {"range": 1.25}, "1.25"),
     ("std_msgs/Header", "stamp", {"stamp": {"secs": 2, "nsecs": 0}}, "2.000 s"),
     ("geometry_msgs/Vector3", "", {"x": 1.0, "y": 2.0, "z": 3.0}, "x: 1.0\ny: 2.0\nz: 3.0"),
     ("sensor_msgs/Image", "data", {"data": "AAAA" * 10}, "AAAA" * 10)],
)
def test_shows_raw_data_of_many_types(type_, path, msg, shown):
    m = build(TextFieldModel, TextFieldSettings(), "/t", type_, "subscribe", path)
    m.on_message(msg)
    assert m.state.value.text == shown and not m.state.value.sent


def test_parse_typed_text_into_the_topics_type():
    m = build(TextFieldModel, TextFieldSettings(), "/cmd_vel", "geometry_msgs/Twist", "publish")
    msg = m.parse("linear: {x: 0.5}\nangular: {z: -0.2}")
    assert msg["linear"] == {"x": 0.5, "y": 0.0, "z": 0.0} and msg["angular"]["z"] == -0.2
    assert m.parse('{"linear": {"y": 1}}')["linear"]["y"] == 1.0
    with pytest.raises(MessageTextError) as err:
        m.parse("linear: {x: fast}")
    assert err.value.path == "linear.x" and "fast" in err.value.problem
    with pytest.raises(MessageTextError) as err:
        m.parse("lineal: {x: 1}")
    assert "lineal" in str(err.value)
    # a field path: the text is the field's value
    f = build(TextFieldModel, TextFieldSettings(), "/speed_limit", "std_msgs/Float64", "publish", "data")
    assert f.parse("0.8") == {"data": 0.8}
    with pytest.raises(MessageTextError) as err:
        f.parse("slow")
    assert err.value.path == "data"
    # a string field takes the text as it is, even when it looks like YAML
    s = build(TextFieldModel, TextFieldSettings(), "/say", "std_msgs/String", "publish", "data")
    assert s.parse("true: [1, 2") == {"data": "true: [1, 2"}
    # a nested message field from YAML
    v = build(TextFieldModel, TextFieldSettings(), "/imu", "sensor_msgs/Imu", "publish", "angular_velocity")
    assert v.parse("{x: 1, z: 3}")["angular_velocity"] == {"x": 1.0, "y": 0.0, "z": 3.0}
    u = build(TextFieldModel, TextFieldSettings(), "/n", "std_msgs/UInt8", "publish", "data")
    with pytest.raises(MessageTextError) as err:
        u.parse("300")
    assert err.value.path == "data"


async def test_typed_speed_limit_arrives_on_the_robot_and_bad_text_sends_nothing(sim):
    async with bridge(sim) as client:
        m = build(TextFieldModel, TextFieldSettings(), "/speed_limit", "std_msgs/Float64", "publish", "data",
                  client=client, types=TypeRegistry.empty())
        m.start()
        await until(lambda: m.types_ready, what="Float64 from the robot")
        m.submit("fast please")
        assert m.state.error.startswith("not sent: data:") and "fast please" in m.state.error
        m.submit("0.65")
        await sim.wait_for_published("/speed_limit", lambda msg: msg["data"] == 0.65, timeout=10)
        await until(lambda: sim.robot.speed_limit == 0.65, what="the robot's limit")
        assert m.state.value.sent and m.state.value.text == "0.65" and m.state.error is None
        assert len(sim.published("/speed_limit")) == 1  # the bad text published nothing
        m.stop()


async def test_whole_twist_typed_as_json_drives_cmd_vel(sim):
    async with bridge(sim) as client:
        m = build(TextFieldModel, TextFieldSettings(), "/cmd_vel", "geometry_msgs/Twist", "publish",
                  client=client)
        m.start()
        m.submit('{"linear": {"x": 0.3}, "angular": {"z": 0.1}}')
        got = await sim.wait_for_published("/cmd_vel", timeout=10)
        assert got["linear"]["x"] == 0.3 and got["angular"]["z"] == 0.1
        m.submit("{linear: {x: 0.3}, angular: {q: 1}}")
        assert "angular" in m.state.error and "q" in m.state.error
        await flushed(client, sim)
        assert len(sim.published("/cmd_vel")) == 1
        m.stop()


async def test_subscribe_depth_range_from_the_robot(sim):
    async with bridge(sim) as client:
        m = build(TextFieldModel, TextFieldSettings(decimals=2), "/depth", "sensor_msgs/Range", "subscribe",
                  "range", client=client)
        m.start()
        await until(lambda: m.state.value is not None, what="a /depth message")
        float(m.state.value.text)  # a number, formatted
        assert len(m.state.value.text.split(".")[1]) == 2
        m.stop()
