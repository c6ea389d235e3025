"""The sim's rosbridge server, exercised with raw ``websockets`` clients over loopback."""

from __future__ import annotations

import asyncio
import base64
import json
import math
import zlib
from typing import Any

import cbor2
import pytest
import websockets

from rcon_core.msgs import TypeRegistry
from rcon_core.sim import SimServer
from rcon_core.sim.auth import make_mac
from rcon_core.testing import until


async def recv_until(ws: Any, pred: Any, timeout: float = 5.0, binary: bool = False) -> Any:
    """The first frame that fits ``pred`` (text frames parsed as JSON; binary frames as bytes)."""

    async def loop() -> Any:
        while True:
            raw = await ws.recv()
            if isinstance(raw, bytes):
                if binary and pred(raw):
                    return raw
                continue
            if binary:
                continue
            msg = json.loads(raw)
            if pred(msg):
                return msg

    return await asyncio.wait_for(loop(), timeout)


async def collect(ws: Any, seconds: float) -> list[Any]:
    """Every frame received within ``seconds`` (text parsed)."""
    out: list[Any] = []
    loop = asyncio.get_running_loop()
    end = loop.time() + seconds
    while (left := end - loop.time()) > 0:
        try:
            raw = await asyncio.wait_for(ws.recv(), left)
        except TimeoutError:
            break
        out.append(raw if isinstance(raw, bytes) else json.loads(raw))
    return out


async def call(ws: Any, service: str, args: Any = None, call_id: Any = "c1", **extra: Any) -> dict[str, Any]:
    frame: dict[str, Any] = {"op": "call_service", "id": call_id, "service": service, **extra}
    if args is not None:
        frame["args"] = args
    await ws.send(json.dumps(frame))
    return await recv_until(ws, lambda m: m.get("op") == "service_response" and m.get("id") == call_id)


async def synced(ws: Any, tag: str = "sync") -> list[Any]:
    """A round trip on ``ws`` (``/rosapi/get_time``): the sim has handled every frame sent on it before, and
    every frame it sent before the answer has been read. Returns those frames (text parsed), answer last."""
    await ws.send(json.dumps({"op": "call_service", "id": tag, "service": "/rosapi/get_time"}))
    frames: list[Any] = []

    def answered(m: Any) -> bool:
        frames.append(m)
        return m.get("op") == "service_response" and m.get("id") == tag

    await recv_until(ws, answered, timeout=10.0)
    return frames


async def robot_ticks(sim: SimServer, topic: str, n: int) -> None:
    """Wait until the simulated robot has published ``topic`` ``n`` more times."""
    start = sim.robot_published().get(topic, 0)
    await until(lambda: sim.robot_published().get(topic, 0) >= start + n, what=f"{n} more {topic} messages")


def publishes(frames: list[Any], topic: str) -> list[dict[str, Any]]:
    return [f for f in frames if isinstance(f, dict) and f.get("op") == "publish" and f.get("topic") == topic]


def connect(sim: SimServer) -> Any:
    # an unbounded client-side queue: a test that stops reading must not stall its own close handshake
    return websockets.connect(sim.url, max_size=None, max_queue=None)


# -- discovery and robot ------------------------------------------------------------------------------


async def test_topics_lists_the_robot(sim: SimServer) -> None:
    async with connect(sim) as ws:
        reply = await call(ws, "/rosapi/topics", {})
    assert reply["result"] is True
    topics = dict(zip(reply["values"]["topics"], reply["values"]["types"], strict=True))
    assert topics["/odom"] == "nav_msgs/Odometry"
    assert topics["/gps/fix"] == "sensor_msgs/NavSatFix"
    assert topics["/camera/front/image_raw"] == "sensor_msgs/Image"
    assert topics["/camera/rear/image_raw/compressed"] == "sensor_msgs/CompressedImage"
    assert topics["/rosout"] == "rosgraph_msgs/Log"
    assert topics["/cmd_vel"] == "geometry_msgs/Twist"


