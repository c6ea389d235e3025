"""The sim's rosbridge server, exercised with raw ``websockets`` clients over loopback."""

from __future__ import annotations

import asyncio
import json
from typing import Any

import pytest
import websockets

from rcon_core.sim import SimServer


async def recv_json(ws: Any, timeout: float = 5.0) -> dict[str, Any]:
    return json.loads(await asyncio.wait_for(ws.recv(), timeout))


async def recv_until(ws: Any, pred: Any, timeout: float = 5.0) -> dict[str, Any]:
    async def loop() -> dict[str, Any]:
        while True:
            raw = await ws.recv()
            if isinstance(raw, bytes):
                continue
            msg = json.loads(raw)
            if pred(msg):
                return msg

    return await asyncio.wait_for(loop(), timeout)


async def call(ws: Any, service: str, args: Any = None, call_id: str = "c1", **extra: Any) -> dict[str, Any]:
    frame: dict[str, Any] = {"op": "call_service", "id": call_id, "service": service, **extra}
    if args is not None:
        frame["args"] = args
    await ws.send(json.dumps(frame))
    return await recv_until(ws, lambda m: m.get("op") == "service_response" and m.get("id") == call_id)


async def test_topics_lists_the_robot(sim: SimServer) -> None:
    async with websockets.connect(sim.url) as ws:
        reply = await call(ws, "/rosapi/topics", {})
    assert reply["result"] is True
    topics = dict(zip(reply["values"]["topics"], reply["values"]["types"], strict=True))
    assert topics["/odom"] == "nav_msgs/Odometry"
    assert topics["/gps/fix"] == "sensor_msgs/NavSatFix"
    assert topics["/camera/front/image_raw"] == "sensor_msgs/Image"
    assert topics["/rosout"] == "rosgraph_msgs/Log"


async def test_cmd_vel_moves_the_vessel_then_watchdog_stops_it(sim: SimServer) -> None:
    async with websockets.connect(sim.url) as ws:
        await ws.send(json.dumps({"op": "subscribe", "topic": "/odom", "type": "nav_msgs/Odometry"}))
        for _ in range(5):
            await ws.send(json.dumps({"op": "publish", "topic": "/cmd_vel",
                                      "msg": {"linear": {"x": 1.0}, "angular": {"z": 0.0}}}))
            await asyncio.sleep(0.1)
        moving = await recv_until(ws, lambda m: m.get("topic") == "/odom"
                                  and m["msg"]["twist"]["twist"]["linear"]["x"] > 0.1)
        assert moving["msg"]["header"]["frame_id"] == "odom"
        stopped = await recv_until(ws, lambda m: m.get("topic") == "/odom"
                                   and abs(m["msg"]["twist"]["twist"]["linear"]["x"]) < 0.02, timeout=15)
        assert stopped["msg"]["pose"]["pose"]["position"]["x"] != 0.0
    assert sim.robot.watchdog_tripped


async def test_service_on_unknown_name_fails_with_text(sim: SimServer) -> None:
    async with websockets.connect(sim.url) as ws:
        reply = await call(ws, "/no/such/service", {})
    assert reply == {"op": "service_response", "service": "/no/such/service",
                     "values": "Service /no/such/service does not exist", "result": False, "id": "c1"}


@pytest.mark.parametrize("args", [{"data": True}, [True]])
async def test_lights_service_args_object_or_array(sim: SimServer, args: Any) -> None:
    async with websockets.connect(sim.url) as ws:
        await ws.send(json.dumps({"op": "subscribe", "topic": "/lights/state"}))
        latched = await recv_until(ws, lambda m: m.get("topic") == "/lights/state")
        assert latched["msg"] == {"data": False}
        await ws.send(json.dumps({"op": "call_service", "id": "l1", "service": "/lights/set", "args": args}))
        state = await recv_until(ws, lambda m: m.get("topic") == "/lights/state")
        assert state["msg"] == {"data": True}
        reply = await recv_until(ws, lambda m: m.get("id") == "l1")
        assert reply["result"] is True and reply["values"]["success"] is True
    assert sim.robot.lights is True
