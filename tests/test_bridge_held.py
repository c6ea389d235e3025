"""Commands held behind an unanswered service call (``rcon_core/bridge/held.py``): when a link reports it,
until when, and on which servers. The watch alone on a manual clock (its scheduler too); then a link to the
sim (ROS 2, and ROS 1 where calls run in threads) with a client of its own serving ``/slow``. No Qt."""

from __future__ import annotations

import asyncio

import pytest

from rcon_core.bridge import ServiceTimeoutError
from rcon_core.bridge.held import HOLD_AFTER, Held, HeldWatch
from rcon_core.testing import ManualClock, connected, until


def watch(may_hold=lambda: True):
    """A watch on a manual clock (its ``call_later`` is the scheduler: ``clock.advance`` runs the checks)."""
    clock = ManualClock(0.0)
    w = HeldWatch(clock=clock, schedule=clock.call_later, may_hold=may_hold)
    told: list[Held | None] = []
    w.add_listener(told.append)
    return w, clock, told


def test_a_call_unanswered_past_half_a_second_is_reported_then_its_answer_ends_it():
    w, clock, told = watch()
    w.started("call:1", "/dock")
    clock.advance(HOLD_AFTER - 0.1)
    assert told == [] and w.current is None  # a quick answer is never reported
    clock.advance(0.2)  # the check it arranged when the call was written
    assert told == [Held("/dock", 0.0)]
    assert w.current.sentence() == "commands held: the robot's bridge is still busy with /dock"
    w.answered("call:1")
    assert told[-1] is None and w.current is None


def test_a_quick_call_is_never_reported():
    w, clock, told = watch()
    w.started("call:1", "/rosapi/topics")
    clock.advance(0.05)
    w.answered("call:1")
    clock.advance(5.0)
    assert told == []


def test_the_oldest_call_is_the_one_named_and_a_later_one_takes_over_when_it_is_answered():
    w, clock, told = watch()
    w.started("a", "/slow")
    clock.advance(0.3)
    w.started("b", "/also_slow")
    clock.advance(0.3)
    assert w.current == Held("/slow", 0.0)
    w.answered("a")  # the next one has waited 0.3 s only: nothing held yet...
    assert w.current is None
    clock.advance(0.3)  # ...until it too passes the threshold
    assert w.current == Held("/also_slow", 0.3)
    assert told == [Held("/slow", 0.0), None, Held("/also_slow", 0.3)]


def test_a_call_that_timed_out_on_the_client_still_counts_until_the_server_answers_or_the_link_drops():
    w, clock, told = watch()
    w.started("call:1", "/client/slow")
    clock.advance(30.0)  # the client gave up long ago; rosbridge 2.1.0 has not
    assert w.current == Held("/client/slow", 0.0)
    w.answered("not-a-call-of-ours")  # another id: nothing changes
    assert w.current is not None
    w.reset()  # the link dropped: the server forgot the connection
    assert w.current is None and told == [Held("/client/slow", 0.0), None]


def test_a_ros1_server_runs_calls_in_threads_and_never_holds():
    ros = {"version": None}
    w, clock, told = watch(may_hold=lambda: ros["version"] != 1)
    w.started("call:1", "/dock")
    ros["version"] = 1
    clock.advance(2.0)
    assert told == [] and w.held() is None
    ros["version"] = 2  # not known, or ROS 2: it may hold
    assert w.check() == Held("/dock", 0.0)


def test_a_long_call_on_a_ros1_server_arranges_no_check_after_the_threshold():
    """Found reading the watch: on a server that does not hold (ROS 1) a call unanswered past the threshold
    re-arranged a check every 10 ms for as long as it ran (a 30 s call: 3,000 wake-ups of the bridge loop
    that also times the teleop pad's commands)."""
    w, clock, told = watch(may_hold=lambda: False)
    w.started("call:1", "/navigate")
    clock.advance(HOLD_AFTER + 0.05)  # the check the call arranged has run
    assert told == [] and clock.pending == 0
    w.check()  # any later check (an answer to another call...) arranges nothing either
    assert clock.pending == 0
    w.started("call:2", "/dock")  # a new call arranges its own threshold check, once
    assert clock.pending == 1
    clock.advance(30.0)
    assert told == [] and clock.pending == 0


def test_a_listener_that_fails_does_not_keep_the_others_from_hearing():
    w, clock, told = watch()

    def broken(_held):
        raise RuntimeError("boom")

    w.add_listener(broken)
    heard: list = []
    remove = w.add_listener(heard.append)
    w.started("x", "/s")
    clock.advance(1.0)
    assert heard == [Held("/s", 0.0)] and told == [Held("/s", 0.0)]
    remove()
    w.answered("x")
    assert heard == [Held("/s", 0.0)] and told[-1] is None