async def test_every_robot_topic_carries_valid_messages(sim: SimServer) -> None:
    reg = TypeRegistry.standard(ros2=False)
    wanted = ["/odom", "/gps/fix", "/imu/data", "/imu/mag", "/camera/front/image_raw",
              "/camera/rear/image_raw/compressed", "/scan", "/battery", "/depth", "/map", "/lights/state",
              "/rosout"]
    async with connect(sim) as ws:
        reply = await call(ws, "/rosapi/topics", {})
        types = dict(zip(reply["values"]["topics"], reply["values"]["types"], strict=True))
        for topic in wanted:
            await ws.send(json.dumps({"op": "subscribe", "id": f"s-{topic}", "topic": topic}))
        seen: dict[str, dict[str, Any]] = {}

        def fits(m: dict[str, Any]) -> bool:
            if m.get("op") == "publish":
                seen.setdefault(m["topic"], m["msg"])
            return set(wanted) <= set(seen)

        await recv_until(ws, fits, timeout=10)
    for topic in wanted:
        assert reg.validate(types[topic], seen[topic]) == [], topic
    assert seen["/camera/front/image_raw"]["encoding"] == "rgb8"
    image = base64.b64decode(seen["/camera/front/image_raw"]["data"])
    assert len(image) == 640 * 480 * 3
    jpeg = base64.b64decode(seen["/camera/rear/image_raw/compressed"]["data"])
    assert jpeg[:2] == b"\xff\xd8" and seen["/camera/rear/image_raw/compressed"]["format"] == "jpeg"
    fix = seen["/gps/fix"]
    assert abs(fix["latitude"] - 43.6385) < 0.01 and abs(fix["longitude"] + 79.379) < 0.01
    assert fix["position_covariance"][0] > 0 and fix["position_covariance_type"] == 2
    scan = seen["/scan"]
    assert len(scan["ranges"]) == 360 and None in scan["ranges"]  # out of range: +inf -> null
    assert any(r is not None and r < scan["range_max"] for r in scan["ranges"])
    assert seen["/odom"]["header"]["stamp"].keys() == {"secs", "nsecs"}


async def test_cmd_vel_moves_the_vessel_then_watchdog_stops_it(sim: SimServer) -> None:
    async with connect(sim) as ws:
        await ws.send(json.dumps({"op": "subscribe", "topic": "/rosout"}))
        await ws.send(json.dumps({"op": "subscribe", "topic": "/odom", "type": "nav_msgs/Odometry"}))
        for _ in range(5):
            await ws.send(json.dumps({"op": "publish", "topic": "/cmd_vel",
                                      "msg": {"linear": {"x": 1.0}, "angular": {"z": 0.0}}}))
            await asyncio.sleep(0.1)
        moving = await recv_until(ws, lambda m: m.get("topic") == "/odom"
                                  and m["msg"]["twist"]["twist"]["linear"]["x"] > 0.1)
        peak = moving["msg"]["twist"]["twist"]["linear"]["x"]
        log = await recv_until(ws, lambda m: m.get("topic") == "/rosout" and "watchdog" in m["msg"]["msg"])
        assert log["msg"]["name"] == "/kingfisher" and log["msg"]["level"] == 4
        slowing = await recv_until(ws, lambda m: m.get("topic") == "/odom"
                                   and m["msg"]["twist"]["twist"]["linear"]["x"] < peak * 0.8)
        assert slowing["msg"]["pose"]["pose"]["position"]["x"] > 0.0
    assert sim.robot.watchdog_tripped and sim.robot.cmd_surge == 0.0


async def test_speed_limit_clamps_the_command(sim: SimServer) -> None:
    async with connect(sim) as ws:
        await ws.send(json.dumps({"op": "publish", "topic": "/speed_limit", "msg": {"data": 0.3}}))
        await ws.send(json.dumps({"op": "publish", "topic": "/cmd_vel", "msg": {"linear": {"x": 2.0}}}))
        await sim.wait_for_published("/cmd_vel")
    assert sim.robot.speed_limit == pytest.approx(0.3)
    assert sim.robot.cmd_surge == pytest.approx(0.3)


