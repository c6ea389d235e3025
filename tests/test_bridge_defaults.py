"""Default messages built from rosapi typedefs agree with the type registry's defaults, in both flavours."""

from __future__ import annotations

import pytest

from rcon_core.bridge.defaults import default_from_typedefs
from rcon_core.msgs import TypeRegistry

pytestmark = pytest.mark.usefixtures("transport")  # every test runs on each transport

TYPES = ["sensor_msgs/msg/Imu", "sensor_msgs/msg/Image", "sensor_msgs/msg/CameraInfo", "nav_msgs/msg/OccupancyGrid",
         "nav_msgs/msg/Odometry", "sensor_msgs/msg/NavSatFix", "std_msgs/msg/Empty", "diagnostic_msgs/msg/DiagnosticArray"]


@pytest.mark.parametrize("ros2", [False, True])
@pytest.mark.parametrize("name", TYPES)
def test_typedef_default_equals_the_registry_default(name: str, ros2: bool) -> None:
    reg = TypeRegistry.standard(ros2=ros2)
    default, strings = default_from_typedefs(reg.typedefs(name))
    assert default == reg.default(name)
    assert strings == {f.name for f in reg.fields(name) if f.base == "string" and f.array_len is None}


@pytest.mark.parametrize("ros2", [False, True])
def test_service_response_default_and_its_message_field(ros2: bool) -> None:
    reg = TypeRegistry.standard(ros2=ros2)
    assert default_from_typedefs(reg.service_typedefs("std_srvs/Trigger", "response")) == (
        {"success": False, "message": ""}, {"message"})
    assert default_from_typedefs(reg.service_typedefs("std_srvs/Empty", "response")) == ({}, set())


def test_odd_typedefs_give_what_is_known() -> None:
    assert default_from_typedefs([]) == ({}, set())
    assert default_from_typedefs(["junk"]) == ({}, set())  # type: ignore[list-item]
    td = {"type": "a/B", "fieldnames": ["x", "nested", 5, "blob", "fixed"],
          "fieldtypes": ["float64", "a/Missing", "int32", "uint8", "char"], "fieldarraylen": [-1, -1, -1, 0, 3]}
    assert default_from_typedefs([td]) == ({"x": 0.0, "nested": {}, "blob": "", "fixed": "AAAA"}, set())
