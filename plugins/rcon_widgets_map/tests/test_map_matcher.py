"""Where the matcher offers the GPS map (plugins loaded from their entry points), with the bound path."""

from __future__ import annotations

import pytest

from rcon_core.matcher import Rank, match
from rcon_core.msgs import TypeRegistry


@pytest.fixture(scope="module")
def types():
    reg = TypeRegistry.standard()
    reg.add_msg_text("geographic_msgs/GeoPoint", "float64 latitude\nfloat64 longitude\nfloat64 altitude\n")
    reg.add_msg_text("lab_msgs/BoatState", "string name\ngeographic_msgs/GeoPoint position\nfloat64 speed\n")
    reg.add_msg_text("lab_msgs/Waypoints", "geographic_msgs/GeoPoint[] points\n")  # arrays: not a single fix
    reg.add_msg_text("lab_msgs/LatOnly", "float64 latitude\nstring longitude\n")  # not numeric: not geo
    return reg


# type, role, expected (rank, field path) of map.gps or None when it must not be offered
TABLE = [
    ("sensor_msgs/NavSatFix", "subscribe", (Rank.EXACT, "")),
    ("sensor_msgs/msg/NavSatFix", "publish", (Rank.EXACT, "")),
    ("geographic_msgs/GeoPoint", "subscribe", (Rank.STRUCTURAL, "")),
    ("lab_msgs/BoatState", "subscribe", (Rank.STRUCTURAL, "position")),
    ("lab_msgs/BoatState", "publish", (Rank.STRUCTURAL, "position")),
    ("lab_msgs/Waypoints", "subscribe", None),
    ("lab_msgs/LatOnly", "subscribe", None),
    ("std_msgs/Float64", "subscribe", None),
    ("std_msgs/Float64", "publish", None),
    ("sensor_msgs/Image", "subscribe", None),
    ("sensor_msgs/Imu", "subscribe", None),
    ("nav_msgs/Odometry", "subscribe", None),
    ("sensor_msgs/NavSatStatus", "subscribe", None),
    ("sensor_msgs/NavSatFix", "call", None),  # topics only
    ("std_srvs/SetBool", "call", None),
]


@pytest.mark.parametrize(("type_name", "role", "expected"), TABLE)
def test_map_offered_where_it_fits(plugins, types, type_name, role, expected):
    found = {m.kind: m for m in match(type_name, role, types, plugins)}
    if expected is None:
        assert "map.gps" not in found
        return
    m = found["map.gps"]
    assert (m.rank, m.field_path) == expected


def test_map_is_first_for_navsatfix(plugins, types):
    for role in ("subscribe", "publish"):
        assert match("sensor_msgs/NavSatFix", role, types, plugins)[0].kind == "map.gps"
