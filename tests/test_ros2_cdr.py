"""cbor-raw on ROS 2 is CDR: the sim sends it (checked against rosbags' own CDR), our client decodes it."""

from __future__ import annotations

import asyncio
import json
import math
from typing import Any

import cbor2
import pytest
import websockets
from rosbags.typesys import Stores, get_typestore

from rcon_core.bridge import BridgeClient
from rcon_core.bridge.cdrdecode import flavour_from_typedefs
from rcon_core.msgs import TypeRegistry
from rcon_core.msgs.cdr import CdrError
from rcon_core.sim import SimServer
from rcon_core.testing import until

STORE = get_typestore(Stores.ROS2_HUMBLE)
REG = TypeRegistry.standard(ros2=True)


def close(a: Any, b: Any, path: str = "") -> list[str]:
    """Differences between two decoded messages (floats within float32 precision)."""
    if isinstance(a, dict):
        return [d for k in a for d in close(a[k], b[k], f"{path}.{k}")] if set(a) == set(b) else [path]
    if isinstance(a, list | tuple):
        return [d for i, (x, y) in enumerate(zip(a, b, strict=True)) for d in close(x, y, f"{path}[{i}]")] \
            if len(a) == len(b) else [path]
    if isinstance(a, float) and b is None:  # JSON carries NaN/inf as null
        return [] if not math.isfinite(a) else [f"{path}: {a} != null"]
    if isinstance(a, float) or isinstance(b, float):
        ok = (math.isnan(a) and math.isnan(b)) or math.isclose(a, b, rel_tol=1e-6, abs_tol=1e-6)
        return [] if ok else [f"{path}: {a} != {b}"]
    if isinstance(b, str) and isinstance(a, bytes | bytearray):
        import base64

        return [] if base64.b64decode(b) == bytes(a) else [path]
    return [] if a == b else [f"{path}: {a!r} != {b!r}"]


async def test_sim_sends_cdr_that_rosbags_reads(sim_ros2: SimServer) -> None:
    async with websockets.connect(sim_ros2.url, max_size=None) as ws:
        for topic in ("/imu/data", "/gps/fix", "/battery"):
            await ws.send(json.dumps({"op": "subscribe", "topic": topic, "compression": "cbor-raw"}))
        frames: dict[str, dict[str, Any]] = {}
        while len(frames) < 3:
            raw = await asyncio.wait_for(ws.recv(), 5)
            assert isinstance(raw, bytes)
            frame = cbor2.loads(raw)
            frames.setdefault(frame["topic"], frame)
    for topic, frame in frames.items():
        assert frame["op"] == "publish" and set(frame["msg"]) == {"secs", "nsecs", "bytes"}
        data = frame["msg"]["bytes"]
        assert data[:4] == b"\x00\x01\x00\x00"  # CDR little endian, not ROS 1
        type_name = sim_ros2.topics[topic].type
        obj = STORE.deserialize_cdr(data, type_name)  # rosbags reads it
        assert bytes(STORE.serialize_cdr(obj, type_name)) == data  # and writes the same bytes
        assert REG.deserialize_cdr(type_name, data)["header"]["frame_id"] == obj.header.frame_id


async def test_multiple_cbor_raw_subscribers_get_the_cdr_string(sim_ros2: SimServer) -> None:
    """The upstream multiple_subscribers_raw conversation: two cbor-raw subscribers, one publish."""
    sub = {"op": "subscribe", "topic": "/a_topic", "type": "std_msgs/String", "compression": "cbor-raw"}
    async with websockets.connect(sim_ros2.url) as a, websockets.connect(sim_ros2.url) as b, \
            websockets.connect(sim_ros2.url) as c:
        for ws in (a, b):
            await ws.send(json.dumps(sub))
            await ws.send(json.dumps({"op": "call_service", "id": "sync", "service": "/rosapi/nodes"}))
            await asyncio.wait_for(ws.recv(), 5)
        await c.send(json.dumps({"op": "advertise", "topic": "/a_topic", "type": "std_msgs/String"}))
        await c.send(json.dumps({"op": "publish", "topic": "/a_topic", "msg": {"data": "hello"}}))
        got = [cbor2.loads(await asyncio.wait_for(ws.recv(), 5)) for ws in (a, b)]
    for frame in got:
        assert frame["topic"] == "/a_topic"
        assert frame["msg"]["bytes"] == b"\x00\x01\x00\x00\x06\x00\x00\x00hello\x00"


@pytest.mark.parametrize("topic", ["/imu/data", "/odom", "/gps/fix", "/scan", "/camera/rear/image_raw/compressed"])
async def test_client_decodes_cdr_like_json(sim_ros2: SimServer, topic: str) -> None:
    client = BridgeClient(sim_ros2.url, call_timeout=5)
    await client.connect(timeout=5)
    try:
        raw: list[dict[str, Any]] = []
        plain: list[dict[str, Any]] = []
        client.node("raw").subscribe(topic, raw.append, compression="cbor-raw")
        other = BridgeClient(sim_ros2.url, call_timeout=5)
        await other.connect(timeout=5)
        try:
            other.node("json").subscribe(topic, plain.append)
            await until(lambda: len(raw) >= 3 and len(plain) >= 3)
        finally:
            await other.close()
    finally:
        await client.close()
    assert raw and plain and client.stats["bad_frames"] == 0
    assert client.ros_version in (None, 2)
    # same stream, same shape: compare the pair with the same stamp
    by_stamp = {json.dumps(m["header"]["stamp"]): m for m in plain}
    pairs = [(m, by_stamp[json.dumps(m["header"]["stamp"])]) for m in raw if json.dumps(m["header"]["stamp"]) in by_stamp]
    assert pairs, "no message arrived both ways"
    assert close(*pairs[0]) == []


