"""``rcon sim --ros2`` against the real rosbridge 2.1.0 recordings: where the sim plays the same role, it
answers in the same shapes, field by field (key order aside: ``shape`` compares keys as sets).

Where the sim differs on purpose it is said in ``docs/architecture.md`` ("Where the sim differs from
rosbridge 2.1.0 on purpose") and not compared here: its graph is a boat, not the recording's demo node; it
sends ``png`` (2.1.0 sends nothing), writes NaN as ``null`` everywhere (2.1.0 writes bare ``NaN`` inside
fixed-size arrays), its typedefs carry only real constants, and it answers rosapi calls that kill 2.1.0.
"""

from __future__ import annotations

import asyncio
import json
from typing import Any

import pytest
import websockets
from replay_server import ROS2, load

from rcon_core.sim import SimServer

pytestmark = pytest.mark.recordings

ROSAPI = load("rosapi.jsonl", ROS2)


def shape(value: Any) -> Any:
    """Keys (as a set, recursively), list element shapes, leaves as their JSON kind; None counts as a number
    (rosbridge writes NaN as null)."""
    if isinstance(value, dict):
        return {k: shape(v) for k, v in value.items()}
    if isinstance(value, list):
        return [shape(value[0])] if value else []
    if isinstance(value, bool):
        return "bool"
    if isinstance(value, int | float) or value is None:
        return "number"
    return type(value).__name__


def same_shape(a: Any, b: Any, where: str = "") -> list[str]:
    """Differences between two shapes; an empty list matches any list (its elements are unknown)."""
    if isinstance(a, dict) and isinstance(b, dict):
        out = [f"{where}: keys {sorted(a.keys() ^ b.keys())}"] if a.keys() != b.keys() else []
        for k in a.keys() & b.keys():
            out += same_shape(a[k], b[k], f"{where}.{k}")
        return out
    if isinstance(a, list) and isinstance(b, list):
        return same_shape(a[0], b[0], f"{where}[]") if a and b else []
    return [] if a == b else [f"{where}: {a} != {b}"]


def _connect(sim: SimServer) -> Any:
    return websockets.connect(sim.url, max_size=None, max_queue=None)


async def next_op(ws: Any, op: str, timeout: float = 5.0, **match: Any) -> dict[str, Any]:
    async def wait() -> dict[str, Any]:
        while True:
            raw = await ws.recv()
            m = json.loads(raw) if isinstance(raw, str) else {}
            if m.get("op") == op and all(m.get(k) == v for k, v in match.items()):
                return m

    return await asyncio.wait_for(wait(), timeout)


async def ask(ws: Any, frame: dict[str, Any]) -> dict[str, Any]:
    await ws.send(json.dumps(frame))
    return await next_op(ws, "service_response", id=frame["id"])


#: rosapi.jsonl lines the sim is compared on (every call of connection 1 but the ones about the demo's
#: parameters, which the boat does not have, and rosapi's own parameter services)
COMPARED = [n for n in range(1, 64) if n not in range(34, 57)]


async def test_rosapi_answers_have_the_recorded_shapes(sim_ros2: SimServer) -> None:
    problems = []
    async with _connect(sim_ros2) as ws:
        for n in COMPARED:
            rec = ROSAPI[n - 1]
            reply = await ask(ws, rec["sent"])
            assert reply.keys() == rec["received"].keys(), n
            assert reply["result"] is rec["received"]["result"], (n, reply)
            problems += [f"rosapi.jsonl:{n}{p}" for p in same_shape(shape(reply["values"]),
                                                                    shape(rec["received"]["values"]))]
    assert problems == []


async def test_failures_read_like_the_recorded_ones(sim_ros2: SimServer) -> None:
    """rosapi.jsonl:57-58, :62-63 and services.jsonl:12: result false with the error as a string."""
    async with _connect(sim_ros2) as ws:
        for rec in (ROSAPI[56], ROSAPI[57], ROSAPI[61], ROSAPI[62], load("services.jsonl", ROS2)[11]):
            reply = await ask(ws, rec["sent"])
            assert reply["result"] is False and isinstance(reply["values"], str)
            assert reply["values"] == rec["received"]["values"], rec["sent"]["id"]