# -- services -----------------------------------------------------------------------------------------


async def test_service_on_unknown_name_fails_with_text(sim: SimServer) -> None:
    async with connect(sim) as ws:
        reply = await call(ws, "/no/such/service", {})
    assert reply == {"op": "service_response", "service": "/no/such/service",
                     "values": "Service /no/such/service does not exist", "result": False, "id": "c1"}
    assert list(reply) == ["op", "service", "values", "result", "id"]


@pytest.mark.parametrize("args", [{"data": True}, [True], [True, 5]])
async def test_lights_service_args_object_or_array(sim: SimServer, args: Any) -> None:
    async with connect(sim) as ws:
        await ws.send(json.dumps({"op": "subscribe", "topic": "/lights/state"}))
        latched = await recv_until(ws, lambda m: m.get("topic") == "/lights/state")
        assert latched["msg"] == {"data": False}
        await ws.send(json.dumps({"op": "call_service", "id": "l1", "service": "/lights/set", "args": args}))
        state = await recv_until(ws, lambda m: m.get("topic") == "/lights/state")
        assert state["msg"] == {"data": True}
        reply = await recv_until(ws, lambda m: m.get("id") == "l1")
        assert reply["result"] is True and reply["values"] == {"success": True, "message": "lights on"}
    assert sim.robot.lights is True


@pytest.mark.parametrize("extra", [{}, {"args": None}])
async def test_missing_or_null_args_mean_defaults(sim: SimServer, extra: dict[str, Any]) -> None:
    sim.robot.lights = True
    async with connect(sim) as ws:
        await ws.send(json.dumps({"op": "call_service", "id": "x", "service": "/lights/set", **extra}))
        reply = await recv_until(ws, lambda m: m.get("id") == "x")
    assert reply["values"] == {"success": True, "message": "lights off"}
    assert sim.robot.lights is False


async def test_service_argument_errors_match_rosbridge(sim: SimServer) -> None:
    async with connect(sim) as ws:
        bad_type = await call(ws, "/lights/set", {"data": "yes"}, "a")
        bad_field = await call(ws, "/lights/set", {"data": True, "force": 1}, "b")
        rosapi_type = await call(ws, "/rosapi/topic_type", {"topic": 42}, "c")
    assert bad_type["result"] is False
    assert bad_type["values"] == ("std_srvs/SetBoolRequest message requires a bool for field data, "
                                  "but got a <class 'str'>")
    assert bad_field["values"] == "Message type std_srvs/SetBoolRequest does not have a field force"
    assert rosapi_type["values"] == ("rosapi/TopicTypeRequest message requires a string for field topic, "
                                     "but got a <class 'int'>")


async def test_reply_ids_none_numeric_and_legacy(sim: SimServer) -> None:
    async with connect(sim) as ws:
        await ws.send(json.dumps({"op": "call_service", "service": "/rosapi/get_time"}))
        no_id = await recv_until(ws, lambda m: m.get("op") == "service_response")
        numeric = await call(ws, "/rosapi/get_time", {}, 12345)
        await ws.send(json.dumps({"op": "call_service", "service": "/rosapi/get_time#legacy-7", "args": {}}))
        legacy = await recv_until(ws, lambda m: m.get("id") == "legacy-7")
        timeout = await call(ws, "/rosapi/get_time", {}, "t", timeout=1.0)
    assert "id" not in no_id and no_id["result"] is True
    assert numeric["id"] == 12345
    assert legacy["service"] == "/rosapi/get_time#legacy-7" and legacy["result"] is True
    assert timeout["result"] is True and set(timeout["values"]["time"]) == {"secs", "nsecs"}