def test_cdr_round_trip_and_errors() -> None:
    msg = {"header": {"stamp": {"sec": 5, "nanosec": 7}, "frame_id": "gps"},
           "status": {"status": 0, "service": 1}, "latitude": 43.6, "longitude": -79.4, "altitude": 75.0,
           "position_covariance": [0.0] * 9, "position_covariance_type": 2}
    data = REG.serialize_cdr("sensor_msgs/msg/NavSatFix", msg)
    assert bytes(STORE.serialize_cdr(STORE.deserialize_cdr(data, "sensor_msgs/msg/NavSatFix"),
                                     "sensor_msgs/msg/NavSatFix")) == data
    assert REG.deserialize_cdr("sensor_msgs/msg/NavSatFix", data) == msg
    assert REG.deserialize_cdr("sensor_msgs/msg/NavSatFix", data + b"\x00\x00") == msg  # padding is fine
    assert REG.serialize_cdr("std_msgs/msg/Empty", {}) == b"\x00\x01\x00\x00\x00"
    with pytest.raises(CdrError, match="header"):
        REG.deserialize_cdr("std_msgs/msg/String", b"\x05\x00\x00\x00hello")  # ROS 1 bytes
    with pytest.raises(CdrError, match="ends before"):
        REG.deserialize_cdr("sensor_msgs/msg/NavSatFix", data[:40])
    with pytest.raises(CdrError, match="left over"):
        REG.deserialize_cdr("std_msgs/msg/Bool", b"\x00\x01\x00\x00\x01\x07\x07\x07\x07")


def test_flavour_from_typedefs() -> None:
    ros2 = TypeRegistry.standard(ros2=True).typedefs("sensor_msgs/msg/Imu")
    ros1 = TypeRegistry.standard(ros2=False).typedefs("sensor_msgs/Imu")
    assert flavour_from_typedefs(ros2) == 2 and flavour_from_typedefs(ros1) == 1
    assert flavour_from_typedefs([{"type": "std_msgs/String", "fieldtypes": ["string"]}]) is None


async def test_client_reads_cdr_of_a_type_that_does_not_tell_its_ros(sim_ros2: SimServer) -> None:
    """std_msgs/String's typedefs look the same on ROS 1 and 2: the client sniffs the CDR header rather than
    asking the server, and gets the string (the upstream multiple_subscribers_raw case, with our client)."""
    a, b = BridgeClient(sim_ros2.url, call_timeout=5), BridgeClient(sim_ros2.url, call_timeout=5)
    await a.connect(timeout=5)
    await b.connect(timeout=5)
    try:
        got_a: list[dict[str, Any]] = []
        got_b: list[dict[str, Any]] = []
        a.node("s").subscribe("/a_topic", got_a.append, type="std_msgs/String", compression="cbor-raw")
        b.node("s").subscribe("/a_topic", got_b.append, type="std_msgs/msg/String", compression="cbor-raw")
        await until(lambda: sim_ros2.topic_subscriber_count("/a_topic") == 2)
        pub = a.node("p").advertise("/a_topic", "std_msgs/msg/String")
        pub.publish({"data": "hello"})
        await until(lambda: got_a and got_b)
        assert got_a == got_b == [{"data": "hello"}]
        assert a.stats["bad_frames"] == b.stats["bad_frames"] == 0
        assert a.ros_version is None  # nothing was asked
    finally:
        await a.close()
        await b.close()


@pytest.mark.parametrize(("name", "msg"), [("std_msgs/msg/Float64", {"data": 1.5}), ("std_msgs/msg/Bool", {"data": True}),
                                           ("std_msgs/msg/UInt16", {"data": 513}), ("std_msgs/msg/Int8", {"data": -3}),
                                           ("geometry_msgs/msg/Vector3", {"x": 1.0, "y": -2.0, "z": 3.5})])
def test_the_frame_reader_of_one_scalar_reads_in_place_as_the_general_path_does(name, msg):
    """``frame_reader``'s short way for a message of one plain scalar (the Foxglove link's hot path) gives
    what rosbags' CDR gives, at an offset, from bytes and from a view; any other length or a big-endian
    header takes the general path, with its checks."""
    from rcon_core.msgs.cdr import frame_reader

    wire_type = STORE.types[name]
    data = bytes(STORE.serialize_cdr(wire_type(**msg), name))
    assert data == REG.serialize_cdr(name, msg)
    read = frame_reader(REG.cdr_codec(), REG.resolve(name), 13)
    head = b"\x01" + bytes(12)
    assert read(head + data) == msg
    assert read(memoryview(bytearray(head + data + b"junk"))[:13 + len(data)]) == msg
    assert read(head + data + b"\x00\x00") == msg  # padding after the message: the general path's rule
    big = bytes(STORE.serialize_cdr(wire_type(**msg), name, little_endian=False))
    assert read(head + big) == msg
    with pytest.raises(CdrError):
        read(head + data[:-1] if len(data) > 5 else head + data[:4])
    with pytest.raises(CdrError):
        read(head + data + b"\x01\x02\x03\x04\x05")
