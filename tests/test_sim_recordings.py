"""The sim against the real rosbridge 0.11.17 recordings: same answers, same shapes."""

from __future__ import annotations

import asyncio
import base64
import json
from pathlib import Path
from typing import Any

import pytest
import websockets

from rcon_core.sim import SimServer

RECORDINGS = Path(__file__).resolve().parent / "recordings" / "rosbridge-ros1"

pytestmark = pytest.mark.recordings


def lines(name: str) -> list[dict[str, Any]]:
    return [json.loads(line) for line in (RECORDINGS / name).read_text(encoding="utf-8").splitlines() if line.strip()]


async def ask(ws: Any, frame: dict[str, Any]) -> dict[str, Any]:
    await ws.send(json.dumps(frame))

    async def wait() -> dict[str, Any]:
        while True:
            msg = json.loads(await ws.recv())
            if msg.get("op") == "service_response" and msg.get("id") == frame.get("id"):
                return msg

    return await asyncio.wait_for(wait(), 5)


def shape(value: Any) -> Any:
    """The key structure of a message: dict keys in order, recursively; leaves as their JSON kind."""
    if isinstance(value, dict):
        return {k: shape(v) for k, v in value.items()}
    if isinstance(value, list):
        return ["list"]
    if isinstance(value, bool):
        return "bool"
    if isinstance(value, int | float) or value is None:
        return "number"
    return type(value).__name__


def _connect(sim: SimServer) -> Any:
    return websockets.connect(sim.url, max_size=None, max_queue=None)


async def test_type_details_equal_the_real_rosapi(sim: SimServer) -> None:
    kinds = {"message_details", "service_request_details", "service_response_details"}
    recorded = [r for r in lines("rosapi.jsonl") if r["sent"] and r["sent"]["service"].split("/")[-1] in kinds]
    assert len(recorded) >= 24
    async with _connect(sim) as ws:
        for rec in recorded:
            reply = await ask(ws, rec["sent"])
            assert reply == rec["received"], rec["sent"]["args"]


async def test_params_cycle_equals_the_real_rosapi(sim: SimServer) -> None:
    sim.params_tree.set("/rec", {"int_param": 7, "str_param": "hi", "list_param": [1, 2, 3], "dict_param": {"a": 1}})
    recorded = [r for r in lines("rosapi.jsonl")
                if r["sent"] and r["sent"]["service"].split("/")[-1] in
                {"get_param", "set_param", "has_param", "delete_param", "search_param"}]
    assert len(recorded) >= 15
    async with _connect(sim) as ws:
        for rec in recorded:
            reply = await ask(ws, rec["sent"])
            if rec["received"]["result"]:
                assert reply == rec["received"], rec["sent"]
            else:  # failure: same shape, our own words for the reason
                assert reply["result"] is False and isinstance(reply["values"], str)
                assert "JSON-formatted string" in reply["values"]
        names = await ask(ws, {"op": "call_service", "id": "n", "service": "/rosapi/get_param_names", "args": {}})
    assert {"/rec/int_param", "/rec/dict_param/a", "/kingfisher/max_speed"} <= set(names["values"]["names"])


async def test_rosapi_failures_and_unknowns_equal_the_real_rosapi(sim: SimServer) -> None:
    wanted = {"rosapi:42:topic_type", "rosapi:63:wrong_arg_type", "rosapi:64:unknown_arg", "rosapi:65:nonexistent",
              "rosapi:2:action_servers", "rosapi:28:service_providers"}
    recorded = [r for r in lines("rosapi.jsonl") if r["sent"] and r["sent"]["id"] in wanted]
    assert len(recorded) == len(wanted)
    async with _connect(sim) as ws:
        for rec in recorded:
            frame = dict(rec["sent"])
            if frame["id"] == "rosapi:64:unknown_arg":
                frame["args"] = {"topic": "/odom", "extra": 1}
            reply = await ask(ws, frame)
            assert reply == rec["received"], frame["id"]


