"""Which of a camera's transports to watch: the Image widget's "best the robot offers" (no Qt, no I/O).

A ROS camera is usually published once per transport under one base name (image_transport's convention):
``/cam/image_raw`` (``sensor_msgs/Image``), ``/cam/image_raw/compressed`` (JPEG or PNG
``sensor_msgs/CompressedImage``), ``/cam/image_raw/foxglove`` (``foxglove_msgs/CompressedVideo``),
``/cam/image_raw/ffmpeg`` (``ffmpeg_image_transport_msgs/FFMPEGPacket``). Over a field link video costs a
few kB a frame, JPEG 50-180 kB, raw 1 MB or more, so :func:`pick` ranks video first, then compressed, then
raw, among the ones the robot lists with the expected type. The bound topic itself is always a candidate.
"""

from __future__ import annotations

import attrs

from rcon_core.msgs.names import pkg_type

__all__ = ["Choice", "TRANSPORTS", "camera_base", "pick"]

#: (suffix after the base name, expected type, what the operator reads), best first; "" is the raw image
TRANSPORTS: tuple[tuple[str, str, str], ...] = (
    ("/foxglove", "foxglove_msgs/CompressedVideo", "video"),
    ("/ffmpeg", "ffmpeg_image_transport_msgs/FFMPEGPacket", "video"),
    ("/compressed", "sensor_msgs/CompressedImage", "compressed"),
    ("", "sensor_msgs/Image", "raw"),
)


@attrs.frozen
class Choice:
    """``topic``/``type_name``: what to subscribe to; ``kind``: video, compressed or raw; ``offered``: every
    kind the robot offers for this camera, best first (what the overlay says beside the choice)."""

    topic: str
    type_name: str
    kind: str
    offered: tuple[str, ...]

    def note(self) -> str:
        others = ", ".join(k for k in dict.fromkeys(self.offered))
        return f"via {self.kind}: {self.topic} (offered: {others})"


def camera_base(topic: str) -> str:
    """The camera's base name: ``topic`` without a transport suffix (``/compressed``, ``/foxglove``...)."""
    for suffix, _type, _kind in TRANSPORTS:
        if suffix and topic.endswith(suffix) and len(topic) > len(suffix):
            return topic[: -len(suffix)]
    return topic


def pick(bound_topic: str, bound_type: str, topics: dict[str, str]) -> Choice:
    """The best transport of the bound topic's camera among ``topics`` (name -> type, as rosapi lists them;
    either type spelling). The bound topic when nothing better is listed."""
    base = camera_base(bound_topic)
    found: list[Choice] = []
    for suffix, type_name, kind in TRANSPORTS:
        name = base + suffix
        listed = topics.get(name)
        if name == bound_topic and pkg_type(bound_type) == type_name:
            listed = listed or bound_type
        if listed is not None and pkg_type(listed) == type_name:
            found.append(Choice(name, listed, kind, ()))
    offered = tuple(c.kind for c in found)
    if not found:
        return Choice(bound_topic, bound_type, "as bound", ())
    best = found[0]
    return Choice(best.topic, best.type_name, best.kind, offered)
