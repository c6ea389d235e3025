"""The Receiver's turns of the loop (``receive.py``, "sharing the loop"), driven by hand with the turn's clock
replaced: the byte room, the clock read only when the room is used up, a turn that goes on into the read the
transport makes at once, reading that waits for the loop's next turn, and picows' read wrapper that says when
the transport reads at once (``pwlink._CappedReads``)."""

from __future__ import annotations

import asyncio
from typing import Any

import orjson
import pytest

from rcon_core.bridge import receive
from rcon_core.bridge.receive import TURN_BUDGET, YIELD_BYTES, Receiver
from rcon_core.bridge.topics import TopicEntry
from rcon_core.bridge.traffic import Traffic


class _Bad:
    def __init__(self) -> None:
        self.errors: list[BaseException] = []

    def failed(self, exc: BaseException) -> None:
        self.errors.append(exc)


class _Inbound:
    """What a Receiver reads from the client's ``Inbound``: here every message is a publish of ``/t``."""

    def __init__(self) -> None:
        self.topics: dict[str, Any] = {}
        self.traffic = Traffic()
        self.bad = _Bad()
        self.heavy = 32 * 1024
        self.taken: list[bytes] = []

    def take(self, raw: Any, text: bool) -> None:
        self.taken.append(bytes(raw))

    def deliver(self, m: Any) -> None:
        raise AssertionError(f"not a publish of a subscribed topic: {m!r}")


class _Clock:
    def __init__(self) -> None:
        self.now = 100.0
        self.reads = 0

    def __call__(self) -> float:
        self.reads += 1
        return self.now


@pytest.fixture
def clock(monkeypatch: pytest.MonkeyPatch) -> _Clock:
    c = _Clock()
    monkeypatch.setattr(receive, "_clock", c)
    return c


def _receiver() -> tuple[Receiver, _Inbound, list[Any], list[str]]:
    inbound = _Inbound()
    got: list[Any] = []
    entry = TopicEntry("/t", lambda kind, text: None)
    entry.fast = got.append
    inbound.topics["/t"] = entry
    r = Receiver(inbound)
    calls: list[str] = []
    r.pause = lambda: calls.append("pause")
    r.resume = lambda: calls.append("resume")
    return r, inbound, got, calls


def _frame(i: int) -> bytes:
    return orjson.dumps({"op": "publish", "topic": "/t", "msg": {"data": f"{i:04d}", "pad": "x" * 40}})  # one size


