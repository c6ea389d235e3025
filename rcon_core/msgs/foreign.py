"""Type names from outside ROS: Foxglove's own schemas (``foxglove.CompressedImage``), protobuf full names,
JSON channels, and the ROS type each one has the shape of, so the matcher offers the widgets that fit.

Decision: a foreign type matches as its ROS equivalent
    A Foxglove schema whose fields are those of a ROS message (``foxglove.CompressedImage`` has ``format``
    and ``data`` as ``sensor_msgs/CompressedImage``; ``foxglove.LocationFix`` has ``latitude``,
    ``longitude``, ``altitude`` as ``sensor_msgs/NavSatFix``) is matched as that ROS type
    (:data:`ROS_EQUIVALENT`): the Image widget takes a Foxglove camera, the Map a Foxglove GPS fix.  Any
    other dotted name (a protobuf type, a JSON channel's schema) is *foreign*: it gets the widgets that
    accept any message.  The link delivers such messages with the ROS field names (the Foxglove link adds
    a ``header`` built from ``timestamp`` and ``frame_id``: ``rcon_core/foxglove/codecs.py``).
"""

from __future__ import annotations

import re

#: Foxglove schema -> the ROS message type with the same fields
ROS_EQUIVALENT = {
    "foxglove.CompressedImage": "sensor_msgs/msg/CompressedImage",
    "foxglove.RawImage": "sensor_msgs/msg/Image",
    "foxglove.LocationFix": "sensor_msgs/msg/NavSatFix",
}

_DOTTED = re.compile(r"[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)+\Z")


def is_foreign(name: str) -> bool:
    """A dotted type name (protobuf full name, a Foxglove schema, a JSON channel's ``json.*`` name)."""
    return isinstance(name, str) and "/" not in name and bool(_DOTTED.match(name))


def ros_equivalent(name: str) -> str | None:
    """The ROS type a foreign type matches as, or None."""
    return ROS_EQUIVALENT.get(name)


def json_type_name(schema_name: str) -> str:
    """A JSON channel's type as RCON lists it: its schema name when it is already a type name, else
    ``json.<schema name>`` (the SDK names a JSON schema ``schema-<hash>``)."""
    if is_foreign(schema_name) or "/" in schema_name:
        return schema_name
    safe = re.sub(r"\W", "_", schema_name).strip("_") or "Message"
    if safe[0].isdigit():
        safe = "_" + safe
    return f"json.{safe}"