async def test_dock_and_reset_pose(sim: SimServer) -> None:
    sim.robot.x, sim.robot.y = 20.0, 5.0
    async with connect(sim) as ws:
        dock = await call(ws, "/dock", {}, "d")
        assert dock["result"] is True and dock["values"]["success"] is True
        assert "docking started" in dock["values"]["message"]
        assert sim.robot.docking
        reset = await call(ws, "/reset_pose", {}, "r")
    assert reset == {"op": "service_response", "service": "/reset_pose", "values": {}, "result": True, "id": "r"}
    assert (sim.robot.x, sim.robot.y) == (0.0, 0.0)


# -- several clients ----------------------------------------------------------------------------------


async def test_client_topic_reaches_other_clients_and_rosapi(sim: SimServer) -> None:
    async with connect(sim) as a, connect(sim) as b:
        await a.send(json.dumps({"op": "advertise", "topic": "/operator/note", "type": "std_msgs/String"}))
        await synced(a)
        await b.send(json.dumps({"op": "subscribe", "topic": "/operator/note"}))
        topics = await call(b, "/rosapi/topics", {})
        assert "/operator/note" in topics["values"]["topics"]
        publishers = await call(b, "/rosapi/publishers", {"topic": "/operator/note"}, "p")
        assert publishers["values"] == {"publishers": ["/rosbridge_websocket"]}
        await a.send(json.dumps({"op": "publish", "topic": "/operator/note", "msg": {"data": "héllo /x"}}))
        got = await recv_until(b, lambda m: m.get("topic") == "/operator/note")
        assert got == {"op": "publish", "topic": "/operator/note", "msg": {"data": "héllo /x"}}
        assert await sim.wait_for_published("/operator/note") == {"data": "héllo /x"}
        assert sim.topic_subscriber_count("/operator/note") == 1
        await a.send(json.dumps({"op": "unadvertise", "topic": "/operator/note"}))
        await b.send(json.dumps({"op": "unsubscribe", "topic": "/operator/note"}))
        await synced(a)
        topics = await call(b, "/rosapi/topics", {}, "t2")
        assert "/operator/note" not in topics["values"]["topics"]
        assert sim.topic_subscriber_count("/operator/note") == 0


async def test_client_publish_conversion(sim: SimServer) -> None:
    async with connect(sim) as a, connect(sim) as b:
        await a.send(json.dumps({"op": "advertise", "topic": "/op/twist", "type": "geometry_msgs/Twist"}))
        await b.send(json.dumps({"op": "subscribe", "topic": "/op/twist"}))
        await synced(b)
        await a.send(json.dumps({"op": "publish", "topic": "/op/twist", "msg": {"linear": {"x": "fast"}}}))
        await a.send(json.dumps({"op": "publish", "topic": "/op/twist", "msg": {"linear": {"x": 1}, "bogus": 1}}))
        await a.send(json.dumps({"op": "publish", "topic": "/op/twist", "msg": {"linear": {"x": 1}}}))
        got = await recv_until(b, lambda m: m.get("topic") == "/op/twist")
    # the two bad messages were dropped; ints became floats; missing fields defaulted
    assert got["msg"] == {"linear": {"x": 1.0, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.0}}
    assert sim.published("/op/twist") == [got["msg"]]


async def test_client_latched_topic_and_header_stamp(sim: SimServer) -> None:
    async with connect(sim) as a:
        await a.send(json.dumps({"op": "advertise", "topic": "/op/goal", "type": "geometry_msgs/PoseStamped",
                                 "latch": True}))
        await a.send(json.dumps({"op": "publish", "topic": "/op/goal", "latch": True,
                                 "msg": {"header": {"frame_id": "map", "seq": 99}}}))
        await sim.wait_for_published("/op/goal")
        async with connect(sim) as late:
            await late.send(json.dumps({"op": "subscribe", "topic": "/op/goal"}))
            got = await recv_until(late, lambda m: m.get("topic") == "/op/goal")
    header = got["msg"]["header"]
    assert header["frame_id"] == "map" and header["stamp"]["secs"] > 1_600_000_000  # stamped by the server
    assert header["seq"] != 99