async def test_the_clock_is_read_once_per_room_of_messages_and_the_turn_ends_past_its_budget(clock):
    r, inbound, got, _calls = _receiver()
    size = len(_frame(0))
    per_room = -(-YIELD_BYTES // size)  # the message that uses the room up reads the clock
    for i in range(per_room - 1):
        r.message(_frame(i), True, False)
    assert clock.reads == 0 and len(got) == per_room - 1  # the first YIELD_BYTES: no clock
    r.message(_frame(per_room), True, False)
    assert clock.reads == 1 and not r.busy  # the turn's clock starts: delivered at once
    clock.now += 2 * TURN_BUDGET
    for i in range(per_room):
        r.message(_frame(i), True, False)
    assert clock.reads == 2 and r.busy  # the budget is spent: the rest waits for the next turn
    assert len(got) == 2 * per_room - 1 and len(r.held) == 1
    r.message(_frame(0), True, False)
    assert len(r.held) == 2  # held, in order, until the loop had its turn
    await r.task
    assert inbound.taken == [_frame(per_room - 1), _frame(0)] and not r.busy
    nbytes, frames = inbound.traffic.snapshot()[1]["/t"]
    assert frames == len(got) and nbytes == frames * size  # the hot path counted what it delivered


async def test_a_heavy_message_waits_unless_it_is_the_first_of_its_turn(clock):
    r, inbound, got, _calls = _receiver()
    big = orjson.dumps({"op": "publish", "topic": "/t", "msg": {"data": "x" * (40 * 1024)}})
    r.message(big, True, False)
    assert inbound.taken == [big] and not r.busy  # the first of its turn: taken now
    r.read_done()
    r.message(_frame(1), True, False)
    r.message(big, True, False)
    assert r.busy and len(got) == 1  # after a message in the same turn: waits for the next
    await r.task
    assert inbound.taken == [big, big]


async def test_a_turn_goes_on_into_the_next_read_while_two_reads_fit_in_its_budget(clock):
    """picows' socket layer reads again at once after a read that filled its buffer (``more``): the turn goes
    on, room and clock; once the turn so far and one more read as long would pass the budget, reading stops
    until the loop has had a turn, and the turn after it starts afresh."""
    r, _inbound, got, calls = _receiver()
    size = len(_frame(0))
    per_room = -(-YIELD_BYTES // size)
    for i in range(2 * per_room):
        r.message(_frame(i), True, False)
    assert r.started == clock.now  # the clock started within this read
    clock.now += 0.3 * TURN_BUDGET
    r.read_done(more=True)  # 0.3 ms so far, one more read as long: 0.6 ms
    assert calls == [] and r.started and r.flood  # the same turn goes on
    for i in range(per_room):
        r.message(_frame(i), True, False)
    clock.now += 0.3 * TURN_BUDGET
    r.read_done(more=True)  # 0.6 ms so far, the last read took 0.3 ms: 0.9 ms
    assert calls == [] and r.started
    clock.now += 0.3 * TURN_BUDGET
    r.read_done(more=True)  # 0.9 ms so far: one more read would pass the budget
    assert calls == ["pause"] and not r.started and r.room == YIELD_BYTES
    await asyncio.sleep(0)
    assert calls == ["pause", "resume"]  # the loop had its turn: reading goes on
    assert not r.busy and len(got) == 3 * per_room


async def test_a_read_that_the_loop_follows_ends_the_turn_and_a_short_turn_needs_no_clock(clock):
    r, _inbound, _got, calls = _receiver()
    for i in range(3):
        r.message(_frame(i), True, False)
    r.read_done(more=True)  # under YIELD_BYTES so far: the turn goes on, the clock unread
    assert clock.reads == 0 and r.room < YIELD_BYTES
    r.read_done()  # the loop runs before the next read: a new turn
    assert r.room == YIELD_BYTES and not r.started and calls == [] and clock.reads == 0


async def test_reading_resumes_after_held_messages_only_once_the_loop_had_a_turn(clock):
    r, inbound, got, calls = _receiver()
    size = len(_frame(0))
    per_room = -(-YIELD_BYTES // size)
    for i in range(per_room):
        r.message(_frame(i), True, False)
    clock.now += 2 * TURN_BUDGET
    for i in range(per_room + 20):  # the budget is spent: the rest is held, and past HOLD_MAX reading stops
        r.message(_frame(i), True, False)
    assert r.busy and calls == ["pause"]
    when: list[int] = []
    r.pause = lambda: (calls.append("pause"), when.append(len(inbound.taken)))
    await r.task  # the held messages are delivered in later turns; half of them out, reading resumed
    await asyncio.sleep(0)
    assert not r.busy and calls == ["pause", "resume", "pause", "resume"]
    assert when == [21]  # all out: reading stopped again, and resumed from the loop's next turn
    assert len(got) == 2 * per_room - 1 and len(inbound.taken) == 21  # every message, once


class _Inner:
    """picows' protocol as the wrapper sees it: a big free buffer, and the reads it was told of."""

    def __init__(self) -> None:
        self.buffer = bytearray(1 << 20)
        self.updated: list[int] = []

    def get_buffer(self, sizehint: int) -> memoryview:
        return memoryview(self.buffer)

    def buffer_updated(self, nbytes: int) -> None:
        self.updated.append(nbytes)


class _Reads:
    def __init__(self, flood: bool) -> None:
        self.flood = flood
        self.done: list[bool] = []

    def read_done(self, more: bool = False) -> None:
        self.done.append(more)


def test_picows_reads_are_capped_and_the_receiver_told_when_the_transport_reads_again_at_once():
    """aiofastnet reads again at once while a read fills the buffer it was given, up to CYCLE bytes a cycle of
    the loop; a short read ends the cycle."""
    pytest.importorskip("picows")
    from rcon_core.bridge.pwlink import BIG_READ_CAP, CYCLE, READ_CAP, _CappedReads

    inner, reads = _Inner(), _Reads(flood=True)
    wrapper = _CappedReads(inner, reads)
    for _ in range(CYCLE // READ_CAP):
        assert len(wrapper.get_buffer(-1)) == READ_CAP
        wrapper.buffer_updated(READ_CAP)
    assert reads.done == [True] * (CYCLE // READ_CAP - 1) + [False]  # the cycle's last read: the loop runs
    wrapper.get_buffer(-1)
    wrapper.buffer_updated(READ_CAP)
    wrapper.get_buffer(-1)
    wrapper.buffer_updated(100)  # a short read: the loop runs next
    assert reads.done[-2:] == [True, False]
    reads.flood = False
    assert len(wrapper.get_buffer(-1)) == BIG_READ_CAP
    wrapper.buffer_updated(BIG_READ_CAP)
    assert reads.done[-1] is False  # one read of CYCLE bytes is the whole cycle
    assert inner.updated[-1] == BIG_READ_CAP