def test_the_number_of_calls_kept_is_bounded():
    clock = ManualClock(0.0)
    w = HeldWatch(clock=clock, schedule=clock.call_later, limit=4)
    for i in range(10):
        clock.advance(0.01)
        w.started(i, f"/s{i}")
    clock.advance(1.0)
    assert w.held() == Held("/s6", 0.07)  # the four newest are kept


# ------------------------------------------------------------------------------ on a link, against the sim
def watched_calls(w: HeldWatch) -> dict[str, list]:
    """From now on, the calls ``w`` is told were written (id, service) and answered (id)."""
    calls: dict[str, list] = {"started": [], "answered": []}
    started, answered = w.started, w.answered

    def on_started(call_id, service):
        calls["started"].append((call_id, service))
        started(call_id, service)

    def on_answered(call_id):
        calls["answered"].append(call_id)
        answered(call_id)

    w.started, w.answered = on_started, on_answered  # type: ignore[method-assign]
    return calls


def checked_later(w: HeldWatch, seconds: float) -> Held | None:
    """What ``w`` reports when it checks ``seconds`` from now: a call still unanswered then is held."""
    clock = w.clock
    w.clock = lambda: clock() + seconds
    try:
        return w.check()
    finally:
        w.clock = clock


def unanswered(w: HeldWatch) -> str | None:
    """The service of the oldest call ``w`` has seen written and not answered for more than the threshold,
    whatever the server (``may_hold`` set aside for one synchronous look: no check runs meanwhile)."""
    may_hold = w.may_hold
    w.may_hold = lambda: True
    try:
        held = w.held()
    finally:
        w.may_hold = may_hold
    return held.service if held is not None else None


async def _serve_slow(url: str):
    """A client of its own serving /slow (std_srvs/Trigger), answering when the returned event is set."""
    gate = asyncio.Event()

    async def handle(_req):
        await gate.wait()
        return {"success": True, "message": "late"}

    cm = connected(url, reconnect=False)
    server = await cm.__aenter__()
    server.node("slow").advertise_service("/slow", "std_srvs/Trigger", handle)
    return cm, gate


async def test_a_link_reports_a_call_held_past_half_a_second_until_its_late_answer(sim_ros2):
    cm, gate = await _serve_slow(sim_ros2.url)
    try:
        async with connected(sim_ros2.url, reconnect=False) as client:
            await client.detect_ros()
            await until(lambda: "/slow" in sim_ros2.services, what="/slow served")
            told: list = []
            client.session.held.add_listener(told.append)
            with pytest.raises(ServiceTimeoutError):  # the client gives up after 1 s...
                await client.call_service("/slow", {}, timeout=1.0)
            assert told == [Held("/slow", told[0].since)]  # ...having said so after 0.5 s
            assert client.session.held.current.sentence().endswith("busy with /slow")
            gate.set()  # the late answer: the server is free again
            await until(lambda: client.session.held.current is None, what="the hold ended by the late answer")
            assert told[-1] is None
            calls = watched_calls(client.session.held)
            assert (await client.call_service("/rosapi/get_time", {}))  # quick calls: never reported...
            [(cid, service)] = calls["started"]
            assert service == "/rosapi/get_time" and calls["answered"] == [cid]  # (watched, and answered)
            assert checked_later(client.session.held, 60.0) is None  # ...however long after
            assert len(told) == 2
    finally:
        await cm.__aexit__(None, None, None)


async def test_a_ros1_link_never_reports_a_hold(sim):
    cm, gate = await _serve_slow(sim.url)
    try:
        async with connected(sim.url, reconnect=False) as client:
            assert (await client.detect_ros()).version == 1  # rosbridge 0.11 runs each call in a thread
            await until(lambda: "/slow" in sim.services, what="/slow served")
            watch = client.session.held
            told: list = []
            watch.add_listener(told.append)
            with pytest.raises(ServiceTimeoutError):
                await client.call_service("/slow", {}, timeout=HOLD_AFTER * 2)
            assert watch.check() is None and watch.current is None and told == []
            # not for want of a call held: /slow is unanswered past the threshold, and a server that may
            # hold frames (a ROS 2 one) would be reported; ROS 1 runs it in a thread of its own
            assert unanswered(watch) == "/slow"
            gate.set()  # the late answer reaches the client, and ends the call there too
            await until(lambda: unanswered(watch) is None, what="the late answer to /slow")
            assert watch.check() is None and told == []
    finally:
        await cm.__aexit__(None, None, None)
