"""The rosbridge ``Session`` as a pure state machine (issue 24.7): the safety rules, table-driven, fed from the
recordings of real rosbridge_suite servers, with no socket, no loop and no sleeping.

Frames go in through the session's methods and ``handle``; what it would write is read from its outbox
(``session.take(now)``); time is a ``ManualClock``.  The last tests hold the rule that ``session.py`` and the
modules it uses import no asyncio.
"""

from __future__ import annotations

import ast
import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import orjson
import pytest
from replay_server import ROS1, ROS2, load

from rcon_core.bridge.errors import ConnectionLostError, ServiceError, ServiceTimeoutError
from rcon_core.bridge.inbound import BadFrames
from rcon_core.bridge.nodes import Node
from rcon_core.bridge.session import DOWN, KEPT, Outgoing, Session
from rcon_core.bridge.shell import SessionShell
from rcon_core.bridge.stats import BridgeStats
from rcon_core.testing import ManualClock

BRIDGE = Path(__file__).resolve().parent.parent / "rcon_core" / "bridge"


class Robot:
    """What a session needs of its host and the nodes of their client, without any connection."""

    url = "ws://robot.test:9090"
    registry = None
    rosapi = None
    call_timeout = 1.0

    def __init__(self, ros_version: int | None = None) -> None:
        self.ros_version = ros_version
        self.stats = BridgeStats()
        self.clock = ManualClock()
        self.spawned: list[Any] = []
        self.session = Session(self, BadFrames(self.url, self.stats), clock=self.clock,
                               schedule=self.clock.call_later)
        SessionShell.build_parts(self.session, self, self.spawned.append)

    def node(self, label: str) -> Node:
        node = self.session.nodes[label] = Node(self, label)  # type: ignore[arg-type]
        return node

    def frames(self) -> list[dict[str, Any]]:
        """What the session would write now, parsed (the outbox is emptied)."""
        return [orjson.loads(out.data) for out in self.session.take(self.clock())]


def sent(recording: str, name: str, op: str) -> list[dict[str, Any]]:
    """The frames of ``op`` the recorded client sent, in order."""
    return [line["sent"] for line in load(name, recording)
            if isinstance(line.get("sent"), dict) and line["sent"].get("op") == op]


def at(recording: str, name: str, n: int) -> dict[str, Any]:
    """Line ``n`` (1-based, as the docstrings cite ``file.jsonl:N``) of a recording."""
    return load(name, recording)[n - 1]


def strip(frame: dict[str, Any], *keys: str) -> dict[str, Any]:
    return {k: v for k, v in frame.items() if k not in keys}


# ====================================================================== restore order after a reconnect

RESTORE = [  # (recording, file): the topics its client subscribed and advertised on its first connections
    (ROS1, "reconnect.jsonl"),
    (ROS2, "reconnect.jsonl"),
    (ROS1, "client_publish.jsonl"),
    (ROS2, "client_publish.jsonl"),
]


