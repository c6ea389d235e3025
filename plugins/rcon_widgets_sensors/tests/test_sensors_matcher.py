"""Matcher table for the sensor widgets, with the plugin manager loaded from entry points."""

import pytest

from rcon_core.matcher import match
from rcon_core.msgs import TypeRegistry


@pytest.fixture(scope="module")
def types():
    return TypeRegistry.standard()


def ours(found):
    return {m.kind: m for m in found if m.kind.startswith("sensors.")}


# (type, role) -> {kind: expected field path} that must be offered; every other sensors.* kind must not be
TABLE = [
    ("sensor_msgs/Image", "subscribe", {"sensors.image": ""}),
    ("sensor_msgs/msg/Image", "subscribe", {"sensors.image": ""}),
    ("sensor_msgs/CompressedImage", "subscribe", {"sensors.image": ""}),
    ("sensor_msgs/LaserScan", "subscribe", {"sensors.image": ""}),
    ("nav_msgs/OccupancyGrid", "subscribe", {"sensors.image": ""}),
    ("foxglove_msgs/CompressedVideo", "subscribe", {"sensors.image": ""}),
    ("foxglove_msgs/msg/CompressedVideo", "subscribe", {"sensors.image": ""}),
    ("ffmpeg_image_transport_msgs/FFMPEGPacket", "subscribe", {"sensors.image": ""}),
    ("stereo_msgs/DisparityImage", "subscribe", {"sensors.image": "image"}),
    ("sensor_msgs/Image", "publish", {"sensors.camera": ""}),
    ("sensor_msgs/CompressedImage", "publish", {"sensors.camera": ""}),
    ("geometry_msgs/Twist", "publish", {"sensors.teleop": ""}),
    ("geometry_msgs/TwistStamped", "publish", {"sensors.teleop": ""}),
    ("geometry_msgs/Pose2D", "publish", {"sensors.teleop": ""}),
    ("geometry_msgs/Point", "publish", {"sensors.teleop": ""}),
    ("geometry_msgs/Twist", "subscribe", {}),
    ("nav_msgs/Odometry", "publish", {}),  # carries a twist, but is not a command
    # the motion sensors bind the whole message; the model puts the vector in the type's usual field
    ("sensor_msgs/Imu", "publish", {"sensors.accelerometer": "", "sensors.gyroscope": ""}),
    ("sensor_msgs/Imu", "subscribe", {"sensors.accelerometer": "", "sensors.gyroscope": ""}),
    ("sensor_msgs/MagneticField", "publish", {"sensors.magnetometer": ""}),
    ("sensor_msgs/MagneticField", "subscribe", {"sensors.magnetometer": ""}),
    ("geometry_msgs/Vector3Stamped", "publish", {"sensors.accelerometer": "", "sensors.gyroscope": "",
                                                 "sensors.magnetometer": "", "sensors.teleop": ""}),
    ("geometry_msgs/Vector3", "publish", {"sensors.accelerometer": "", "sensors.gyroscope": "",
                                          "sensors.magnetometer": "", "sensors.teleop": ""}),
    ("geometry_msgs/Vector3", "subscribe", {"sensors.accelerometer": "", "sensors.gyroscope": "",
                                            "sensors.magnetometer": ""}),
    ("geometry_msgs/Accel", "subscribe", {}),
    ("sensor_msgs/BatteryState", "subscribe", {}),
    ("std_msgs/Float64", "publish", {}),
    ("std_srvs/SetBool", "call", {}),
    ("sensor_msgs/NavSatFix", "subscribe", {}),
]


@pytest.mark.parametrize("type_name,role,expected", TABLE)
def test_table(plugins, types, type_name, role, expected):
    found = ours(match(type_name, role, types, plugins))
    registered = {s.kind for s in plugins.widgets() if s.kind.startswith("sensors.")}
    expected = {k: v for k, v in expected.items() if k in registered}
    assert set(found) == set(expected), (type_name, role, sorted(found))
    for kind, path in expected.items():
        assert found[kind].field_path == path, (kind, found[kind].field_path)


def test_image_and_teleop_rank_first_for_the_demo_topics(plugins, types):
    assert match("sensor_msgs/Image", "subscribe", types, plugins)[0].kind == "sensors.image"
    assert match("sensor_msgs/CompressedImage", "subscribe", types, plugins)[0].kind == "sensors.image"
    assert match("geometry_msgs/Twist", "publish", types, plugins)[0].kind == "sensors.teleop"


def test_all_kinds_registered(plugins):
    kinds = {s.kind for s in plugins.widgets() if s.package == "rcon-widgets-sensors" or s.kind.startswith("sensors.")}
    assert {"sensors.image", "sensors.teleop", "sensors.accelerometer", "sensors.gyroscope",
            "sensors.magnetometer"} <= kinds
