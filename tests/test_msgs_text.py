"""Messages typed by a person: YAML/JSON in, complete wire-shape dicts out, precise errors."""

import json
import math

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rcon_core.msgs import MessageTextError, Problem, TypeRegistry
from rcon_core.msgs.strategies import message
from rcon_core.msgs.text import parse_text

REG = TypeRegistry.standard()
REG2 = TypeRegistry.standard(ros2=True)


def test_yaml_fills_missing_fields():
    assert REG.from_text("geometry_msgs/Twist", "linear: {x: 0.5}\nangular:\n  z: -1") == {
        "linear": {"x": 0.5, "y": 0.0, "z": 0.0},
        "angular": {"x": 0.0, "y": 0.0, "z": -1.0},
    }


def test_json_works_too():
    msg = REG.from_text("sensor_msgs/NavSatFix", '{"latitude": 43.77, "longitude": -79.5, "status": {"status": -1}}')
    assert msg["latitude"] == 43.77 and msg["status"] == {"status": -1, "service": 0}
    assert msg["position_covariance"] == [0.0] * 9 and msg["header"]["stamp"] == {"secs": 0, "nsecs": 0}


def test_empty_text_is_the_default_message():
    assert REG.from_text("std_msgs/Header", "  \n") == REG.default("std_msgs/Header")


def test_single_field_shorthand():
    assert REG.from_text("std_msgs/Float64", "2.5") == {"data": 2.5}
    assert REG.from_text("std_msgs/String", "hello") == {"data": "hello"}
    assert REG.from_text("std_msgs/Bool", "true") == {"data": True}


def test_values_are_converted_to_the_wire_shape():
    img = REG.from_text("sensor_msgs/Image", "data: [0, 1, 255]\nstep: 3.0")
    assert img["data"] == "AAH/" and img["step"] == 3 and isinstance(img["step"], int)
    assert REG.from_text("sensor_msgs/Image", "data: AAH/")["data"] == "AAH/"
    stamp = REG.from_text("std_msgs/Header", "stamp: 12.25")["stamp"]
    assert stamp == {"secs": 12, "nsecs": 250_000_000}
    # either time shape in, the flavour's shape out
    assert REG.from_text("std_msgs/Header", "stamp: {sec: 3, nanosec: 4}")["stamp"] == {"secs": 3, "nsecs": 4}
    assert REG2.from_text("std_msgs/Header", "stamp: {secs: 3, nsecs: 4}")["stamp"] == {"sec": 3, "nanosec": 4}
    assert REG.from_text("std_msgs/Float64", "data: 1e-5") == {"data": 1e-5}  # YAML 1.1 would say "1e-5"
    # NaN and infinity only where the caller allows them (a laser scan's "no return")
    scan = REG.from_text("sensor_msgs/LaserScan", "ranges: [1, .inf, .nan, null, nan]", finite=False)["ranges"]
    assert scan[0] == 1.0 and math.isinf(scan[1]) and all(math.isnan(v) for v in scan[2:])


@pytest.mark.parametrize("text", ["nan", ".nan", "data: NaN", "inf", "-.inf", "data: -Infinity", "data: null"])
def test_typed_non_finite_numbers_are_refused_unless_allowed(text):
    with pytest.raises(MessageTextError) as info:
        REG.from_text("std_msgs/Float64", text)
    assert info.value.path == "data" and "not a finite number" in info.value.problem
    with pytest.raises(MessageTextError, match=r"ranges\[1\]: .*not a finite number"):
        REG.from_text("sensor_msgs/LaserScan", "ranges: [1, .inf]")
    assert REG.from_text("std_msgs/Float64", "2.5") == {"data": 2.5}
    # a dict made by code is still checked as before, unless told
    assert math.isnan(REG.complete("std_msgs/Float64", {"data": math.nan})["data"])
    assert REG.validate("std_msgs/Float64", {"data": math.inf}, finite=True)


@pytest.mark.parametrize("text", ["1e5", "1E5", "data: 1e5", '{"data": 1e5}', "1e+5", "100000"])
def test_numbers_as_a_person_types_them(text):
    """issue 21.12: ``1e5`` was refused as "got a string" (YAML 1.1 wants a dot in an exponent)."""
    assert REG.from_text("std_msgs/Float64", text) == {"data": 100000.0}
    assert parse_text(text.removeprefix("data: ")) in (100000.0, {"data": 100000.0}, 100000)


@pytest.mark.parametrize("text", ["1.0e+400", "data: 1e400", '{"data": -1.0e+400}'])
def test_a_number_that_overflows_to_infinity_is_refused_with_a_word(text):
    """issue 21.12: ``1.0e+400`` became ``.inf`` without a word. Refused even where infinity is allowed: a
    deliberate infinity is spelled ``.inf``."""
    with pytest.raises(MessageTextError, match=r"is too large for a number \(it would become infinity\)"):
        parse_text(text)
    with pytest.raises(MessageTextError, match="too large"):
        REG.from_text("std_msgs/Float64", text, finite=False)
    with pytest.raises(MessageTextError, match="2e308 is too large"):
        REG.from_text("sensor_msgs/LaserScan", "ranges: [1, 2e308]", finite=False)
    assert math.isinf(REG.from_text("std_msgs/Float64", "data: .inf", finite=False)["data"])
    assert parse_text("1e308") == 1e308


