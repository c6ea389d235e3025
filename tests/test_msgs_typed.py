"""Typed attrs classes built at run time, and the registry's cattrs converter."""

import math

import attrs
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rcon_core.msgs import TypeRegistry
from rcon_core.msgs.strategies import message

REG = TypeRegistry.standard()


def test_class_shape_and_defaults():
    Imu = REG.typed("sensor_msgs/Imu")
    assert REG.typed("sensor_msgs/msg/Imu") is Imu  # cached, either spelling
    assert attrs.has(Imu) and Imu.__msgtype__ == "sensor_msgs/msg/Imu"
    imu = Imu()
    assert imu.orientation_covariance == [0.0] * 9
    assert imu.header.stamp.secs == 0 and imu.header.stamp.to_float() == 0.0
    assert Imu().orientation_covariance is not imu.orientation_covariance  # no shared defaults
    assert REG.typed("sensor_msgs/Image")().data == b""
    assert REG.unstructure(imu) == REG.default("sensor_msgs/Imu")


def test_constants_are_class_attributes():
    Battery = REG.typed("sensor_msgs/BatteryState")
    assert Battery.POWER_SUPPLY_STATUS_FULL == 4
    assert REG.typed("rosgraph_msgs/Log").ERROR == 8


def test_structure_reads_the_wire_shape():
    img = REG.structure({"header": {"stamp": {"secs": 5, "nsecs": 6}}, "data": "AAEC", "width": 3}, "sensor_msgs/Image")
    assert img.data == b"\x00\x01\x02" and img.width == 3 and img.header.stamp.nsecs == 6
    assert REG.unstructure(img)["data"] == "AAEC"
    scan = REG.structure({"ranges": [None, 1.5]}, "sensor_msgs/LaserScan")
    assert math.isnan(scan.ranges[0]) and scan.ranges[1] == 1.5
    # a list of ints and raw bytes work for binary fields too
    assert REG.structure({"data": [1, 2]}, "sensor_msgs/CompressedImage").data == b"\x01\x02"
    assert REG.structure({"data": b"\x07"}, "sensor_msgs/CompressedImage").data == b"\x07"


def test_time_in_either_shape_and_ros2_names():
    ros2 = TypeRegistry.standard(ros2=True)
    h = ros2.structure({"stamp": {"secs": 1, "nsecs": 2}}, "std_msgs/Header")
    assert (h.stamp.sec, h.stamp.nanosec) == (1, 2)
    assert ros2.unstructure(h) == {"stamp": {"sec": 1, "nanosec": 2}, "frame_id": ""}


def test_bad_input():
    with pytest.raises(ValueError, match=r"geometry_msgs/Twist.*linear\.x"):
        REG.structure({"linear": {"x": "abc"}}, "geometry_msgs/Twist")
    with pytest.raises(ValueError, match="expected a dict"):
        REG.structure([1, 2], "geometry_msgs/Twist")
    with pytest.raises(TypeError, match="not a typed message"):
        REG.unstructure(object())


def test_learned_types_and_keyword_field_names():
    reg = TypeRegistry.empty()
    reg.add_typedefs([{"type": "odd_pkg/Odd", "fieldnames": ["from", "class", "n"],
                       "fieldtypes": ["string", "float64", "uint8"], "fieldarraylen": [-1, -1, 4],
                       "examples": ["", "0.0", "[]"], "constnames": ["LIMIT"], "constvalues": ["3"]}])
    Odd = reg.typed("odd_pkg/Odd")
    obj = reg.structure({"from": "a", "class": 2, "n": "AQIDBA=="}, "odd_pkg/Odd")
    assert obj.from_ == "a" and obj.class_ == 2.0 and obj.n == b"\x01\x02\x03\x04"
    assert Odd.LIMIT == 3
    assert reg.unstructure(obj) == {"from": "a", "class": 2.0, "n": "AQIDBA=="}


TYPES = ["sensor_msgs/Imu", "sensor_msgs/Image", "rosgraph_msgs/Log", "visualization_msgs/MarkerArray",
         "sensor_msgs/BatteryState", "rcon_sim/action/NavigateToFix_Feedback"]


@pytest.mark.parametrize("type_name", TYPES)
@settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_structure_unstructure_round_trip(type_name, data):
    msg = data.draw(message(REG, REG.resolve(type_name)))
    obj = REG.structure(msg, type_name)
    assert isinstance(obj, REG.typed(type_name))
    assert REG.unstructure(obj) == msg
