"""A robot link marked view-only sends nothing that could change the robot (``rcon_core.bridge.guard``).

Found by a person (issue 21.1): with the robot marked View only in a locked app, the Params tab still set
``/kingfisher:max_speed`` 2.0 -> 5.0 and the robot took it, because view-only lived only in the widgets'
ports. Now the rule is on the link: this module reads every op name the bridge can write from its source
(a new op must be classified in ``guard.py`` or this fails), then, for each op that could change the
robot, drives the public API to make it three ways against the sim, which counts the ops each connection
sent: an ordinary link (the op reaches the sim: the scenario is real), a link marked view-only from the
start, and a link marked view-only while it had things offered (both: 0 such ops reach the sim).
"""

from __future__ import annotations

import asyncio
import re
from collections import Counter
from collections.abc import Awaitable, Callable
from pathlib import Path
from typing import Any

import pytest

import rcon_core.bridge
from rcon_core.bridge import BridgeClient, ViewOnlyError
from rcon_core.bridge import guard as G
from rcon_core.testing import until

REASON = "robot “Boat” at ws://test is view-only"
TWIST = "geometry_msgs/Twist"
FIBONACCI = "action_tutorials_interfaces/action/Fibonacci"
STOP = {"linear": {"x": 0.0, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.0}}


def bridge_ops() -> set[str]:
    """Every op name written as a frame literal anywhere in ``rcon_core/bridge`` (dicts and the publish
    frame's pre-encoded head)."""
    src = "\n".join(p.read_text(encoding="utf-8") for p in Path(rcon_core.bridge.__file__).parent.glob("*.py"))
    return set(re.findall(r'"op":\s*"(\w+)"', src)) | set(re.findall(r"""b'\{"op":"(\w+)\"""", src))


def test_every_op_the_bridge_writes_is_classified_by_the_guard():
    found = bridge_ops()
    assert len(found) >= 17  # the regexes still find the ops (publish's head included)
    assert "publish" in found and "call_service" in found
    assert found == G.OUTGOING_OPS, f"classify in guard.py: {sorted(found ^ G.OUTGOING_OPS)}"
    assert set(SCENARIOS) == G.CHANGE_OPS | G.WITHDRAW_OPS, "every op that could change the robot has a scenario"


# ------------------------------------------------------------------------------------ the scenarios
# Each scenario is (setup, attempt): setup runs first (on an ordinary link, or on a view-only one), then the
# attempt, which makes the op on an ordinary link. Both run through the public API only.
Step = Callable[[BridgeClient, dict[str, Any]], Awaitable[None]]


async def nothing(_c: BridgeClient, _s: dict[str, Any]) -> None:
    return None


async def advertise_cmd(c: BridgeClient, s: dict[str, Any]) -> None:
    s["pub"] = c.node("pad").advertise("/cmd_vel", TWIST)


async def publish_cmd(_c: BridgeClient, s: dict[str, Any]) -> None:
    s["pub"].publish(STOP)


async def advertise_new_topic(c: BridgeClient, _s: dict[str, Any]) -> None:
    c.node("new-topic").advertise("/rogue", "std_msgs/String")


async def unadvertise_cmd(_c: BridgeClient, s: dict[str, Any]) -> None:
    s["pub"].unadvertise()


async def call_services(c: BridgeClient, _s: dict[str, Any]) -> None:
    """A service from the side panel, a parameter write and delete (the Params tab), a ROS 2 style set."""
    node = c.node("caller")
    for call in (lambda: node.call_service("/lights/set", {"data": True}, timeout=3),
                 lambda: c.params.set("/kingfisher/max_speed", 5.0, verify=False),
                 lambda: c.params.delete("/kingfisher/max_speed"),
                 lambda: node.call_service("/kingfisher/set_parameters", {"parameters": []}, timeout=3)):
        try:
            await call()
        except ViewOnlyError:
            raise
        except Exception:  # the sim may not serve every one of them: what counts is what was sent
            pass


def serve(c: BridgeClient, s: dict[str, Any]) -> None:
    s["srv"] = c.node("server").advertise_service("/rogue/serve", "std_srvs/Trigger",
                                                  lambda _req: {"success": True, "message": "done"})


async def advertise_service(c: BridgeClient, s: dict[str, Any]) -> None:
    serve(c, s)


async def unadvertise_service(_c: BridgeClient, s: dict[str, Any]) -> None:
    s["srv"].unadvertise()


async def answer_a_call(c: BridgeClient, s: dict[str, Any]) -> None:
    """The robot calls the service this link provides (a frame as the server sends it)."""
    c.session.handle({"op": "call_service", "service": "/rogue/serve", "id": "call:1", "args": {}})
    await until(lambda: s["srv"].calls >= 1, what="the handler ran")


