"""ROS 1 versus ROS 2 shapes: type spellings, time keys, headers."""

from __future__ import annotations

import time as _time
from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class Flavour:
    """How the simulated robot spells types and times on the wire."""

    ros2: bool = False

    def msg(self, pkg: str, name: str) -> str:
        """The wire spelling of message type ``pkg/name``."""
        return f"{pkg}/msg/{name}" if self.ros2 else f"{pkg}/{name}"

    def srv(self, pkg: str, name: str) -> str:
        """The wire spelling of service type ``pkg/name``."""
        return f"{pkg}/srv/{name}" if self.ros2 else f"{pkg}/{name}"

    def action(self, pkg: str, name: str) -> str:
        return f"{pkg}/action/{name}"

    def time(self, t: float | None = None) -> dict[str, int]:
        """A time value in this flavour's shape (``secs/nsecs`` or ``sec/nanosec``)."""
        if t is None:
            t = _time.time()
        secs = int(t)
        nsecs = int(round((t - secs) * 1e9))
        if nsecs >= 1_000_000_000:
            secs, nsecs = secs + 1, nsecs - 1_000_000_000
        if self.ros2:
            return {"sec": secs, "nanosec": nsecs}
        return {"secs": secs, "nsecs": nsecs}

    def header(self, frame_id: str, t: float | None = None) -> dict[str, Any]:
        """A std_msgs/Header; ROS 1 has ``seq`` (the topic sets it when publishing)."""
        if self.ros2:
            return {"stamp": self.time(t), "frame_id": frame_id}
        return {"seq": 0, "stamp": self.time(t), "frame_id": frame_id}

    def wire(self, name: str, kind: str = "msg") -> str:
        """Convert a type name in either spelling to this flavour's spelling (``kind`` for 2-part names)."""
        parts = name.strip("/").split("/")
        if len(parts) == 3:
            pkg, kind, base = parts
        elif len(parts) == 2:
            pkg, base = parts
        else:
            return name
        if self.ros2:
            return f"{pkg}/{kind}/{base}"
        return f"{pkg}/{base}"