@pytest.mark.parametrize(("recording", "name"), RESTORE)
def test_restore_after_reconnect_resends_everything_in_order(recording: str, name: str) -> None:
    """rosbridge forgets everything with the connection (``reconnect.jsonl:8``): after every (re)connect the
    session sends set_level, every advertisement (a latched value kept while down right after its own),
    every service, every action, then every subscription -- each as the recorded client sent it."""
    subs = {f["topic"]: f for f in sent(recording, name, "subscribe")}
    advs = {f["topic"]: f for f in sent(recording, name, "advertise")}
    assert subs or advs, f"{recording}/{name} has nothing to restore"
    robot = Robot()
    session = robot.session
    node = robot.node("ui")
    session.set_level("warning")
    for topic, f in subs.items():
        node.subscribe(topic, lambda m: None, type=f.get("type"))
    pubs = {topic: node.advertise(topic, f["type"], latch=bool(f.get("latch"))) for topic, f in advs.items()}
    node.advertise_service("/ui/reset", "std_srvs/Empty", lambda req: {})
    node.advertise_action("/ui/fib", "example_interfaces/action/Fibonacci", lambda goal: {})
    assert robot.frames() == [], "nothing is written before a connection is attached"

    for conn in (1, 2, 3):
        latched = [t for t, f in advs.items() if f.get("latch")]
        for t in latched:  # published while down: kept, latest wins
            assert pubs[t].publish({"data": f"old {conn}"}) is True
            assert pubs[t].publish({"data": f"latest {conn}"}) is True
        session.attached()
        frames = robot.frames()
        ops = [f["op"] for f in frames]
        want = (["set_level"] + [x for t in advs for x in (["advertise", "publish"] if t in latched else ["advertise"])]
                + ["advertise_service", "advertise_action"] + ["subscribe"] * len(subs))
        assert ops == want, f"connection {conn}"
        assert frames[0] == {"op": "set_level", "level": "warning"}
        restored = [f for f in frames if f["op"] == "advertise"]
        for f, rec in zip(restored, advs.values(), strict=True):
            assert strip(f, "id", "queue_size", "latch") == strip(rec, "id", "queue_size", "latch")
            assert f["latch"] is bool(rec.get("latch"))
        for t in latched:  # the latest value only, right after its advertisement, "latch": true (:26-30)
            i = next(i for i, f in enumerate(frames) if f["op"] == "advertise" and f["topic"] == t)
            assert frames[i + 1] == {"op": "publish", "topic": t, "msg": {"data": f"latest {conn}"}, "latch": True}
        resubscribed = [f for f in frames if f["op"] == "subscribe"]
        for f, (topic, rec) in zip(resubscribed, subs.items(), strict=True):
            assert f["topic"] == topic and f.get("type") == rec.get("type")
        assert len({f["id"] for f in resubscribed}) == len(resubscribed)
        session.detached()
        assert robot.frames() == []


# ====================================================================== latched value held; others dropped

LATCH = [  # (recording, advertise line, publish line): a latched topic as the recorded client used it
    (ROS1, 26, 28),
    (ROS2, 53, 54),
]


@pytest.mark.parametrize(("recording", "adv_line", "pub_line"), LATCH)
def test_latched_value_held_while_down_and_others_dropped(recording: str, adv_line: int, pub_line: int) -> None:
    adv = at(recording, "client_publish.jsonl", adv_line)["sent"]
    rec = at(recording, "client_publish.jsonl", pub_line)["sent"]
    cmd_adv = sent(recording, "client_publish.jsonl", "advertise")[0]  # a command topic (cmd_vel)
    cmd_msg = next(f["msg"] for f in sent(recording, "client_publish.jsonl", "publish")
                   if f["topic"] == cmd_adv["topic"] and isinstance(f.get("msg"), dict))
    robot = Robot()
    session, node = robot.session, robot.node("ui")
    latched = node.advertise(adv["topic"], adv["type"], latch=True)
    cmd = node.advertise(cmd_adv["topic"], cmd_adv["type"])
    table = [  # (publisher, message, the session's decision while down)
        (latched, {"data": "first"}, KEPT),
        (cmd, cmd_msg, DOWN),
        (latched, rec["msg"], KEPT),
        (cmd, cmd_msg, DOWN),
    ]
    for pub, msg, want in table:
        assert session.command(pub, msg, robot.clock()) is want
    assert (cmd.dropped, cmd.sent, robot.stats.dropped_while_down) == (2, 0, 2)
    assert (latched.dropped, latched.sent) == (0, 0)
    session.attached()
    frames = robot.frames()
    mine = [f for f in frames if f.get("topic") == adv["topic"]]
    assert [f["op"] for f in mine] == ["advertise", "publish"]
    assert mine[1] == {"op": "publish", "topic": adv["topic"], "msg": rec["msg"], "latch": True}  # the latest only
    assert not [f for f in frames if f["op"] == "publish" and f["topic"] == cmd_adv["topic"]], \
        "a command published while down is never delivered later"
    session.detached()
    session.attached()
    assert [f["op"] for f in robot.frames() if f.get("topic") == adv["topic"]] == ["advertise"], \
        "a held value is sent once, not after every reconnect"


# ====================================================================== stale command dropped

