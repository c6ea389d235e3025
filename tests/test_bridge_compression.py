"""Every compression on every sim topic decodes to the message compression ``none`` gives.

Two clients on one sim: a reference client subscribed to every topic with ``compression: "none"``, and a
client under test subscribed with the compression (and fragment size) of the case.  Messages are paired by
header stamp (every sim topic but ``/lights/state`` has a header; that one is latched and never changes in
the test), then compared leaf by leaf: floats within float32 precision (cbor-raw carries float32 fields as
float32; JSON as the shortest double), NaN equal to the ``None`` JSON gives for it, ``uint8[]`` as bytes
(base64 text in JSON and png, a byte string in CBOR).
"""

from __future__ import annotations

import math
from collections.abc import AsyncIterator
from typing import Any

import pytest
import pytest_asyncio

from rcon_core.bridge import BridgeClient
from rcon_core.msgs.values import as_bytes
from rcon_core.sim import SimServer
from rcon_core.testing import until

pytestmark = pytest.mark.usefixtures("transport")  # every test runs on each transport

TOPICS = {
    "/odom": "nav_msgs/Odometry",
    "/gps/fix": "sensor_msgs/NavSatFix",
    "/imu/data": "sensor_msgs/Imu",
    "/imu/mag": "sensor_msgs/MagneticField",
    "/camera/front/image_raw": "sensor_msgs/Image",
    "/camera/rear/image_raw/compressed": "sensor_msgs/CompressedImage",
    "/scan": "sensor_msgs/LaserScan",
    "/battery": "sensor_msgs/BatteryState",
    "/depth": "sensor_msgs/Range",
    "/map": "nav_msgs/OccupancyGrid",
    "/lights/state": "std_msgs/Bool",
    "/rosout": "rosgraph_msgs/Log",
}

FIXED_ARRAY_TYPES = {"nav_msgs/Odometry", "sensor_msgs/NavSatFix", "sensor_msgs/Imu", "sensor_msgs/MagneticField"}

# (compression, fragment_size): fragment_size makes the sim cut every frame into `fragment` frames, the
# way rosbridge does -- for png that is the png frame's JSON text cut into pieces
CASES = [("png", None), ("png", 4096), ("cbor", None), ("cbor-raw", None), ("none", 1000)]


@pytest_asyncio.fixture
async def sim() -> AsyncIterator[SimServer]:
    server = SimServer(rate_scale=2.0)
    await server.start()
    try:
        yield server
    finally:
        await server.stop()


def differences(a: Any, b: Any, path: str = "") -> list[str]:
    """Where ``a`` (under test) and ``b`` (reference, compression none) differ, NaN/None and bytes aware."""
    if isinstance(a, dict) and isinstance(b, dict):
        if a.keys() != b.keys():
            return [f"{path or '.'}: keys {sorted(a)} != {sorted(b)}"]
        return [d for k in a for d in differences(a[k], b[k], f"{path}.{k}")]
    if isinstance(a, bytes | bytearray) or isinstance(b, bytes | bytearray):
        return [] if as_bytes(a) == as_bytes(b) else [f"{path}: {len(as_bytes(a))} bytes differ"]
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            return [f"{path}: length {len(a)} != {len(b)}"]
        out: list[str] = []
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            out += differences(x, y, f"{path}[{i}]")
            if len(out) > 5:
                break
        return out
    if isinstance(a, float) and (b is None or isinstance(b, float)) and (math.isnan(a) or math.isinf(a)):
        return [] if b is None or a == b or (math.isnan(a) and math.isnan(b)) else [f"{path}: {a} != {b}"]
    if isinstance(a, bool) or isinstance(b, bool) or not isinstance(a, int | float) or not isinstance(b, int | float):
        return [] if a == b and type(a) is type(b) else [f"{path}: {a!r} != {b!r}"]
    return [] if math.isclose(a, b, rel_tol=2e-7, abs_tol=1e-37) else [f"{path}: {a!r} != {b!r}"]


def key(msg: dict[str, Any]) -> Any:
    header = msg.get("header")
    if isinstance(header, dict):
        stamp = header["stamp"]
        return (stamp["secs"], stamp["nsecs"], msg.get("msg"), msg.get("name"))
    return "latched"


@pytest.mark.parametrize(("compression", "fragment_size"), CASES,
                         ids=[f"{c}-frag{f}" if f else c for c, f in CASES])
async def test_every_compression_equals_none_on_every_topic(sim: SimServer, compression: str,
                                                            fragment_size: int | None) -> None:
    ref: dict[str, dict[Any, dict]] = {t: {} for t in TOPICS}
    got: dict[str, dict[Any, dict]] = {t: {} for t in TOPICS}
    reference = BridgeClient(sim.url, call_timeout=5)
    tested = BridgeClient(sim.url, call_timeout=5)
    await reference.connect(timeout=5)
    await tested.connect(timeout=5)
    try:
        for topic in TOPICS:
            reference.node(f"ref{topic}").subscribe(topic, lambda m, t=topic: ref[t].setdefault(key(m), m))
            tested.node(f"test{topic}").subscribe(topic, lambda m, t=topic: got[t].setdefault(key(m), m),
                                                  compression=compression, fragment_size=fragment_size)

        def paired() -> dict[str, list[Any]]:
            return {t: [k for k in got[t] if k in ref[t]] for t in TOPICS}

        try:
            await until(lambda: all(paired().values()), 15, "a message paired on every topic")
        except AssertionError:
            missing = sorted(t for t, keys in paired().items() if not keys)
            pytest.fail(f"no {compression} message paired with a reference one on {missing} "
                        f"(received: { {t: len(got[t]) for t in missing} })")
        for topic, keys in paired().items():
            for k in keys:
                problems = differences(got[topic][k], ref[topic][k])
                assert not problems, f"{topic} [{TOPICS[topic]}] over {compression}: {problems}"
        assert tested.stats["bad_frames"] == 0 and reference.stats["bad_frames"] == 0
        # the sim really sent the case's compression (cbor becomes cbor-raw on fixed-array types only)
        modes = {t: {c.subscriptions[t].compression for c in sim.connections if t in c.subscriptions} for t in TOPICS}
        for topic, used in modes.items():
            expected = {compression}
            if compression == "cbor" and TOPICS[topic] in FIXED_ARRAY_TYPES:
                expected = {"cbor-raw"}
            assert used == {"none"} | expected, f"{topic}: the sim sent {used}"
        if fragment_size:
            assert tested.inbound.fragments.completed > 0  # the frames really came in pieces
    finally:
        await tested.close()
        await reference.close()


def test_the_comparison_catches_differences() -> None:
    """The checker above is strict where it must be and lenient only where the encodings differ."""
    assert differences({"a": [1.0, None, float("inf")], "b": b"\x01\x02"}, {"a": [1.0, None, None], "b": "AQI="}) == []
    assert differences({"x": 0.1 + 1e-6}, {"x": 0.1})  # beyond float32 precision of 0.1
    assert differences({"x": 1.0}, {"x": None})
    assert differences({"x": float("nan")}, {"x": 1.0})
    assert differences({"x": 1}, {"x": True})
    assert differences({"d": b"\x01"}, {"d": "AAI="})
    assert differences({"l": [1, 2]}, {"l": [1, 2, 3]})
    assert differences({"k": 1}, {"j": 1})
    assert differences({"s": "a"}, {"s": "b"})
