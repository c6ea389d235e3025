"""Conversations with a rosbridge 2.x server (tests/recordings/rosbridge-ros2, derived from the upstream
websocket tests) replayed against ``rcon sim --ros2``, in raw frames; then the same conversations with
our client on one side or both."""

from __future__ import annotations

import asyncio
import json
from collections.abc import AsyncIterator
from pathlib import Path
from typing import Any

import pytest
import pytest_asyncio
import websockets

from rcon_core.bridge import BridgeClient, GoalStatus
from rcon_core.sim import SimServer
from rcon_core.testing import until

CONVERSATIONS = Path(__file__).parent / "recordings" / "rosbridge-ros2"
FILES = sorted(p.name for p in CONVERSATIONS.glob("*.jsonl"))
ACTION = "/test_fibonacci_action"


def substitute(value: Any, seen: dict[str, Any]) -> Any:
    if isinstance(value, dict):
        if set(value) == {"$ref"}:
            return seen[value["$ref"]]
        return {k: substitute(v, seen) for k, v in value.items()}
    if isinstance(value, list):
        return [substitute(v, seen) for v in value]
    return value


def matches(expected: Any, actual: Any, seen: dict[str, Any], path: str = "") -> list[str]:
    """Differences between an expected frame (with $capture / $any / $ref) and the actual one."""
    if isinstance(expected, dict) and set(expected) == {"$capture"}:
        seen[expected["$capture"]] = actual
        return []
    if isinstance(expected, dict) and set(expected) == {"$any"}:
        return []
    if isinstance(expected, dict) and set(expected) == {"$ref"}:
        expected = seen[expected["$ref"]]
    if isinstance(expected, dict):
        if not isinstance(actual, dict) or set(expected) != set(actual):
            return [f"{path or '.'}: keys {sorted(actual) if isinstance(actual, dict) else actual!r}, "
                    f"expected {sorted(expected)}"]
        return [d for k in expected for d in matches(expected[k], actual[k], seen, f"{path}.{k}")]
    if isinstance(expected, list):
        if not isinstance(actual, list) or len(actual) != len(expected):
            return [f"{path}: {actual!r}, expected {expected!r}"]
        return [d for i, (e, a) in enumerate(zip(expected, actual, strict=True))
                for d in matches(e, a, seen, f"{path}[{i}]")]
    if expected != actual or type(expected) is not type(actual):
        return [f"{path}: {actual!r}, expected {expected!r}"]
    return []


async def replay(url: str, steps: list[dict[str, Any]]) -> None:
    clients: dict[str, Any] = {}
    seen: dict[str, Any] = {}
    closed: set[str] = set()
    try:
        for n, step in enumerate(steps, 1):
            if "note" in step:
                continue
            name = step["client"]
            if name not in clients:
                clients[name] = await websockets.connect(url, max_size=None)
            ws = clients[name]
            if step.get("close"):
                await ws.close()
                closed.add(name)
                continue
            if "send" in step:
                await ws.send(json.dumps(substitute(step["send"], seen)))
                continue
            frame = json.loads(await asyncio.wait_for(ws.recv(), 5))
            problems = matches(step["expect"], frame, seen)
            assert not problems, f"step {n} ({name}): {problems}; frame {frame}"
        for name, ws in clients.items():  # nothing more arrived than the conversation says
            if name in closed:
                continue
            with pytest.raises(TimeoutError):
                await asyncio.wait_for(ws.recv(), 0.2)
    finally:
        for ws in clients.values():
            await ws.close()


@pytest.mark.parametrize("name", FILES)
async def test_conversation_in_raw_frames(sim_ros2: SimServer, name: str) -> None:
    steps = [json.loads(line) for line in (CONVERSATIONS / name).read_text(encoding="utf-8").splitlines()
             if line.strip()]
    await replay(sim_ros2.url, steps)


def test_the_conversations_are_there() -> None:
    assert {"advertise_action_two_goals.jsonl", "advertise_action_feedback.jsonl", "send_action_goal_feedback.jsonl",
            "advertise_service_two_calls.jsonl", "call_service.jsonl", "multiple_subscribers.jsonl",
            "transient_local_publisher.jsonl"} <= set(FILES)


# ---------------------------------------------------------------------------------- with our client

@pytest_asyncio.fixture
async def pair(sim_ros2: SimServer) -> AsyncIterator[tuple[BridgeClient, BridgeClient]]:
    a, b = BridgeClient(sim_ros2.url, call_timeout=5), BridgeClient(sim_ros2.url, call_timeout=5)
    await a.connect(timeout=5)
    await b.connect(timeout=5)
    try:
        yield a, b
    finally:
        await a.close()
        await b.close()


async def until_listed(client: BridgeClient, action: str) -> None:
    """Ask rosapi again (every 20 ms, 10 s at most) until it lists ``action``."""
    for _ in range(500):
        if action in await client.rosapi.action_servers():
            return
        await asyncio.sleep(0.02)
    raise AssertionError(f"{action} never listed")