async def test_parameter_services_answer_in_the_recorded_shapes(sim_ros2: SimServer) -> None:
    """rosapi.jsonl:34-38: a node's own parameter services; every ParameterValue slot present, byte[] a
    list, GetParameterTypes' uint8[] types as base64 text."""
    async with _connect(sim_ros2) as ws:
        for n in (34, 35, 36, 37, 38):
            rec = ROSAPI[n - 1]
            frame = dict(rec["sent"], service="/kingfisher/" + rec["sent"]["service"].rsplit("/", 1)[-1])
            if "names" in frame.get("args", {}):
                frame["args"] = {"names": ["max_speed", "nope"][: len(frame["args"]["names"])]}
            reply = await ask(ws, frame)
            assert reply["result"] is True
            assert same_shape(shape(reply["values"]), shape(rec["received"]["values"])) == [], n
        got = await ask(ws, {"op": "call_service", "id": "v", "service": "/kingfisher/get_parameters",
                             "args": {"names": ["max_speed"]}})
        assert got["values"]["values"][0]["byte_array_value"] == []


async def test_published_messages_have_the_recorded_shapes(sim_ros2: SimServer) -> None:
    """publish_json.jsonl: the bridge's own topics and the types both have, plus what a client publishes and
    reads back on one connection (String, Float64MultiArray, UInt8MultiArray as base64, Int8MultiArray as
    a list, Int64, Imu)."""
    from rcon_core.bridge.protocol import loads_text

    recorded = {}
    for line in load("publish_json.jsonl", ROS2):
        got = loads_text(line["received_text"]) if line.get("received_text") else None  # real NaN floats
        if got and got.get("op") == "publish":
            recorded.setdefault(got["topic"], got)
    pairs = {"/client_count": "/client_count", "/connected_clients": "/connected_clients", "/rosout": "/rosout",
             "/camera/front/image_raw": "/peer/image"}
    seen: dict[str, dict[str, Any]] = {}
    async with _connect(sim_ros2) as ws:
        for topic in pairs:
            await ws.send(json.dumps({"op": "subscribe", "id": f"s:{topic}", "topic": topic}))
        fed = {"/client/f64arr": "std_msgs/msg/Float64MultiArray", "/client/u8arr": "std_msgs/msg/UInt8MultiArray",
               "/client/i8arr": "std_msgs/msg/Int8MultiArray", "/client/i64": "std_msgs/msg/Int64",
               "/client/imu": "sensor_msgs/msg/Imu", "/from_client": "std_msgs/msg/String"}
        for topic, type_name in fed.items():
            await ws.send(json.dumps({"op": "advertise", "topic": topic, "type": type_name}))
            await ws.send(json.dumps({"op": "subscribe", "id": f"s:{topic}", "topic": topic, "type": type_name}))
        sent = {line["sent"]["topic"]: line["sent"] for line in load("publish_json.jsonl", ROS2)
                if isinstance(line.get("sent"), dict) and line["sent"].get("op") == "publish"}
        for topic in fed:
            msg = dict(sent[topic]["msg"]) if topic in sent else {"data": "x"}
            if topic == "/client/imu":  # (the recorded ones hold NaN tokens: see the module docstring)
                msg = {"header": {"frame_id": "imu"}}
            elif topic == "/client/f64arr":
                msg = {"layout": {"dim": [], "data_offset": 0}, "data": [0.1, -0.0, 1e20]}
            await ws.send(json.dumps({"op": "publish", "topic": topic, "msg": msg}))

        async def gather() -> None:
            while len(seen) < len(pairs) + len(fed):
                raw = await ws.recv()
                m = json.loads(raw)
                if m.get("op") == "publish":
                    assert m.keys() == {"op", "topic", "msg"}
                    seen.setdefault(m["topic"], m)

        await asyncio.wait_for(gather(), 10)
    recorded["/from_client"] = recorded["/from_client/echo"]
    problems = []
    for topic in list(pairs) + list(fed):
        problems += [f"{topic}{p}" for p in same_shape(shape(seen[topic]["msg"]),
                                                       shape(recorded[pairs.get(topic, topic)]["msg"]))]
    assert problems == []
    assert isinstance(seen["/client/u8arr"]["msg"]["data"], str) and seen["/client/i8arr"]["msg"]["data"] == [-1, 0, 1, 127, -128]
    assert seen["/client/i64"]["msg"]["data"] == 9007199254740993


