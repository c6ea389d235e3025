"""Time values: ``{secs, nsecs}`` (ROS 1) and ``{sec, nanosec}`` (ROS 2); read either, write either."""

from __future__ import annotations

import math
import time as _time
from typing import Any

__all__ = ["now", "from_float", "read", "to_float", "to_ns", "convert", "is_time"]

_NS = 1_000_000_000


def _keys(ros2: bool) -> tuple[str, str]:
    return ("sec", "nanosec") if ros2 else ("secs", "nsecs")


def from_float(seconds: float, ros2: bool = False) -> dict[str, int]:
    """A time value for ``seconds`` (rounded to the nanosecond, nanoseconds always in 0..1e9-1)."""
    if not math.isfinite(seconds):
        raise ValueError(f"not a finite time: {seconds}")
    total = round(seconds * _NS)
    a, b = _keys(ros2)
    return {a: total // _NS, b: total % _NS}


def now(ros2: bool = False) -> dict[str, int]:
    """The wall-clock time now, in the flavour's shape."""
    total = _time.time_ns()
    a, b = _keys(ros2)
    return {a: total // _NS, b: total % _NS}


def is_time(value: Any) -> bool:
    """True for a dict in either time shape."""
    return isinstance(value, dict) and (
        ("secs" in value and "nsecs" in value) or ("sec" in value and "nanosec" in value)
    )


def read(value: Any) -> tuple[int, int]:
    """``(seconds, nanoseconds)`` from either dict shape, a ``(s, ns)`` pair or a number of seconds."""
    if isinstance(value, dict):
        if "secs" in value or "nsecs" in value:
            return int(value.get("secs", 0) or 0), int(value.get("nsecs", 0) or 0)
        if "sec" in value or "nanosec" in value:
            return int(value.get("sec", 0) or 0), int(value.get("nanosec", 0) or 0)
        raise ValueError(f"not a time value: {value!r} (expected secs/nsecs or sec/nanosec)")
    if isinstance(value, tuple | list) and len(value) == 2:
        return int(value[0]), int(value[1])
    if isinstance(value, int | float) and not isinstance(value, bool):
        total = round(value * _NS)
        return total // _NS, total % _NS
    raise ValueError(f"not a time value: {value!r}")


def to_ns(value: Any) -> int:
    """Integer nanoseconds of a time value in any accepted shape."""
    s, ns = read(value)
    return s * _NS + ns


def to_float(value: Any) -> float:
    """Seconds as a float, from a time value in any accepted shape."""
    s, ns = read(value)
    return s + ns / _NS


def convert(value: Any, ros2: bool) -> dict[str, int]:
    """The same time in the other (or same) flavour's dict shape."""
    s, ns = read(value)
    a, b = _keys(ros2)
    return {a: s, b: ns}
