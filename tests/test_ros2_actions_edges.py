"""Edges of ROS 2 actions: bad action frames to the sim, a provided action across a reconnect."""

from __future__ import annotations

import asyncio
import json
from typing import Any

import websockets

from rcon_core.bridge import BridgeClient, GoalStatus
from rcon_core.sim import SimServer
from rcon_core.testing import until

ACTION = "/edge_action"
TYPE = "example_interfaces/action/Fibonacci"


async def call(ws: Any, service: str, cid: str) -> dict[str, Any]:
    await ws.send(json.dumps({"op": "call_service", "id": cid, "service": service, "args": {}}))
    while True:
        frame = json.loads(await asyncio.wait_for(ws.recv(), 5))
        if frame.get("id") == cid:
            return frame


async def test_bad_action_frames_are_dropped_and_the_link_lives(sim_ros2: SimServer) -> None:
    bad = [
        {"op": "advertise_action", "action": ACTION},  # no type
        {"op": "advertise_action", "action": 5, "type": TYPE},
        {"op": "advertise_action", "action": ACTION, "type": "no_pkg/action/Nothing"},
        {"op": "unadvertise_action", "action": "/never_advertised"},
        {"op": "action_feedback", "action": "/fibonacci", "id": "x", "values": {}},  # not this client's
        {"op": "action_result", "action": ACTION, "id": "x", "status": 4, "result": True, "values": {}},
        {"op": "action_result", "action": ACTION, "status": "done", "result": True},
        {"op": "cancel_action_goal", "action": "/fibonacci", "id": "nothing-running"},
        {"op": "send_action_goal", "action": "/fibonacci"},  # no action_type
    ]
    async with websockets.connect(sim_ros2.url) as ws:
        for frame in bad:
            await ws.send(json.dumps(frame))
        servers = await call(ws, "/rosapi/action_servers", "after")
        # still a working action link: a real goal runs to its end
        await ws.send(json.dumps({"op": "send_action_goal", "id": "ok", "action": "/fibonacci",
                                  "action_type": "action_tutorials_interfaces/action/Fibonacci", "args": {"order": 2}}))
        result = json.loads(await asyncio.wait_for(ws.recv(), 5))
    assert servers["values"] == {"action_servers": ["/fibonacci", "/navigate_to_fix"]}
    assert result == {"op": "action_result", "action": "/fibonacci", "values": {"sequence": [0, 1, 1]}, "status": 4,
                      "result": True, "id": "ok"}


async def test_goal_args_that_do_not_fit_the_goal_type_fail_with_a_reason(sim_ros2: SimServer) -> None:
    async with websockets.connect(sim_ros2.url) as ws:
        await ws.send(json.dumps({"op": "send_action_goal", "id": "g", "action": "/fibonacci",
                                  "action_type": "action_tutorials_interfaces/Fibonacci",
                                  "args": {"order": "many"}}))
        result = json.loads(await asyncio.wait_for(ws.recv(), 5))
    assert result["result"] is False and result["status"] == 0 and result["id"] == "g"
    assert "order" in result["values"] and "int" in result["values"]


async def test_a_provided_action_survives_a_reconnect() -> None:
    first = SimServer(ros2=True, rate_scale=4.0)
    await first.start()
    port = first.port
    provider = BridgeClient(first.url, call_timeout=3, backoff_min=0.05, backoff_max=0.2)
    await provider.connect(timeout=5)
    started: list[Any] = []

    async def handler(goal: Any) -> dict[str, Any]:
        started.append(goal)
        if goal.args["order"] == 99:
            await asyncio.Event().wait()  # hangs until the link drops
        return {"sequence": [goal.args["order"]]}

    srv = provider.node("p").advertise_action(ACTION, TYPE, handler)
    caller = BridgeClient(first.url, call_timeout=3, reconnect=False)
    await caller.connect(timeout=5)
    hanging = caller.node("c").send_action_goal(ACTION, TYPE, {"order": 99}, check=False)
    await until(lambda: started)
    await first.stop()  # the robot goes away with a goal in flight
    second = SimServer(ros2=True, rate_scale=4.0, port=port)
    try:
        await second.start()
        await until(lambda: provider.connected and ACTION in second.action_hub.names())
        # abandoned, not answered late; its fate is unknown, not success
        assert started[0].done and started[0].task.done() and started[0].status == GoalStatus.UNKNOWN
        assert not srv.goals
        late = BridgeClient(second.url, call_timeout=3)
        await late.connect(timeout=5)
        try:
            goal = late.node("c").send_action_goal(ACTION, TYPE, {"order": 4})
            assert await goal.result(timeout=5) == {"sequence": [4]}
            assert goal.status == GoalStatus.SUCCEEDED
        finally:
            await late.close()
    finally:
        await provider.close()
        await caller.close()
        await second.stop()
    assert hanging.done  # the caller's goal failed with the lost link, it did not hang
    assert hanging.outcome == "unknown (link lost)" and not hanging.succeeded


async def test_action_part_layouts_come_from_the_local_registry(sim_ros2: SimServer) -> None:
    """rosapi 2.1.0 answers [] for an action's parts; the client falls back to its registry."""
    from rcon_core.bridge import BridgeError
    from rcon_core.msgs import TypeRegistry

    with_registry = BridgeClient(sim_ros2.url, call_timeout=3, registry=TypeRegistry.standard(ros2=True))
    bare = BridgeClient(sim_ros2.url, call_timeout=3)
    await with_registry.connect(timeout=5)
    await bare.connect(timeout=5)
    try:
        typedefs = await with_registry.typedefs("rcon_sim/action/NavigateToFix_Goal")
        assert typedefs[0]["fieldnames"] == ["target"]
        try:
            await bare.typedefs("rcon_sim/action/NavigateToFix_Goal")
        except BridgeError as exc:
            assert "no definition" in str(exc)
        else:
            raise AssertionError("a server answer of [] must not pass for a definition")
    finally:
        await with_registry.close()
        await bare.close()


async def test_an_advertisers_bad_feedback_or_result_is_refused_and_the_goal_stays_open(sim_ros2: SimServer) -> None:
    async with websockets.connect(sim_ros2.url) as a, websockets.connect(sim_ros2.url) as b:
        await a.send(json.dumps({"op": "advertise_action", "action": ACTION, "type": TYPE}))
        await call(a, "/rosapi/action_servers", "sync")
        await b.send(json.dumps({"op": "send_action_goal", "id": "g", "action": ACTION, "action_type": TYPE,
                                 "args": {"order": 3}, "feedback": True}))
        goal = json.loads(await asyncio.wait_for(a.recv(), 5))
        gid = goal["id"]
        await a.send(json.dumps({"op": "action_feedback", "action": ACTION, "id": gid,
                                 "values": {"sequence": "not a list"}}))
        await a.send(json.dumps({"op": "action_result", "action": ACTION, "id": gid, "status": 4, "result": True,
                                 "values": {"sequence": ["x"]}}))
        await a.send(json.dumps({"op": "action_result", "action": ACTION, "id": gid, "status": 4, "result": True,
                                 "values": {"sequence": [0, 1, 1, 2]}}))
        result = json.loads(await asyncio.wait_for(b.recv(), 5))  # no feedback frame came before it
    assert result == {"op": "action_result", "action": ACTION, "values": {"sequence": [0, 1, 1, 2]}, "status": 4,
                      "result": True, "id": "g"}
