"""Reading positions and headings out of messages (dicts as they come off the bridge). Pure Python.

A *geo* (sub)message is anything with numeric ``latitude`` and ``longitude`` (sensor_msgs/NavSatFix,
geographic_msgs/GeoPoint, ...). NavSatFix adds ``status.status`` (-1 = no fix) and
``position_covariance`` (row-major 3x3, ENU, m^2) with ``position_covariance_type`` (0 = unknown).
"""

from __future__ import annotations

import math
from typing import Any

import attrs

STATUS_NO_FIX = -1
COVARIANCE_TYPE_UNKNOWN = 0


class GeoError(ValueError):
    """The message has no usable latitude/longitude; ``str()`` says what is wrong."""


@attrs.frozen
class Fix:
    """One position report. ``lat``/``lon`` are None when the receiver has no fix."""

    lat: float | None
    lon: float | None
    altitude: float | None = None
    status: int | None = None
    accuracy_m: float | None = None

    @property
    def has_fix(self) -> bool:
        return self.lat is not None and self.lon is not None and self.status != STATUS_NO_FIX


def _number(value: Any) -> float | None:
    """A finite float, or None (rosbridge sends NaN as null)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    f = float(value)
    return f if math.isfinite(f) else None


def accuracy_from_covariance(covariance: Any, covariance_type: Any = None) -> float | None:
    """Horizontal 1-sigma radius in metres from a NavSatFix covariance (the larger of east and north)."""
    if covariance_type is not None and covariance_type == COVARIANCE_TYPE_UNKNOWN:
        return None
    if not isinstance(covariance, (list, tuple)) or len(covariance) < 5:
        return None
    east, north = _number(covariance[0]), _number(covariance[4])
    variances = [v for v in (east, north) if v is not None and v > 0]
    return math.sqrt(max(variances)) if variances else None


def fix_from_message(geo: Any) -> Fix:
    """A :class:`Fix` from a geo (sub)message. Raises :class:`GeoError` when it has no lat/lon fields."""
    if not isinstance(geo, dict):
        raise GeoError(f"expected a message with latitude and longitude, got {type(geo).__name__}")
    if "latitude" not in geo or "longitude" not in geo:
        raise GeoError("the message has no latitude/longitude fields (bind the map to a geo field)")
    lat, lon = _number(geo.get("latitude")), _number(geo.get("longitude"))
    if lat is not None and not -90.0 <= lat <= 90.0:
        lat = None
    if lon is not None and not -180.0 <= lon <= 360.0:
        lon = None
    if lon is not None and lon >= 180.0:
        lon -= 360.0
    status = None
    st = geo.get("status")
    if isinstance(st, dict) and isinstance(st.get("status"), int):
        status = int(st["status"])
    return Fix(
        lat=lat,
        lon=lon,
        altitude=_number(geo.get("altitude")),
        status=status,
        accuracy_m=accuracy_from_covariance(geo.get("position_covariance"), geo.get("position_covariance_type")),
    )


def yaw_from_quaternion(q: Any) -> float | None:
    """Yaw (radians, about +z, counter-clockwise from +x) of a geometry_msgs/Quaternion dict; None if unset."""
    if not isinstance(q, dict):
        return None
    x, y, z, w = (_number(q.get(k)) for k in ("x", "y", "z", "w"))
    if None in (x, y, z, w):
        return None
    assert x is not None and y is not None and z is not None and w is not None
    if x * x + y * y + z * z + w * w < 1e-9:
        return None
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def compass_from_enu_yaw(yaw: float) -> float:
    """ENU yaw (0 = east, counter-clockwise) -> compass heading (0 = north, clockwise), degrees [0, 360)."""
    return (90.0 - math.degrees(yaw)) % 360.0


#: where the orientation sits in the message types a heading topic may have
HEADING_PATHS = {
    "sensor_msgs/Imu": ("orientation",),
    "nav_msgs/Odometry": ("pose", "pose", "orientation"),
    "geometry_msgs/PoseStamped": ("pose", "orientation"),
}


def heading_from_message(msg: Any, type_name: str) -> float | None:
    """Compass heading in degrees from an Imu / Odometry / PoseStamped message (ENU yaw), or None."""
    path = HEADING_PATHS.get(type_name)
    if path is None or not isinstance(msg, dict):
        return None
    if type_name == "sensor_msgs/Imu":
        cov = msg.get("orientation_covariance")
        if isinstance(cov, (list, tuple)) and cov and cov[0] == -1:  # "no orientation estimate"
            return None
    node: Any = msg
    for part in path:
        node = node.get(part) if isinstance(node, dict) else None
    yaw = yaw_from_quaternion(node)
    return None if yaw is None else compass_from_enu_yaw(yaw)