async def handle_goal(goal: Any) -> dict[str, Any]:
    goal.publish_feedback({"partial_sequence": [0, 1]})
    return {"sequence": [0, 1, 1]}


def provide(c: BridgeClient, s: dict[str, Any]) -> None:
    s["act"] = c.node("action-server").advertise_action("/rogue_action", FIBONACCI, handle_goal)


async def advertise_action(c: BridgeClient, s: dict[str, Any]) -> None:
    provide(c, s)


async def unadvertise_action(_c: BridgeClient, s: dict[str, Any]) -> None:
    s["act"].unadvertise()


async def serve_a_goal(c: BridgeClient, s: dict[str, Any]) -> None:
    """The robot sends a goal to the action this link provides: feedback and result go back."""
    c.session.handle({"op": "send_action_goal", "action": "/rogue_action", "id": "action_goal:1",
                      "args": {"order": 2}})
    for _ in range(20):  # the handler's task runs and answers within a few turns of the loop
        await asyncio.sleep(0)


async def send_goal(c: BridgeClient, s: dict[str, Any]) -> None:
    s["goal"] = c.node("navigate").send_action_goal("/fibonacci", FIBONACCI, {"order": 3}, check=False)


async def cancel_goal(_c: BridgeClient, s: dict[str, Any]) -> None:
    s["goal"].cancel()


SCENARIOS: dict[str, tuple[Step, Step]] = {
    "publish": (advertise_cmd, publish_cmd),
    "advertise": (nothing, advertise_new_topic),
    "unadvertise": (advertise_cmd, unadvertise_cmd),
    "call_service": (nothing, call_services),
    "advertise_service": (nothing, advertise_service),
    "unadvertise_service": (advertise_service, unadvertise_service),
    "service_response": (advertise_service, answer_a_call),
    "advertise_action": (nothing, advertise_action),
    "unadvertise_action": (advertise_action, unadvertise_action),
    "action_feedback": (advertise_action, serve_a_goal),
    "action_result": (advertise_action, serve_a_goal),
    "send_action_goal": (nothing, send_goal),
    "cancel_action_goal": (send_goal, cancel_goal),
}


# ------------------------------------------------------------------------------------ the sim's count
def connection_of(sim: Any, client: BridgeClient) -> Any:
    assert client.link is not None and client.link.socket is not None
    port = client.link.socket.getsockname()[1]
    return next(c for c in sim.connections if c.ws.remote_address[1] == port)


def changing(ops: Counter) -> dict[tuple[str, str], int]:
    """The ops in ``ops`` that are not reads (``auth``, ``subscribe``... and read-only rosapi calls)."""
    return {k: n for k, n in ops.items() if n and k[0] not in G.READ_OPS
            and not (k[0] == "call_service" and G.read_only_service(k[1]))}


async def all_received(client: BridgeClient) -> None:
    """Everything the client wrote so far has been counted by the sim: it handles one connection's frames
    in order, so the answer to a read-only call comes after them."""
    await client.call_service("/rosapi/get_time", {}, timeout=5)


async def run(step: Step, client: BridgeClient, state: dict[str, Any], refusals: list[str]) -> None:
    try:
        await step(client, state)
    except ViewOnlyError as exc:
        refusals.append(str(exc))
    except KeyError:  # the setup was refused, so there is nothing to attempt with
        pass


@pytest.mark.parametrize("op", sorted(SCENARIOS))
async def test_a_view_only_link_sends_no_op_that_could_change_the_robot(sim, op):
    setup, attempt = SCENARIOS[op]

    # an ordinary link: the attempt makes the op (so the scenario is a real one)
    async with _client(sim) as ordinary:
        state: dict[str, Any] = {}
        await setup(ordinary, state)
        await all_received(ordinary)
        conn = connection_of(sim, ordinary)
        before = conn.ops_received.copy()
        await attempt(ordinary, state)
        await all_received(ordinary)
        made = conn.ops_received - before
        assert any(k[0] == op for k in made), f"the scenario for {op} sent {dict(made)}"

    # view-only from the start: not one changing op reaches the sim
    async with _client(sim, view_only=True) as monitor:
        state, refusals = {}, []
        await run(setup, monitor, state, refusals)
        await run(attempt, monitor, state, refusals)
        await all_received(monitor)
        assert changing(connection_of(sim, monitor).ops_received) == {}
        assert all(s.endswith(f"{REASON}.") for s in refusals), refusals

    # marked view-only while it had things offered: they are withdrawn, then nothing more is sent
    async with _client(sim) as marked:
        state, refusals = {}, []
        await setup(marked, state)
        await all_received(marked)
        conn = connection_of(sim, marked)
        marked.guard.set_view_only(REASON)
        await all_received(marked)
        withdrawn = conn.ops_received.copy()
        await run(attempt, marked, state, refusals)
        await all_received(marked)
        assert changing(conn.ops_received - withdrawn) == {}
        assert marked.guard.offered == set()  # nobody can publish through it or call what it served
        assert all(s.endswith(f"{REASON}.") for s in refusals), refusals