STALE = [  # (max_age, seconds before the shell takes it, written?)
    (0.25, 0.0, True),
    (0.25, 0.2, True),
    (0.25, 0.25, True),
    (0.25, 0.26, False),
    (0.25, 3.0, False),
    (1.0, 0.5, True),
    (None, 60.0, True),  # no freshness limit (a latched topic by default)
]


@pytest.mark.parametrize(("max_age", "wait", "written"), STALE)
@pytest.mark.parametrize("recording", [ROS1, ROS2])
def test_stale_command_is_dropped_not_delivered(recording: str, max_age: float | None, wait: float,
                                                written: bool) -> None:
    """A command carries ``now + max_age`` as its deadline; past it, it is dropped and counted, never written."""
    cmd_adv = sent(recording, "client_publish.jsonl", "advertise")[0]
    msgs = [f["msg"] for f in sent(recording, "client_publish.jsonl", "publish")
            if f["topic"] == cmd_adv["topic"] and isinstance(f.get("msg"), dict)][:3]
    robot = Robot()
    session, node = robot.session, robot.node("teleop")
    pub = node.advertise(cmd_adv["topic"], cmd_adv["type"], max_age=max_age)
    session.attached()
    assert [f["op"] for f in robot.frames()] == ["advertise"]
    t0 = robot.clock()
    decided = session.command(pub, msgs[0], t0)
    assert isinstance(decided, Outgoing)
    assert decided.deadline == (None if max_age is None else t0 + max_age)
    for msg in msgs:
        assert pub.publish(msg) is True  # handed to the outbox with its deadline
    robot.clock.advance(wait)
    frames = robot.frames()
    if written:
        assert frames == [{"op": "publish", "topic": cmd_adv["topic"], "msg": m} for m in msgs]
        assert (pub.sent, pub.dropped, robot.stats.stale_dropped) == (3, 0, 0)
    else:
        assert frames == []
        assert (pub.sent, pub.dropped, robot.stats.stale_dropped) == (0, 3, 3)


@pytest.mark.parametrize(("refused", "result", "sent_", "dropped"), [(False, True, 1, 0), (True, False, 0, 1)])
def test_a_command_the_link_refuses_at_its_limit_is_counted_dropped(refused: bool, result: bool, sent_: int,
                                                                   dropped: int) -> None:
    """The link's ``send_by`` (lent by the shell) says False when the link is degraded or stalling: publish
    returns False, counted."""
    robot = Robot()
    session, node = robot.session, robot.node("teleop")
    pub = node.advertise("/cmd_vel", "geometry_msgs/Twist")
    session.attached()
    robot.frames()
    handed: list[tuple[bytes, Any, float, float]] = []
    session.send_by = lambda data, p, deadline, now: handed.append((data, p, deadline, now)) or not refused
    assert pub.publish({"linear": {"x": 0.5}}) is result
    assert len(handed) == 1 and handed[0][1:] == (pub, robot.clock() + 0.25, robot.clock())
    assert orjson.loads(handed[0][0])["topic"] == "/cmd_vel"
    assert (pub.sent, pub.dropped, robot.stats.stale_dropped) == (sent_, dropped, dropped)


def test_frames_left_when_the_link_drops_are_dropped_and_counted() -> None:
    robot = Robot()
    session, node = robot.session, robot.node("ui")
    session.attached()
    robot.frames()
    node.subscribe("/chatter", lambda m: None, type="std_msgs/String")
    assert len(session.outbox) == 1
    session.detached()
    assert robot.frames() == [] and robot.stats.dropped_on_disconnect == 1


# ====================================================================== subscription option merging

def _options(frame: dict[str, Any]) -> dict[str, Any]:
    keys = ("type", "throttle_rate", "queue_length", "fragment_size", "compression")
    return {k: frame[k] for k in keys if frame.get(k) is not None}


def _valid(opts: dict[str, Any]) -> bool:
    """Options a node may ask for (the recordings also probe the server with malformed ones)."""
    ints = [opts.get("throttle_rate", 0), opts.get("queue_length", 0), opts.get("fragment_size", 1)]
    return all(isinstance(v, int) and not isinstance(v, bool) and v >= 0 for v in ints) \
        and opts.get("fragment_size", 1) > 0 and isinstance(opts.get("type", ""), str)


