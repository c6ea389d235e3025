"""Time and value helpers: either time shape, bytes in three spellings, NaN/inf as None."""

import math
import time as pytime

import numpy as np
import pytest

from rcon_core.msgs import time as rtime
from rcon_core.msgs import values


def test_read_either_shape():
    assert rtime.read({"secs": 3, "nsecs": 5}) == (3, 5)
    assert rtime.read({"sec": 3, "nanosec": 5}) == (3, 5)
    assert rtime.read(2.5) == (2, 500_000_000)
    assert rtime.read((7, 8)) == (7, 8)
    assert rtime.to_float({"secs": 1795259706, "nsecs": 872053623}) == pytest.approx(1795259706.872053623)
    assert rtime.to_ns({"sec": 1, "nanosec": 2}) == 1_000_000_002
    with pytest.raises(ValueError, match="not a time value"):
        rtime.read({"seconds": 1})
    with pytest.raises(ValueError, match="not a time value"):
        rtime.read("noon")


def test_write_either_shape():
    assert rtime.from_float(1.25) == {"secs": 1, "nsecs": 250_000_000}
    assert rtime.from_float(-0.5, ros2=True) == {"sec": -1, "nanosec": 500_000_000}
    assert rtime.convert({"secs": 1, "nsecs": 2}, ros2=True) == {"sec": 1, "nanosec": 2}
    assert rtime.is_time({"sec": 0, "nanosec": 0}) and not rtime.is_time({"x": 1})
    with pytest.raises(ValueError):
        rtime.from_float(math.nan)


def test_now_is_wall_clock():
    before = pytime.time()
    now = rtime.now()
    assert set(now) == {"secs", "nsecs"} and 0 <= now["nsecs"] < 1_000_000_000
    assert abs(rtime.to_float(now) - before) < 60
    assert set(rtime.now(ros2=True)) == {"sec", "nanosec"}


def test_as_bytes():
    assert values.as_bytes("AAH/") == b"\x00\x01\xff"
    assert values.as_bytes(b"\x01") == b"\x01"
    assert values.as_bytes(bytearray(b"\x02")) == b"\x02"
    assert values.as_bytes([0, 1, 255]) == b"\x00\x01\xff"
    assert values.as_bytes(np.array([3, 4], dtype=np.uint8)) == b"\x03\x04"
    assert values.as_bytes(None) == b""
    assert values.as_bytes("") == b""
    with pytest.raises(ValueError, match="not base64"):
        values.as_bytes("%%%")
    with pytest.raises(ValueError, match="0..255"):
        values.as_bytes([256])
    with pytest.raises(ValueError, match="cannot read bytes"):
        values.as_bytes(3.5)
    assert values.to_base64(b"\x00\x01\xff") == "AAH/"


def test_nan_helpers():
    assert values.is_missing_number(None) and values.is_missing_number(math.inf)
    assert not values.is_missing_number(0.0)
    assert math.isnan(values.as_float(None)) and values.as_float(None, 0.0) == 0.0
    assert math.isinf(values.as_float("-Infinity"))
    assert values.floats([1, None, 2.5], default=-1.0) == [1.0, -1.0, 2.5]
    assert values.json_safe_float(math.nan) is None and values.json_safe_float(1.5) == 1.5