class _client:
    """``async with _client(sim, view_only=...)``: a client, marked view-only before it connects if asked."""

    def __init__(self, sim: Any, view_only: bool = False) -> None:
        self.client = BridgeClient(sim.url, reconnect=False, call_timeout=5)
        if view_only:
            self.client.guard.set_view_only(REASON)

    async def __aenter__(self) -> BridgeClient:
        await self.client.connect(timeout=10)
        return self.client

    async def __aexit__(self, *exc: object) -> None:
        await self.client.close()


# ------------------------------------------------------------------------------------ what it still does
async def test_a_view_only_link_still_shows_everything_and_names_the_robot_when_it_refuses(sim):
    async with _client(sim, view_only=True) as monitor:
        got: list[dict[str, Any]] = []
        monitor.node("label").subscribe("/battery", got.append)
        topics = await monitor.rosapi.topics()
        assert "/battery" in topics
        await until(lambda: got, what="a battery message")
        with pytest.raises(ViewOnlyError) as refused:
            await monitor.params.set("/kingfisher/max_speed", 5.0)
        assert str(refused.value) == f"Setting parameter /kingfisher/max_speed was not sent: {REASON}."
        pub = monitor.node("pad").advertise("/cmd_vel", TWIST)
        with pytest.raises(ViewOnlyError, match="Publishing on /cmd_vel was not sent: robot “Boat”"):
            pub.publish(STOP)
        assert isinstance(refused.value, PermissionError)
        assert monitor.guard.refused == 3  # the set, the advertisement withheld, the publish


async def test_lifting_the_mark_offers_again_what_the_link_keeps(sim):
    async with _client(sim) as c:
        state: dict[str, Any] = {}
        await advertise_cmd(c, state)
        await advertise_service(c, state)
        await all_received(c)
        c.guard.set_view_only(REASON)
        await all_received(c)
        assert sim.topic_subscriber_count("/cmd_vel") >= 0 and c.guard.offered == set()
        with pytest.raises(ViewOnlyError):
            state["pub"].publish(STOP)
        c.guard.set_view_only(None)
        await all_received(c)
        assert c.guard.offered == {("advertise", "/cmd_vel"), ("advertise_service", "/rogue/serve")}
        conn = connection_of(sim, c)
        before = conn.ops_received[("publish", "/cmd_vel")]
        assert state["pub"].publish(STOP)
        await all_received(c)
        assert conn.ops_received[("publish", "/cmd_vel")] == before + 1


async def test_a_mark_set_from_another_thread_takes_effect_at_once(sim):
    async with _client(sim) as c:
        pub = c.node("pad").advertise("/cmd_vel", TWIST)
        await all_received(c)
        await asyncio.to_thread(c.guard.set_view_only, REASON)
        with pytest.raises(ViewOnlyError):  # before the loop ran the withdrawal
            pub.publish(STOP)
        await all_received(c)
        assert ("advertise", "/cmd_vel") not in c.guard.offered


def test_a_mark_needs_its_reason_in_words():
    guard = G.LinkGuard("ws://x")
    with pytest.raises(ValueError, match="reason"):
        guard.set_view_only("  ")


async def test_a_call_waiting_for_the_link_when_the_mark_is_set_is_refused_not_sent(sim):
    client = BridgeClient(sim.url, reconnect=True, call_timeout=5)
    connecting = asyncio.ensure_future(client.connect(timeout=10))
    try:
        await asyncio.sleep(0)
        call = asyncio.ensure_future(client.call_service("/lights/set", {"data": True}))
        await asyncio.sleep(0)  # checked (not view-only yet), now waiting for the link
        assert not call.done()
        client.guard.set_view_only(REASON)
        await connecting
        with pytest.raises(ViewOnlyError, match="The call to /lights/set was not sent: robot “Boat”"):
            await asyncio.wait_for(call, 4)  # at once, not after the call's timeout
        await all_received(client)
        assert changing(connection_of(sim, client).ops_received) == {}
    finally:
        await client.close()


async def test_a_view_only_ros2_link_reads_parameters_through_the_nodes_but_never_sets_one(sim_ros2):
    """On ROS 2 ``client.params`` reads through each node's ``list_parameters``/``get_parameters`` (never
    rosapi's parameter calls, which kill rosapi 2.1.0): a view-only robot's Parameters panel still shows its
    parameters, and ``set_parameters`` stays refused before it is written."""
    async with _client(sim_ros2, view_only=True) as monitor:
        assert "/kingfisher:max_speed" in (await monitor.params.by_owner())["/kingfisher"]
        assert await monitor.params.get("/kingfisher:max_speed") == 2.0
        with pytest.raises(ViewOnlyError, match="robot “Boat”"):
            await monitor.params.set("/kingfisher:max_speed", 5.0)
        await all_received(monitor)
        assert not changing(connection_of(sim_ros2, monitor).ops_received)
    async with _client(sim_ros2) as operator:
        assert await operator.params.get("/kingfisher:max_speed") == 2.0  # the robot kept its value