async def test_client_provides_an_action_with_two_concurrent_goals(pair: tuple[BridgeClient, BridgeClient]) -> None:
    provider, caller = pair
    seen: list[tuple[str, dict[str, Any]]] = []
    release = asyncio.Event()

    async def fibonacci(goal: Any) -> dict[str, Any]:
        seen.append((goal.id, goal.args))
        sequence = [0, 1]
        for i in range(1, goal.args["order"]):
            sequence.append(sequence[i] + sequence[i - 1])
            goal.publish_feedback({"sequence": list(sequence)})
        await release.wait()  # both goals are in flight at once
        return {"sequence": sequence}

    srv = provider.node("fib").advertise_action(ACTION, "example_interfaces/action/Fibonacci", fibonacci)
    await until_listed(caller, ACTION)
    feedback3: list[dict[str, Any]] = []
    g3 = caller.node("ui").send_action_goal(ACTION, "example_interfaces/action/Fibonacci", {"order": 3},
                                            feedback3.append)
    g5 = caller.node("ui").send_action_goal(ACTION, "example_interfaces/action/Fibonacci", {"order": 5})
    await until(lambda: len(seen) == 2)
    assert [args for _, args in seen] == [{"order": 3}, {"order": 5}]
    assert [gid for gid, _ in seen] == [f"action_goal:{ACTION}:1", f"action_goal:{ACTION}:2"]
    release.set()
    assert await g3.result(timeout=5) == {"sequence": [0, 1, 1, 2]}
    assert await g5.result(timeout=5) == {"sequence": [0, 1, 1, 2, 3, 5]}
    assert g3.status == GoalStatus.SUCCEEDED and g5.succeeded and g3.outcome == "succeeded"
    assert feedback3 == [{"sequence": [0, 1, 1]}, {"sequence": [0, 1, 1, 2]}]
    assert g3.last_feedback == {"sequence": [0, 1, 1, 2]}
    assert g5.feedback_count == 0  # asked for none
    assert srv.received == 2 and srv.failures == 0 and not srv.goals


async def test_cancel_reaches_the_client_provider(pair: tuple[BridgeClient, BridgeClient]) -> None:
    provider, caller = pair

    running: list[Any] = []

    async def wait_for_cancel(goal: Any) -> dict[str, Any]:
        running.append(goal)
        await goal.cancelled.wait()
        goal.status = GoalStatus.CANCELED
        return {"sequence": [0]}

    provider.node("fib").advertise_action(ACTION, "example_interfaces/action/Fibonacci", wait_for_cancel)
    await until_listed(caller, ACTION)
    goal = caller.node("ui").send_action_goal(ACTION, "example_interfaces/action/Fibonacci", {"order": 9})
    await until(lambda: running, what="the goal running at the provider")
    goal.cancel()
    assert goal.outcome == "canceling"
    assert await goal.result(timeout=5) == {"sequence": [0]}
    assert goal.status == GoalStatus.CANCELED and goal.outcome == "canceled"


async def test_a_failing_handler_aborts_the_callers_goal(pair: tuple[BridgeClient, BridgeClient]) -> None:
    provider, caller = pair
    srv = provider.node("fib").advertise_action(ACTION, "example_interfaces/action/Fibonacci",
                                                lambda goal: {}["boom"])
    await until_listed(caller, ACTION)
    goal = caller.node("ui").send_action_goal(ACTION, "example_interfaces/action/Fibonacci", {"order": 2})
    assert await goal.result(timeout=5) == {"sequence": []}
    assert goal.status == GoalStatus.ABORTED and srv.failures == 1
    assert goal.outcome == "aborted" and GoalStatus(goal.status).word == "aborted"


async def test_unadvertise_aborts_goals_and_unlists(pair: tuple[BridgeClient, BridgeClient]) -> None:
    provider, caller = pair
    never, running = asyncio.Event(), []

    async def hang(goal: Any) -> dict[str, Any]:
        running.append(goal)
        await never.wait()
        return {}

    node = provider.node("fib")
    node.advertise_action(ACTION, "example_interfaces/action/Fibonacci", hang)
    await until_listed(caller, ACTION)
    goal = caller.node("ui").send_action_goal(ACTION, "example_interfaces/action/Fibonacci", {"order": 2})
    await until(lambda: running, what="the goal running at the provider")
    node.close()
    await goal.result(timeout=5)
    assert goal.status == GoalStatus.ABORTED
    assert ACTION not in await caller.rosapi.action_servers()