async def test_client_provided_service_is_routed(sim: SimServer) -> None:
    async with connect(sim) as provider, connect(sim) as caller:
        await provider.send(json.dumps({"op": "advertise_service", "service": "/op/confirm",
                                        "type": "std_srvs/SetBool"}))
        await synced(provider)
        listed = await call(caller, "/rosapi/service_type", {"service": "/op/confirm"}, "st")
        assert listed["values"] == {"type": "std_srvs/SetBool"}
        await caller.send(json.dumps({"op": "call_service", "id": "q1", "service": "/op/confirm",
                                      "args": {"data": True}}))
        request = await recv_until(provider, lambda m: m.get("op") == "call_service")
        assert request == {"op": "call_service", "id": "service_request:/op/confirm:1", "service": "/op/confirm",
                           "args": {"data": True}}
        await provider.send(json.dumps({"op": "service_response", "id": request["id"], "service": "/op/confirm",
                                        "values": {"success": True, "message": "ok"}, "result": True}))
        reply = await recv_until(caller, lambda m: m.get("id") == "q1")
        assert reply["result"] is True and reply["values"] == {"success": True, "message": "ok"}
        # a pending call is aborted when the provider unadvertises
        await caller.send(json.dumps({"op": "call_service", "id": "q2", "service": "/op/confirm", "args": [False]}))
        request = await recv_until(provider, lambda m: m.get("op") == "call_service")
        assert request["id"] == "service_request:/op/confirm:2"
        await provider.send(json.dumps({"op": "service_response", "id": request["id"], "service": "/op/confirm",
                                        "values": "not an object", "result": False}))  # rejected, call waits
        await provider.send(json.dumps({"op": "unadvertise_service", "service": "/op/confirm"}))
        aborted = await recv_until(caller, lambda m: m.get("id") == "q2")
        assert aborted["result"] is False and "service handler returned None" in aborted["values"]
        gone = await call(caller, "/op/confirm", {}, "q3")
        assert gone["values"] == "Service /op/confirm does not exist"


async def test_disconnect_cleans_up_client_state(sim: SimServer) -> None:
    async with connect(sim) as a:
        await a.send(json.dumps({"op": "subscribe", "topic": "/odom"}))
        await a.send(json.dumps({"op": "advertise_service", "service": "/op/x", "type": "std_srvs/Trigger"}))
        await recv_until(a, lambda m: m.get("topic") == "/odom")
        assert sim.topic_subscriber_count("/odom") == 1
    await until(lambda: sim.topic_subscriber_count("/odom") == 0 and "/op/x" not in sim.services,
                what="the closed connection's subscription and service gone")


async def test_client_count_follows_connections(sim: SimServer) -> None:
    async with connect(sim) as a:
        await a.send(json.dumps({"op": "subscribe", "topic": "/client_count"}))
        first = await recv_until(a, lambda m: m.get("topic") == "/client_count")
        assert first["msg"] == {"data": 1}
        async with connect(sim):
            more = await recv_until(a, lambda m: m.get("topic") == "/client_count")
            assert more["msg"] == {"data": 2}
        fewer = await recv_until(a, lambda m: m.get("topic") == "/client_count")
        assert fewer["msg"] == {"data": 1}


# -- subscription options -----------------------------------------------------------------------------


async def test_throttle_drops_and_lowest_rate_wins(sim: SimServer) -> None:
    async with connect(sim) as ws:
        await ws.send(json.dumps({"op": "subscribe", "id": "slow", "topic": "/imu/data", "throttle_rate": 400}))
        throttled = publishes(await collect(ws, 1.0), "/imu/data")
        await ws.send(json.dumps({"op": "subscribe", "id": "fast", "topic": "/imu/data", "throttle_rate": 0}))
        fast = publishes(await collect(ws, 0.6), "/imu/data")
    # 200 Hz (rate_scale 2): throttled to about 3 frames per second, the first at once
    assert 1 <= len(throttled) <= 5
    assert len(fast) > 20
    seqs = [m["msg"]["header"]["seq"] for m in throttled]
    assert all(b - a > 20 for a, b in zip(seqs, seqs[1:], strict=False))  # dropped, not delayed