MERGE_FILES = [(ROS1, "subscribe_options.jsonl"), (ROS2, "subscribe_options.jsonl")]


@pytest.mark.parametrize(("recording", "name"), MERGE_FILES)
def test_subscription_options_merge_into_one_server_subscription(recording: str, name: str) -> None:
    """Two consumers of one topic share one server-side subscription whose options serve both: the lowest
    throttle_rate, the longest queue_length, the smallest fragment_size, the richest compression; a change
    subscribes anew, then unsubscribes the old id (no gap); the last one leaving unsubscribes."""
    frames = sent(recording, name, "subscribe")
    type_name = frames[0]["type"]  # every set is tried on one topic of this type
    recorded = [strip(_options(f), "type") for f in frames if f.get("compression", "none") in ("none", "png")]
    recorded = [o for i, o in enumerate(recorded) if _valid(o) and o not in recorded[:i]]
    assert len(recorded) >= 4, "the recording holds several option sets"
    recorded = [{**o, "type": type_name} for o in recorded] + [{"queue_length": 1}]  # one without a type
    rank = {"png": 2, "none": 3}
    for a in recorded:
        for b in recorded:
            robot = Robot()
            session, node = robot.session, robot.node("ui")
            session.attached()
            first = node.subscribe("/chatter", lambda m: None, **a)
            (f1,) = robot.frames()
            assert _options(f1) == {"throttle_rate": 0, "queue_length": 0, "compression": "none", **a}
            second = node.subscribe("/chatter", lambda m: None, **b)
            merged: dict[str, Any] = {
                "throttle_rate": min(a.get("throttle_rate", 0), b.get("throttle_rate", 0)),
                "queue_length": max(a.get("queue_length", 0), b.get("queue_length", 0)),
                "compression": min(a.get("compression", "none"), b.get("compression", "none"), key=rank.__getitem__),
                "type": a.get("type") or b.get("type"),
            }
            merged = {k: v for k, v in merged.items() if v is not None}
            frags = [x["fragment_size"] for x in (a, b) if x.get("fragment_size")]
            if frags:
                merged["fragment_size"] = min(frags)
            frames = robot.frames()
            if merged == _options(f1):
                assert frames == [], "options unchanged: no new subscription"
                current = f1["id"]
            else:
                assert [f["op"] for f in frames] == ["subscribe", "unsubscribe"]
                assert _options(frames[0]) == merged
                assert frames[1] == {"op": "unsubscribe", "id": f1["id"], "topic": "/chatter"}
                current = frames[0]["id"]
            second.unsubscribe()
            back = robot.frames()
            if back:
                assert _options(back[0]) == _options(f1) and back[1]["id"] == current
                current = back[0]["id"]
            first.unsubscribe()
            assert robot.frames() == [{"op": "unsubscribe", "id": current, "topic": "/chatter"}]
            assert "/chatter" not in session.topics


# ====================================================================== service calls as data

CALLS = [  # (recording, file, line): a recorded call and its answer
    (ROS1, "services.jsonl", 1), (ROS1, "services.jsonl", 2), (ROS1, "services.jsonl", 9),
    (ROS1, "services.jsonl", 10), (ROS2, "services.jsonl", 1), (ROS2, "services.jsonl", 2),
]


@pytest.mark.parametrize(("recording", "name", "line"), CALLS)
def test_a_recorded_answer_settles_its_call(recording: str, name: str, line: int) -> None:
    rec = at(recording, name, line)
    req, answer = rec["sent"], rec["received"]
    robot = Robot()
    session = robot.session
    session.attached()
    got: list[tuple[Any, BaseException | None]] = []
    call = session.open_call(req["service"], req.get("args"), done=lambda v, e: got.append((v, e)))
    assert session.start_call(call) is True
    (frame,) = robot.frames()
    assert (frame["service"], frame.get("args")) == (req["service"], req.get("args"))
    session.handle({**answer, "id": frame["id"]})
    assert len(got) == 1 and not session.pending
    values, error = got[0]
    if answer.get("result", True) is False:
        assert isinstance(error, ServiceError) and error.message == answer["values"]
    else:
        assert error is None and values == answer["values"]


