"""The sim in ROS 2 flavour: pkg/msg/Type names, sec/nanosec times, the NavigateToFix action."""

from __future__ import annotations

import asyncio
import json
from typing import Any

import websockets

from rcon_core.msgs import TypeRegistry
from rcon_core.sim import SimServer
from rcon_core.testing import until


async def recv_until(ws: Any, pred: Any, timeout: float = 5.0) -> dict[str, Any]:
    async def loop() -> dict[str, Any]:
        while True:
            msg = json.loads(await ws.recv())
            if pred(msg):
                return msg

    return await asyncio.wait_for(loop(), timeout)


async def test_ros2_types_and_times(sim_ros2: SimServer) -> None:
    reg = TypeRegistry.standard(ros2=True)
    async with websockets.connect(sim_ros2.url, max_size=None, max_queue=None) as ws:
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


async def test_navigate_to_fix_action(sim_ros2: SimServer) -> None:
    lat, lon = sim_ros2.robot.lat_lon()
    # a target 4 m ahead of the vessel's heading
    import math

    x = sim_ros2.robot.x + 4.0 * math.cos(sim_ros2.robot.yaw)
    y = sim_ros2.robot.y + 4.0 * math.sin(sim_ros2.robot.yaw)
    lat = sim_ros2.robot.origin_lat + math.degrees(y / 6_378_137.0)
    lon = sim_ros2.robot.origin_lon + math.degrees(x / (6_378_137.0 * math.cos(math.radians(sim_ros2.robot.origin_lat))))
    async with websockets.connect(sim_ros2.url, max_size=None, max_queue=None) as ws:
        await ws.send(json.dumps({"op": "call_service", "id": "a", "service": "/rosapi/action_servers", "args": {}}))
        servers = await recv_until(ws, lambda m: m.get("id") == "a")
        assert servers["values"] == {"action_servers": ["/fibonacci", "/navigate_to_fix"]}
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


async def test_cancel_action_goal(sim_ros2: SimServer) -> None:
    async with websockets.connect(sim_ros2.url, max_size=None, max_queue=None) as ws:
        await ws.send(json.dumps({"op": "send_action_goal", "id": "far", "action": "/navigate_to_fix",
                                  "action_type": "rcon_sim/action/NavigateToFix", "feedback": True,
                                  "args": {"target": {"latitude": 43.70, "longitude": -79.30}}}))
        await recv_until(ws, lambda m: m.get("op") == "action_feedback")
        await ws.send(json.dumps({"op": "cancel_action_goal", "id": "far", "action": "/navigate_to_fix"}))
        result = await recv_until(ws, lambda m: m.get("op") == "action_result")
    # rosbridge's ROS 2 capability: a goal that ended (cancelled too) is result true with its GoalStatus
    assert result["status"] == 5 and result["result"] is True
    assert result["values"]["success"] is False and result["values"]["message"] == "canceled"
    assert sim_ros2.robot.cmd_surge == 0.0


async def test_feedback_only_when_asked(sim_ros2: SimServer) -> None:
    """ROSBRIDGE_PROTOCOL.md: ``feedback`` defaults to false, so a goal without it gets no feedback frames."""
    nav, steps = sim_ros2.navigate_action, []
    real_distance = nav._distance  # called once per step of the drive, where a feedback frame would go out
    nav._distance = lambda goal: steps.append(goal) or real_distance(goal)
    async with websockets.connect(sim_ros2.url, max_size=None, max_queue=None) as ws:
        await ws.send(json.dumps({"op": "send_action_goal", "id": "quiet", "action": "/navigate_to_fix",
                                  "action_type": "rcon_sim/action/NavigateToFix",
                                  "args": {"target": {"latitude": 43.70, "longitude": -79.30}}}))
        await until(lambda: len(steps) >= 3, what="three steps of the drive")  # the result comes after them
        await ws.send(json.dumps({"op": "cancel_action_goal", "id": "quiet", "action": "/navigate_to_fix"}))
        seen: list[dict[str, Any]] = []
        result = await recv_until(ws, lambda m: seen.append(m) or m.get("op") == "action_result")
    assert result["status"] == 5
    assert [m for m in seen if m.get("op") == "action_feedback"] == []


async def test_goals_that_cannot_be_sent_fail_like_rosbridge(sim_ros2: SimServer) -> None:
    """Unknown action, unknown type, unusable args: ``result: false``, status 0, the error as a string."""
    goals = [
        ({"action": "/no_such_action", "action_type": "rcon_sim/action/NavigateToFix"}, "No action server available"),
        ({"action": "/navigate_to_fix", "action_type": "rcon_sim/action/Nope"}, "Unable to load the action type"),
        ({"action": "/navigate_to_fix", "action_type": "rcon_sim/NavigateToFix", "args": {"target": 5}},
         "sensor_msgs/NavSatFix 'target'"),
        ({"action": "/navigate_to_fix", "action_type": "rcon_sim/action/NavigateToFix",
          "args": {"target": {"latitude": "north", "longitude": 1}}}, "must be numbers"),
    ]
    async with websockets.connect(sim_ros2.url, max_size=None, max_queue=None) as ws:
        for n, (frame, text) in enumerate(goals):
            await ws.send(json.dumps({"op": "send_action_goal", "id": f"g{n}", **frame}))
            result = await recv_until(ws, lambda m, n=n: m.get("op") == "action_result" and m.get("id") == f"g{n}")
            assert result["result"] is False and result["status"] == 0
            assert isinstance(result["values"], str) and text in result["values"]
            assert result["action"] == frame["action"]
    assert sim_ros2.robot.cmd_surge == 0.0