async def test_unsubscribe_one_id_keeps_the_stream(sim: SimServer) -> None:
    async with connect(sim) as ws, connect(sim) as witness:
        # another client keeps /odom published throughout (the robot publishes only what someone reads)
        await witness.send(json.dumps({"op": "subscribe", "topic": "/odom"}))
        await synced(witness)
        for sub_id in ("a", "b"):
            await ws.send(json.dumps({"op": "subscribe", "id": sub_id, "topic": "/odom"}))
        await synced(ws, "subscribed")
        await robot_ticks(sim, "/odom", 6)
        frames = publishes(await synced(ws, "s1"), "/odom")
        seqs = [f["msg"]["header"]["seq"] for f in frames]
        assert len(seqs) == len(set(seqs)) > 3  # one frame per message, whatever the number of ids
        await ws.send(json.dumps({"op": "unsubscribe", "id": "a", "topic": "/odom"}))
        await ws.send(json.dumps({"op": "unsubscribe", "id": "nope", "topic": "/odom"}))
        await synced(ws, "s2")  # both handled
        await robot_ticks(sim, "/odom", 3)
        assert publishes(await synced(ws, "s3"), "/odom")  # "b" keeps the stream
        await ws.send(json.dumps({"op": "unsubscribe", "topic": "/odom"}))
        await synced(ws, "s4")  # handled: what was sent before it is read and dropped here
        await robot_ticks(sim, "/odom", 3)  # the robot goes on publishing (for the witness)...
        assert publishes(await synced(ws, "s5"), "/odom") == []  # ...and none of it reaches this client


async def test_subscribe_before_topic_exists_with_type(sim: SimServer) -> None:
    async with connect(sim) as sub, connect(sim) as pub:
        await sub.send(json.dumps({"op": "subscribe", "topic": "/later", "type": "std_msgs/Int32"}))
        await sub.send(json.dumps({"op": "subscribe", "topic": "/untyped/unknown"}))  # silently fails
        await synced(sub)
        await pub.send(json.dumps({"op": "publish", "topic": "/later", "msg": {"data": 5}}))
        got = await recv_until(sub, lambda m: m.get("topic") == "/later")
    assert got["msg"] == {"data": 5}
    assert sim.topic_subscriber_count("/untyped/unknown") == 0


async def test_fragment_size_applies_to_the_connection(sim: SimServer) -> None:
    async with connect(sim) as ws:
        await ws.send(json.dumps({"op": "subscribe", "topic": "/odom", "fragment_size": 100}))
        frags = []
        while True:
            frame = await recv_until(ws, lambda m: m.get("op") == "fragment")
            if frame["num"] == 0:
                frags = []
            frags.append(frame)
            if frame["num"] == math.floor(frame["total"]) - 1 and len(frags) == frame["num"] + 1:
                break
        assert list(frags[0]) == ["op", "id", "data", "num", "total"]
        assert all(f["id"] == 0 and isinstance(f["total"], float) for f in frags)
        assert all(len(f["data"]) <= 100 for f in frags)
        joined = json.loads("".join(f["data"] for f in frags))
        assert joined["op"] == "publish" and joined["topic"] == "/odom"
        await ws.send(json.dumps({"op": "unsubscribe", "topic": "/odom"}))
        await ws.send(json.dumps({"op": "subscribe", "topic": "/battery"}))  # no fragment_size: still fragmented
        frame = await recv_until(ws, lambda m: m.get("op") == "fragment" and '"/battery"' in m["data"], timeout=5)
        assert frame["num"] == 0