async def test_our_provider_speaks_the_upstream_frames(sim_ros2: SimServer, pair: tuple[BridgeClient, BridgeClient]) -> None:
    """Our client as the action server, a raw caller: the frames the caller sees are the upstream ones."""
    provider, _ = pair

    async def fibonacci(goal: Any) -> dict[str, Any]:
        sequence = [0, 1]
        for i in range(1, goal.args["order"]):
            sequence.append(sequence[i] + sequence[i - 1])
            goal.publish_feedback({"sequence": list(sequence)})
        return {"sequence": sequence}

    provider.node("fib").advertise_action(ACTION, "example_interfaces/Fibonacci", fibonacci)
    await until_listed(provider, ACTION)
    steps = [
        {"client": "B", "send": {"op": "send_action_goal", "action": ACTION, "action_type": "example_interfaces/Fibonacci",
                                 "args": {"order": 5}, "feedback": True}},
        *[{"client": "B", "expect": {"op": "action_feedback", "action": ACTION, "values": {"sequence": seq}}}
          for seq in ([0, 1, 1], [0, 1, 1, 2], [0, 1, 1, 2, 3], [0, 1, 1, 2, 3, 5])],
        {"client": "B", "expect": {"op": "action_result", "action": ACTION, "values": {"sequence": [0, 1, 1, 2, 3, 5]},
                                   "status": 4, "result": True}},
    ]
    await replay(sim_ros2.url, steps)


async def test_our_caller_against_a_raw_provider(sim_ros2: SimServer, pair: tuple[BridgeClient, BridgeClient]) -> None:
    """A raw advertiser (the upstream frames), our client as the caller."""
    _, caller = pair
    async with websockets.connect(sim_ros2.url) as ws:
        await ws.send(json.dumps({"op": "advertise_action", "action": ACTION, "type": "example_interfaces/Fibonacci"}))
        await until_listed(caller, ACTION)
        feedback: list[dict[str, Any]] = []
        goal = caller.node("ui").send_action_goal(ACTION, "example_interfaces/action/Fibonacci", {"order": 5},
                                                  feedback.append)
        request = json.loads(await asyncio.wait_for(ws.recv(), 5))
        assert request["op"] == "send_action_goal" and request["args"] == {"order": 5}
        await ws.send(json.dumps({"op": "action_feedback", "action": ACTION, "id": request["id"],
                                  "values": {"sequence": [0, 1, 1, 2]}}))
        await ws.send(json.dumps({"op": "action_result", "action": ACTION, "id": request["id"], "status": 4,
                                  "result": True, "values": {"sequence": [0, 1, 1, 2, 3, 5]}}))
        assert await goal.result(timeout=5) == {"sequence": [0, 1, 1, 2, 3, 5]}
    assert feedback == [{"sequence": [0, 1, 1, 2]}] and goal.succeeded


async def test_builtin_fibonacci_with_our_client(pair: tuple[BridgeClient, BridgeClient]) -> None:
    _, caller = pair
    feedback: list[dict[str, Any]] = []
    goal = caller.node("ui").send_action_goal("/fibonacci", "action_tutorials_interfaces/action/Fibonacci",
                                              {"order": 5}, feedback.append)
    assert await goal.result(timeout=10) == {"sequence": [0, 1, 1, 2, 3, 5]}
    assert [f["partial_sequence"] for f in feedback] == [[0, 1, 1], [0, 1, 1, 2], [0, 1, 1, 2, 3], [0, 1, 1, 2, 3, 5]]


async def test_wrong_action_type_fails_clearly(pair: tuple[BridgeClient, BridgeClient]) -> None:
    from rcon_core.bridge import ActionError

    _, caller = pair
    goal = caller.node("ui").send_action_goal("/fibonacci", "example_interfaces/action/Fibonacci", {"order": 2})
    with pytest.raises(ActionError, match="serves action_tutorials_interfaces/action/Fibonacci"):
        await goal.result(timeout=5)
    assert goal.outcome == "failed"


async def test_services_and_subscribers_with_our_client(sim_ros2: SimServer, pair: tuple[BridgeClient, BridgeClient]) -> None:
    """advertise_service with two concurrent calls, two subscribers, a latched (transient local) topic."""
    a, b = pair
    a.node("srv").advertise_service("/test_service", "std_srvs/srv/SetBool",
                                    lambda req: {"success": True, "message": f"Hello {req['data']}"})
    await until(lambda: "/test_service" in sim_ros2.services)
    r1, r2 = await asyncio.gather(b.call_service("/test_service", {"data": True}),
                                  b.call_service("/test_service", {"data": False}))
    assert (r1, r2) == ({"success": True, "message": "Hello True"}, {"success": True, "message": "Hello False"})

    got_a: list[dict[str, Any]] = []
    got_b: list[dict[str, Any]] = []
    a.node("sub").subscribe("/a_topic", got_a.append, type="std_msgs/msg/String")
    b.node("sub").subscribe("/a_topic", got_b.append, type="std_msgs/msg/String")
    await until(lambda: sim_ros2.topic_subscriber_count("/a_topic") == 2)
    pub = a.node("pub").advertise("/a_topic", "std_msgs/msg/String", latch=True)
    pub.publish({"data": "hello"})
    await until(lambda: got_a and got_b)
    assert got_a == got_b == [{"data": "hello"}]
    late = BridgeClient(sim_ros2.url, call_timeout=5)
    await late.connect(timeout=5)
    try:
        box: list[dict[str, Any]] = []
        late.node("late").subscribe("/a_topic", box.append)
        await until(lambda: box)
    finally:
        await late.close()
    assert box == [{"data": "hello"}]
