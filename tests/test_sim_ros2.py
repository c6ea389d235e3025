"""The sim in ROS 2 flavour: pkg/msg/Type names, sec/nanosec times, the NavigateToFix action."""

from __future__ import annotations

import asyncio
import json
from collections.abc import AsyncIterator
from typing import Any

import pytest_asyncio
import websockets

from rcon_core.msgs import TypeRegistry
from rcon_core.sim import SimServer


@pytest_asyncio.fixture
async def sim2() -> AsyncIterator[SimServer]:
    server = SimServer(ros2=True, rate_scale=4.0)
    await server.start()
    try:
        yield server
    finally:
        await server.stop()


async def recv_until(ws: Any, pred: Any, timeout: float = 5.0) -> dict[str, Any]:
    async def loop() -> dict[str, Any]:
        while True:
            msg = json.loads(await ws.recv())
            if pred(msg):
                return msg

    return await asyncio.wait_for(loop(), timeout)


async def test_ros2_types_and_times(sim2: SimServer) -> None:
    reg = TypeRegistry.standard(ros2=True)
    async with websockets.connect(sim2.url, max_size=None, max_queue=None) as ws:
        await ws.send(json.dumps({"op": "call_service", "id": "t", "service": "/rosapi/topics", "args": {}}))
        topics = await recv_until(ws, lambda m: m.get("id") == "t")
        types = dict(zip(topics["values"]["topics"], topics["values"]["types"], strict=True))
        assert types["/odom"] == "nav_msgs/msg/Odometry"
        assert types["/rosout"] == "rcl_interfaces/msg/Log"
        await ws.send(json.dumps({"op": "subscribe", "topic": "/odom"}))
        await ws.send(json.dumps({"op": "subscribe", "topic": "/rosout"}))
        seen: dict[str, dict[str, Any]] = {}
        await recv_until(ws, lambda m: bool(seen.setdefault(m.get("topic"), m)) and {"/odom", "/rosout"} <= set(seen))
        odom, log = seen["/odom"], seen["/rosout"]
        await ws.send(json.dumps({"op": "call_service", "id": "s", "service": "/lights/set", "args": {"data": True}}))
        reply = await recv_until(ws, lambda m: m.get("id") == "s")
    assert odom["msg"]["header"]["stamp"].keys() == {"sec", "nanosec"}
    assert "seq" not in odom["msg"]["header"]
    assert reg.validate("nav_msgs/msg/Odometry", odom["msg"]) == []
    assert reg.validate("rcl_interfaces/msg/Log", log["msg"]) == []
    assert log["msg"]["level"] in (10, 20, 30, 40, 50)
    assert reply["values"] == {"success": True, "message": "lights on"}


async def test_navigate_to_fix_action(sim2: SimServer) -> None:
    lat, lon = sim2.robot.lat_lon()
    # a target 4 m ahead of the vessel's heading
    import math

    x = sim2.robot.x + 4.0 * math.cos(sim2.robot.yaw)
    y = sim2.robot.y + 4.0 * math.sin(sim2.robot.yaw)
    lat = sim2.robot.origin_lat + math.degrees(y / 6_378_137.0)
    lon = sim2.robot.origin_lon + math.degrees(x / (6_378_137.0 * math.cos(math.radians(sim2.robot.origin_lat))))
    async with websockets.connect(sim2.url, max_size=None, max_queue=None) as ws:
        await ws.send(json.dumps({"op": "call_service", "id": "a", "service": "/rosapi/action_servers", "args": {}}))
        servers = await recv_until(ws, lambda m: m.get("id") == "a")
        assert servers["values"] == {"action_servers": ["/navigate_to_fix"]}
        await ws.send(json.dumps({"op": "send_action_goal", "id": "goal-1", "action": "/navigate_to_fix",
                                  "action_type": "rcon_sim/action/NavigateToFix", "feedback": True,
                                  "args": {"target": {"latitude": lat, "longitude": lon}}}))
        feedback = await recv_until(ws, lambda m: m.get("op") == "action_feedback")
        assert feedback["id"] == "goal-1" and feedback["action"] == "/navigate_to_fix"
        assert 2.0 < feedback["values"]["distance_remaining"] < 6.0
        result = await recv_until(ws, lambda m: m.get("op") == "action_result", timeout=20)
    assert list(result) == ["op", "id", "action", "values", "status", "result"]
    assert result["status"] == 4 and result["result"] is True
    assert result["values"]["success"] is True and result["values"]["distance"] <= 2.0


async def test_cancel_action_goal(sim2: SimServer) -> None:
    async with websockets.connect(sim2.url, max_size=None, max_queue=None) as ws:
        await ws.send(json.dumps({"op": "send_action_goal", "id": "far", "action": "/navigate_to_fix",
                                  "action_type": "rcon_sim/action/NavigateToFix",
                                  "args": {"target": {"latitude": 43.70, "longitude": -79.30}}}))
        await recv_until(ws, lambda m: m.get("op") == "action_feedback")
        await ws.send(json.dumps({"op": "cancel_action_goal", "id": "far", "action": "/navigate_to_fix"}))
        result = await recv_until(ws, lambda m: m.get("op") == "action_result")
    assert result["status"] == 5 and result["result"] is False
    assert result["values"]["success"] is False
    assert sim2.robot.cmd_surge == 0.0