@pytest.mark.parametrize(
    ("type_name", "text", "path", "problem"),
    [
        ("geometry_msgs/Twist", "linear: {x: abc}", "linear.x", "expected a number, got 'abc'"),
        ("geometry_msgs/Twist", "linear: {foo: 1}", "linear.foo", "unknown field 'foo' (known: x, y, z)"),
        ("sensor_msgs/Image", "is_bigendian: 300", "is_bigendian", "value 300 out of range for uint8"),
        ("sensor_msgs/Imu", "orientation_covariance: [1, 2, 3, 4]", "orientation_covariance",
         "expected 9 items, got 4"),
        ("geometry_msgs/PoseWithCovariance", "covariance: [0,0,0,x" + ",0" * 32 + "]", "covariance[3]",
         "expected a number, got 'x'"),
        ("std_msgs/Int8", "data: -129", "data", "value -129 out of range for int8"),
        ("std_msgs/Int32", "data: 1.5", "data", "expected an integer, got 1.5"),
        ("std_msgs/Bool", "data: 2", "data", "expected true or false, got 2"),
        ("std_msgs/Header", "frame_id: 12", "frame_id", "expected a string, got 12"),
        ("std_msgs/Header", "stamp: {secs: 1, msecs: 2}", "stamp.msecs", "unknown field 'msecs'"),
        ("geometry_msgs/Twist", "linear: 5", "linear", "expected a mapping of the fields of geometry_msgs/Vector3"),
        ("sensor_msgs/Image", "data: [1, 256]", "data[1]", "expected a byte 0..255, got 256"),
        ("sensor_msgs/Image", "data: '%%%'", "data", "expected base64 text"),
        ("sensor_msgs/LaserScan", "ranges: 3", "ranges", "expected a list, got 3"),
        ("std_msgs/Float32", "data: 1e39", "data", "out of range for float32"),
        ("geometry_msgs/Twist", "linear: {x: 1", "", "not valid YAML or JSON (line 1"),
    ],
)
def test_errors_name_the_place_and_the_problem(type_name, text, path, problem):
    with pytest.raises(MessageTextError) as info:
        REG.from_text(type_name, text)
    assert info.value.path == path
    assert problem in info.value.problem
    assert path in str(info.value) and problem in str(info.value)


def test_to_text_quotes_strings_that_look_like_numbers():
    msg = REG.complete("std_msgs/Header", {"frame_id": "0E0"})
    assert "'0E0'" in REG.to_text(msg)
    assert REG.from_text("std_msgs/Header", REG.to_text(msg)) == msg


def test_all_problems_are_collected():
    with pytest.raises(MessageTextError) as info:
        REG.from_text("geometry_msgs/Twist", "linear: {x: a, y: b}\nspin: 1")
    assert [p.path for p in info.value.problems] == ["spin", "linear.x", "linear.y"]


def test_validate():
    assert REG.validate("geometry_msgs/Twist", REG.default("geometry_msgs/Twist")) == []
    problems = REG.validate("sensor_msgs/Imu", {"orientation_covariance": [1, 2], "header": {"seq": -1}})
    assert problems == [
        Problem("header.seq", "value -1 out of range for uint32 (0..4294967295)"),
        Problem("orientation_covariance", "expected 9 items, got 2"),
    ]
    assert str(problems[1]) == "orientation_covariance: expected 9 items, got 2"
    # what a server sends over JSON is valid as it is: None for NaN, base64 bytes
    assert REG.validate("sensor_msgs/LaserScan", {"ranges": [None, 1.0]}) == []
    assert REG.validate("sensor_msgs/CompressedImage", {"data": "/9j/4AAQ"}) == []


def test_complete_accepts_bytes_and_tuples():
    msg = REG.complete("sensor_msgs/CompressedImage", {"data": b"\xff\xd8", "format": "jpeg"})
    assert msg["data"] == "/9g=" and msg["header"]["seq"] == 0
    assert REG.complete("geometry_msgs/PoseWithCovariance", {"covariance": tuple(range(36))})["covariance"][35] == 35.0


TYPES = ["sensor_msgs/Imu", "sensor_msgs/Image", "rosgraph_msgs/Log", "visualization_msgs/Marker",
         "sensor_msgs/BatteryState", "nav_msgs/OccupancyGrid"]


@pytest.mark.parametrize("type_name", TYPES)
@settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_yaml_round_trip_property(type_name, data):
    # PyYAML folds C1 line breaks such as NEL inside plain text; people do not type those
    printable = st.text(st.characters(exclude_categories=("Cc", "Cs", "Zl", "Zp")), max_size=12)
    msg = data.draw(message(REG, REG.resolve(type_name), text=printable))
    text = REG.to_text(msg)
    assert REG.from_text(type_name, text) == msg
    assert REG.from_text(type_name, json.dumps(msg)) == msg
    assert REG.validate(type_name, msg) == []