async def test_png_compression(sim: SimServer) -> None:
    async with connect(sim) as ws:
        await ws.send(json.dumps({"op": "subscribe", "topic": "/depth", "compression": "png"}))
        frame = await recv_until(ws, lambda m: m.get("op") == "png")
    assert list(frame) == ["op", "data"]
    png = base64.b64decode(frame["data"])
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    width, height = int.from_bytes(png[16:20], "big"), int.from_bytes(png[20:24], "big")
    idat = png.index(b"IDAT")
    size = int.from_bytes(png[idat - 4:idat], "big")
    raw = zlib.decompress(png[idat + 4:idat + 4 + size])
    rows = [raw[r * (width * 3 + 1) + 1:(r + 1) * (width * 3 + 1)] for r in range(height)]
    text = b"".join(rows).rstrip(b"\n").decode()
    msg = json.loads(text)
    assert msg["op"] == "publish" and msg["topic"] == "/depth" and msg["msg"]["radiation_type"] == 0
    assert width == math.floor(math.sqrt(len(text) / 3))


async def test_cbor_compression_typed_arrays(sim: SimServer) -> None:
    async with connect(sim) as ws:
        for topic in ("/scan", "/odom", "/camera/rear/image_raw/compressed", "/map"):
            await ws.send(json.dumps({"op": "subscribe", "topic": topic, "compression": "cbor"}))
        seen: dict[str, Any] = {}

        def fits(raw: bytes) -> bool:
            msg = cbor2.loads(raw)
            seen.setdefault(msg["topic"], msg)
            return len(seen) == 4

        await recv_until(ws, fits, timeout=10, binary=True)
    scan = seen["/scan"]["msg"]
    assert isinstance(scan["ranges"], cbor2.CBORTag) and scan["ranges"].tag == 85  # float32 little endian
    ranges = memoryview(scan["ranges"].value).cast("f").tolist()
    assert len(ranges) == 360 and any(math.isinf(r) for r in ranges)  # inf stays inf in CBOR
    odom = seen["/odom"]["msg"]
    assert odom["pose"]["covariance"].tag == 86 and len(odom["pose"]["covariance"].value) == 36 * 8
    assert isinstance(seen["/camera/rear/image_raw/compressed"]["msg"]["data"], bytes)
    assert seen["/map"]["msg"]["data"].tag == 72  # int8
    assert list(seen["/scan"]) == ["op", "topic", "msg"]


async def test_cbor_raw_is_ros1_serialized(sim: SimServer) -> None:
    reg = TypeRegistry.standard(ros2=False)
    async with connect(sim) as ws:
        await ws.send(json.dumps({"op": "subscribe", "topic": "/imu/data", "compression": "cbor-raw"}))
        raw = await recv_until(ws, lambda b: True, binary=True)
    frame = cbor2.loads(raw)
    assert frame["op"] == "publish" and set(frame["msg"]) == {"secs", "nsecs", "bytes"}
    imu = reg.deserialize_ros1("sensor_msgs/Imu", frame["msg"]["bytes"])
    assert imu["header"]["frame_id"] == "imu_link"
    assert abs(imu["linear_acceleration"]["z"] - 9.8) < 1.0
    assert abs(frame["msg"]["secs"] - imu["header"]["stamp"]["secs"]) <= 1


async def test_stalled_client_does_not_stall_others(sim: SimServer) -> None:
    stalled = await websockets.connect(sim.url, max_size=None, max_queue=1)
    try:
        await stalled.send(json.dumps({"op": "subscribe", "topic": "/camera/front/image_raw", "queue_length": 2}))
        await stalled.send(json.dumps({"op": "subscribe", "topic": "/imu/data"}))
        await asyncio.sleep(0.3)
        stalled.transport.pause_reading()  # stop reading altogether: TCP fills up
        await asyncio.sleep(1.5)
        async with connect(sim) as ws:
            await ws.send(json.dumps({"op": "subscribe", "topic": "/odom"}))
            frames = publishes(await collect(ws, 1.0), "/odom")
        conn = next(c for c in sim.connections if c.subscriptions.get("/camera/front/image_raw"))
        assert len(frames) >= 15  # 40 Hz odom still flows to the healthy client
        assert conn.dropped > 0 and conn.queued <= conn.max_frames
    finally:
        stalled.transport.abort()