def test_a_timeout_names_the_earlier_unanswered_call_and_a_late_answer_is_quiet() -> None:
    robot = Robot(ros_version=2)
    session = robot.session
    session.attached()
    told: list[Any] = []
    session.held.add_listener(told.append)
    slow = session.open_call("/slow", {})
    quick = session.open_call("/quick", {})
    for c in (slow, quick):
        session.start_call(c)
    robot.clock.advance(0.6)  # the held watch's timer runs on the injected clock: commands held
    assert told and told[-1].service == "/slow"
    err = session.timed_out(quick, 1.0)
    assert isinstance(err, ServiceTimeoutError) and "(/slow) is still unanswered" in str(err)
    session.timed_out(slow, 1.0)
    assert not session.pending and list(session.unanswered.values()) == ["/quick", "/slow"]
    bad = robot.stats.bad_frames
    (f1, f2) = robot.frames()
    for f in (f1, f2):  # late answers: dropped quietly, and the server is free again
        session.handle({"op": "service_response", "id": f["id"], "service": f["service"], "values": {}, "result": True})
    assert robot.stats.bad_frames == bad and told[-1] is None and not session.unanswered


def test_calls_waiting_when_the_link_drops_fail() -> None:
    robot = Robot()
    session = robot.session
    session.attached()
    got: list[Any] = []
    session.start_call(session.open_call("/rec/trigger", {}, done=lambda v, e: got.append(e)))
    session.detached()
    assert len(got) == 1 and isinstance(got[0], ConnectionLostError) and not session.pending


def test_a_status_error_fails_the_call_it_names() -> None:
    """No recording holds a server's error ``status`` naming a call (the servers recorded answer with a
    ``service_response``), so the frame is rosbridge's ``status`` op as its protocol states it."""
    req = at(ROS1, "services.jsonl", 5)["sent"]
    robot = Robot()
    session = robot.session
    session.attached()
    got: list[Any] = []
    call = session.open_call(req["service"], req.get("args"), done=lambda v, e: got.append(e))
    session.start_call(call)
    session.handle({"op": "status", "level": "error", "msg": "the service handler died", "id": call.id})
    assert isinstance(got[0], ServiceError) and got[0].message == "the service handler died" and not session.pending


# ====================================================================== the rule: no asyncio in the session

PURE_CHECK = r"""
import sys, types, importlib, pathlib
sys.modules["asyncio"] = None  # any "import asyncio" now fails
bridge = pathlib.Path(sys.argv[1])
pkg = types.ModuleType("rcon_core.bridge")  # the package without its __init__ (which imports the client)
pkg.__path__ = [str(bridge)]
import rcon_core
sys.modules["rcon_core.bridge"] = pkg
importlib.import_module("rcon_core.bridge.session")
import json
print(json.dumps(sorted(m for m in sys.modules if m.startswith("rcon_core.bridge."))))
"""


def test_session_and_the_modules_it_uses_import_no_asyncio() -> None:
    """Importing ``session.py`` with asyncio made unimportable works: neither it nor any module it imports
    at run time needs asyncio (the parts that do are the shell's: ``shell.py``)."""
    out = subprocess.run([sys.executable, "-c", PURE_CHECK, str(BRIDGE)], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    loaded = json.loads(out.stdout.strip().splitlines()[-1])
    assert "rcon_core.bridge.session" in loaded
    for shell_side in ("client", "shell", "goals", "services", "action_server", "subscribe", "linkbase", "inbound"):
        assert f"rcon_core.bridge.{shell_side}" not in loaded


def test_session_source_makes_no_future_task_or_timer() -> None:
    """No ``async def``, no ``await``, and no name of asyncio's in the session's own source."""
    tree = ast.parse((BRIDGE / "session.py").read_text(encoding="utf-8"))
    found = [type(n).__name__ for n in ast.walk(tree) if isinstance(n, ast.AsyncFunctionDef | ast.Await)]
    found += [n.id for n in ast.walk(tree) if isinstance(n, ast.Name) and n.id == "asyncio"]
    found += [n.attr for n in ast.walk(tree) if isinstance(n, ast.Attribute)
              and n.attr in ("create_future", "ensure_future", "create_task", "get_running_loop", "call_later")]
    assert found == []