async def test_fragments_have_the_recorded_shape_and_stick_to_the_connection(sim_ros2: SimServer) -> None:
    """subscribe_options.jsonl:22-35: id 0 for a publish, a float total, the request's id for a reply."""
    recorded = [line["received"] for line in load("subscribe_options.jsonl", ROS2)
                if (line.get("received") or {}).get("op") == "fragment"]
    async with _connect(sim_ros2) as ws:
        await ws.send(json.dumps({"op": "subscribe", "id": "f", "topic": "/client_count", "fragment_size": 30}))
        first = await next_op(ws, "fragment")
        assert first.keys() == recorded[0].keys() and first["id"] == 0 and isinstance(first["total"], float)
        await ws.send(json.dumps({"op": "unsubscribe", "id": "f", "topic": "/client_count"}))
        await ws.send(json.dumps({"op": "call_service", "id": "sticky", "service": "/rosapi/get_time", "args": {}}))
        reply = await next_op(ws, "fragment", id="sticky")
        assert reply.keys() == recorded[-1].keys() and isinstance(reply["total"], float)


async def test_goal_frames_have_the_recorded_shapes(sim_ros2: SimServer) -> None:
    """actions.jsonl:1-8: action_feedback {op, action, values, id}; action_result {op, action, values,
    status, result, id} with status 4; feedback only when asked."""
    lines = load("actions.jsonl", ROS2)
    fb_rec, res_rec = lines[1]["received"], lines[5]["received"]
    async with _connect(sim_ros2) as ws:
        await ws.send(json.dumps({"op": "send_action_goal", "id": "g", "action": "/fibonacci",
                                  "action_type": "action_tutorials_interfaces/action/Fibonacci",
                                  "args": {"order": 3}, "feedback": True}))
        fb = await next_op(ws, "action_feedback", timeout=10)
        res = await next_op(ws, "action_result", timeout=20)
    assert fb.keys() == fb_rec.keys() and res.keys() == res_rec.keys()
    assert res["status"] == 4 and res["result"] is True and list(res["values"]) == list(res_rec["values"])


async def test_frames_to_a_providing_client_have_the_recorded_shapes(sim_ros2: SimServer) -> None:
    """client_service.jsonl:3 and actions.jsonl:32, :38: what the server sends a client that provides a
    service or an action: the keys, the ids' forms, feedback always asked."""
    call_rec = load("client_service.jsonl", ROS2)[2]["received"]
    actions = load("actions.jsonl", ROS2)
    goal_rec, cancel_rec = actions[31]["received"], actions[37]["received"]
    async with _connect(sim_ros2) as provider, _connect(sim_ros2) as caller:
        await provider.send(json.dumps({"op": "advertise_service", "service": "/client/set_bool",
                                        "type": "std_srvs/srv/SetBool"}))
        await provider.send(json.dumps({"op": "advertise_action", "action": "/client/fibonacci",
                                        "type": "example_interfaces/action/Fibonacci"}))
        await ask(provider, {"op": "call_service", "id": "sync", "service": "/rosapi/get_time", "args": {}})
        await caller.send(json.dumps({"op": "call_service", "id": "c", "service": "/client/set_bool",
                                      "args": {"data": True}}))
        call = await next_op(provider, "call_service")
        assert call.keys() == call_rec.keys() and call["id"] == "service_request:/client/set_bool:1"
        await caller.send(json.dumps({"op": "send_action_goal", "id": "g", "action": "/client/fibonacci",
                                      "action_type": "example_interfaces/action/Fibonacci", "args": {"order": 3}}))
        goal = await next_op(provider, "send_action_goal")
        assert goal.keys() == goal_rec.keys() and goal["feedback"] is True
        assert goal["id"] == "action_goal:/client/fibonacci:1"
        await caller.send(json.dumps({"op": "cancel_action_goal", "id": "g", "action": "/client/fibonacci"}))
        cancel = await next_op(provider, "cancel_action_goal")
        assert cancel.keys() == cancel_rec.keys() and cancel["id"] == goal["id"]