# -- bad input ----------------------------------------------------------------------------------------


async def test_bad_frames_get_no_reply_and_keep_the_connection(sim: SimServer) -> None:
    bad: list[str | bytes] = [
        "this is not json", '{"op": "call_service", "id": "trunc"', '{"id": "noop"}', '{"receiver": "/x"}',
        '{"op": "frobnicate"}', '{"op": 5}', '{"op": "subscribe"}', '{"op": "subscribe", "topic": 42}',
        '{"op": "call_service", "id": "n", "service": 42}', "[1, 2, 3]", "", b"\xff\x00garbage",
        '{"op": "publish", "topic": "/never/advertised", "msg": {}}',
        '{"op": "advertise", "topic": "/x", "type": "no_pkg/Nothing"}',
        '{"op": "subscribe", "topic": "/odom", "type": "std_msgs/Int32"}',
        '{"op": "unadvertise_service", "service": "/never"}',
    ]
    async with connect(sim) as ws, connect(sim) as other:
        await other.send(json.dumps({"op": "subscribe", "topic": "/odom"}))
        for frame in bad:
            await ws.send(frame)
        frames = await collect(ws, 0.5)
        assert frames == []
        probe = await call(ws, "/rosapi/get_time", {}, "probe")
        assert probe["result"] is True
        assert await recv_until(other, lambda m: m.get("topic") == "/odom")


async def test_lenient_parsing(sim: SimServer) -> None:
    async with connect(sim) as ws:
        two = ('{"op": "call_service", "id": "m1", "service": "/rosapi/get_time", "args": {}}'
               '{"op": "call_service", "id": "m2", "service": "/rosapi/get_time", "args": {}}')
        await ws.send(two)
        await ws.send('{"op":"call_service","service":"/rosapi/get_time","id":"nan-1","args":{},"x":NaN}')
        await ws.send(b'{"op": "call_service", "id": "bin", "service": "/rosapi/get_time", "args": {}}')
        ids = set()
        await recv_until(ws, lambda m: ids.add(m.get("id")) or {"m1", "m2", "nan-1", "bin"} <= ids)


async def test_huge_id_is_echoed(sim: SimServer) -> None:
    big = "Y" * 200_000
    async with connect(sim) as ws:
        reply = await call(ws, "/rosapi/get_time", {}, big)
    assert reply["id"] == big


# -- auth -----------------------------------------------------------------------------------------------


def _auth_frame(secret: str, now: float, **override: Any) -> dict[str, Any]:
    fields = {"client": "192.168.1.5", "dest": "192.168.1.2", "rand": "r4nd", "t": int(now), "level": "admin",
              "end": int(now) + 60}
    fields.update(override)
    mac = make_mac(secret, fields["client"], fields["dest"], fields["rand"], fields["t"], fields["level"],
                   fields["end"])
    return {"op": "auth", "mac": mac, **fields}


async def test_auth_required_when_configured() -> None:
    import time

    server = SimServer(auth_secret="s3cret", robot=False)
    await server.start()
    try:
        async with websockets.connect(server.url) as ws:
            await ws.send(json.dumps(_auth_frame("s3cret", time.time())))
            reply = await call(ws, "/rosapi/get_time", {})
            assert reply["result"] is True
        for frame in (_auth_frame("wrong", time.time()), {"op": "call_service", "service": "/rosapi/get_time"},
                      _auth_frame("s3cret", time.time() - 100)):
            async with websockets.connect(server.url) as ws:
                await ws.send(json.dumps(frame))
                with pytest.raises(websockets.ConnectionClosed):
                    await asyncio.wait_for(ws.recv(), 5)
    finally:
        await server.stop()