async def test_rosapi_listing_shapes(sim: SimServer) -> None:
    recorded = {r["sent"]["id"].split(":")[-1]: r["received"] for r in lines("rosapi.jsonl") if r["sent"]}
    async with _connect(sim) as ws:
        for key, service, args in [("nodes", "nodes", {}), ("node_details", "node_details", {"node": "/kingfisher"}),
                                   ("get_time", "get_time", {}), ("get_loggers", "get_loggers", {}),
                                   ("services", "services", {}), ("topics_and_raw_types", "topics_and_raw_types", {}),
                                   ("services_for_type", "services_for_type", {"type": "std_srvs/Trigger"}),
                                   ("service_providers", "service_providers", {"service": "std_srvs/Trigger"})]:
            reply = await ask(ws, {"op": "call_service", "id": key, "service": f"/rosapi/{service}", "args": args})
            assert reply["result"] is True
            assert list(reply["values"]) == list(recorded[key]["values"]), key
            assert shape(reply["values"]) == shape(recorded[key]["values"]), key
        details = await ask(ws, {"op": "call_service", "id": "nd", "service": "/rosapi/node_details",
                                 "args": {"node": "/kingfisher"}})
        raw = await ask(ws, {"op": "call_service", "id": "raw", "service": "/rosapi/topics_and_raw_types",
                             "args": {}})
        providers = await ask(ws, {"op": "call_service", "id": "sp", "service": "/rosapi/service_providers",
                                   "args": {"service": "std_srvs/Trigger"}})
    assert "/odom" in details["values"]["publishing"] and "/cmd_vel" in details["values"]["subscribing"]
    assert "/dock" in details["values"]["services"]
    text = dict(zip(raw["values"]["topics"], raw["values"]["typedefs_full_text"], strict=True))["/odom"]
    assert "MSG: std_msgs/Header" in text and "geometry_msgs/PoseWithCovariance pose" in text
    assert providers["values"] == {"providers": ["/kingfisher"]}


async def test_robot_messages_have_the_recorded_shapes(sim: SimServer) -> None:
    by_type: dict[str, dict[str, Any]] = {}
    topic_types = dict(zip(*(lines("rosapi.jsonl")[42]["received"]["values"][k] for k in ("topics", "types")),
                           strict=True))
    for rec in lines("publish_json.jsonl"):
        got = rec.get("received")
        if got and got.get("op") == "publish" and got["topic"] in topic_types:
            by_type.setdefault(topic_types[got["topic"]], got["msg"])
    pairs = {"/odom": "nav_msgs/Odometry", "/gps/fix": "sensor_msgs/NavSatFix", "/imu/data": "sensor_msgs/Imu",
             "/scan": "sensor_msgs/LaserScan", "/map": "nav_msgs/OccupancyGrid", "/battery": "sensor_msgs/BatteryState",
             "/imu/mag": "sensor_msgs/MagneticField", "/camera/rear/image_raw/compressed": "sensor_msgs/CompressedImage",
             "/camera/front/image_raw": "sensor_msgs/Image", "/rosout": "rosgraph_msgs/Log"}
    seen: dict[str, dict[str, Any]] = {}
    async with _connect(sim) as ws:
        for topic in pairs:
            await ws.send(json.dumps({"op": "subscribe", "topic": topic}))

        async def gather() -> None:
            while set(seen) != set(pairs):
                frame = await ws.recv()
                assert isinstance(frame, str)
                msg = json.loads(frame)
                assert list(msg) == ["op", "topic", "msg"]
                if msg["op"] == "publish":
                    seen.setdefault(msg["topic"], msg["msg"])

        await asyncio.wait_for(gather(), 10)
    for topic, type_name in pairs.items():
        assert shape(seen[topic]) == shape(by_type[type_name]), topic
    # uint8[] as base64 text; int8[] as a list with -1 for unknown cells
    assert base64.b64decode(seen["/camera/front/image_raw"]["data"])
    assert -1 in seen["/map"]["data"] and 100 in seen["/map"]["data"]
    assert seen["/map"]["info"]["map_load_time"].keys() == {"secs", "nsecs"}


async def test_malformed_recording_replay(sim: SimServer) -> None:
    """Every frame of malformed.jsonl: replies exactly where the real server replied, never a close."""
    records = lines("malformed.jsonl")
    expected: list[Any] = []
    async with _connect(sim) as ws, _connect(sim) as bystander:
        await bystander.send(json.dumps({"op": "subscribe", "topic": "/odom"}))
        for rec in records:
            if rec.get("sent_b64"):
                await ws.send(base64.b64decode(rec["sent_b64"]))
            elif isinstance(rec.get("sent"), str):
                await ws.send(rec["sent"])
            elif rec.get("sent") is not None:
                await ws.send(json.dumps(rec["sent"]))
            got = rec.get("received")
            if got and got.get("op") == "service_response" and not rec.get("abbreviated"):
                expected.append(got["id"])
        replies: list[Any] = []

        async def gather() -> None:
            while len([r for r in replies if not str(r).startswith("<1000000")]) < len(expected):
                msg = json.loads(await ws.recv())
                if msg.get("op") == "service_response":
                    replies.append(msg["id"])
                elif msg.get("op") == "publish":  # only /rec/str would publish, which the sim has not
                    raise AssertionError(f"unexpected publish {msg['topic']}")

        await asyncio.wait_for(gather(), 10)
        extra = []
        try:
            extra.append(json.loads(await asyncio.wait_for(ws.recv(), 0.5)))
        except TimeoutError:
            pass
        assert extra == []
        assert json.loads(await asyncio.wait_for(bystander.recv(), 5))["topic"] == "/odom"
    assert sorted(r for r in replies if not str(r).startswith("<1000000")) == sorted(expected)