# ------------------------------------------------------------------------------------ the Foxglove link
# The same rule on the second protocol (``rcon_core/foxglove/guard.py``): every op the Foxglove link writes is
# classified, and a view-only Foxglove link gets nothing that changes the robot to the foxglove-sdk peer.

def foxglove_ops() -> set[str]:
    """Every op the Foxglove link writes: the JSON ops in its frame builders and the kinds its session and
    the session's parts (``requests.py``...) pass to the guard (binary frames by the names ``publish`` and
    ``call_service``)."""
    import rcon_core.foxglove

    folder = Path(rcon_core.foxglove.__file__).parent
    wire_src = (folder / "wire.py").read_text(encoding="utf-8")
    builders = wire_src.split("# ====", 2)[-1]  # the client -> server half
    session_src = "\n".join(p.read_text(encoding="utf-8") for p in sorted(folder.glob("*.py")))
    return (set(re.findall(r'"op":\s*"(\w+)"', builders)) | set(re.findall(r'"(\w+)" if subscribe', builders))
            | set(re.findall(r'else "(\w+)"', builders)) | set(re.findall(r'_send\("(\w+)"', session_src))
            | set(re.findall(r'admit_op\("(\w+)"', session_src)))


def test_every_op_the_foxglove_link_writes_is_classified_by_its_guard():
    from rcon_core.foxglove import guard as FG

    found = foxglove_ops()
    assert {"subscribe", "advertise", "setParameters", "publish", "call_service"} <= found
    assert found == FG.OUTGOING_OPS, f"classify in foxglove/guard.py: {sorted(found ^ FG.OUTGOING_OPS)}"


async def test_a_view_only_foxglove_link_sends_nothing_that_changes_the_robot():
    from rcon_core.foxglove import FoxgloveClient
    from rcon_core.foxglove.testing import FoxPeer

    peer = FoxPeer()
    ordinary = FoxgloveClient(peer.url, call_timeout=3)
    marked = FoxgloveClient(peer.url, call_timeout=3)
    marked.guard.set_view_only(REASON)
    try:
        await ordinary.connect(timeout=10)
        await marked.connect(timeout=10)
        # the scenario is real on an ordinary link: each op reaches the peer
        pub = ordinary.node("pad").advertise("/cmd_vel", "geometry_msgs/msg/Twist")
        await until(lambda: peer.advertised)
        pub.publish(STOP)
        await until(lambda: peer.received)
        await ordinary.call_service("/add", {"a": 1, "b": 1})
        await ordinary.params.set("/boat.max_speed", 3.0)
        assert len(peer.calls) == 1
        # marked from the start: refused in words, nothing reaches the peer
        before = (len(peer.advertised), len(peer.received), len(peer.calls))
        node = marked.node("pad")
        held = node.advertise("/cmd_vel2", "geometry_msgs/msg/Twist")  # kept, not offered
        with pytest.raises(ViewOnlyError, match="is view-only"):
            held.publish(STOP)
        with pytest.raises(ViewOnlyError, match="The call to /add was not sent"):
            await marked.call_service("/add", {"a": 1, "b": 1})
        with pytest.raises(ViewOnlyError, match="Setting parameter /boat.max_speed was not sent"):
            await marked.params.set("/boat.max_speed", 9.0)
        assert await marked.params.get("/boat.max_speed") == 3.0  # reads pass
        got: list = []
        node.subscribe("/chatter", got.append)  # subscriptions pass
        await until(lambda: "/chatter" in peer.subscribed)
        # marked while it had a topic offered: the offer is withdrawn
        ordinary.guard.set_view_only(REASON)
        await until(lambda: "/cmd_vel" in peer.unadvertised, what="the withdrawal")
        with pytest.raises(ViewOnlyError):
            pub.publish(STOP)
        for client in (ordinary, marked):  # a round trip on each link after the rest: the peer has all before it
            assert await client.params.get("/boat.max_speed") == 3.0
        assert (len(peer.advertised), len(peer.received), len(peer.calls)) == before
        assert marked.guard.refused >= 3
        # lifting the mark offers the topic again
        ordinary.guard.set_view_only(None)
        await until(lambda: len(peer.advertised) == before[0] + 1, what="offered again")
    finally:
        await ordinary.close()
        await marked.close()
        peer.stop()
