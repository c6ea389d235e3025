"""Messages in from a transport adapter (``pwlink.py``, ``wslink.py``), in order, on the event loop.

Decision: messages are pushed, and most are finished in the callback that brought them
    An adapter calls :meth:`Receiver.message` for every whole message as its parser finds it (bytes, or
    for picows' binary messages a view into its read buffer, valid during the call only) and says when a
    read's messages are all in (``last`` with the read's last message, or :meth:`Receiver.read_done` after
    the read: picows' adapter, one argument less per message).  On picows the Receiver is called straight
    from the parser for a whole text frame (:meth:`Receiver.frame_callback`, installed as the listener's
    ``on_ws_frame``: the same steps as :meth:`Receiver.message`'s hot path, without the listener's call in
    between; the Foxglove link's Receiver so takes its whole binary frames).  The Receiver hands it to :meth:`Inbound.take <rcon_core.bridge.inbound.Inbound.take>`,
    which parses and delivers a small publish at once.  What needs to wait -- a frame decoded in the
    worker thread (``offload.py``), a frame of a latest-only topic looking for a newer one
    (``latest.py``), a big message completed by fragments -- comes back as an awaitable: the Receiver
    runs it in a task and *holds* (copies) every message that arrives meanwhile, so delivery keeps the
    order of arrival.  While more than :data:`HOLD_MAX` messages are held, the transport stops reading
    (``pause_reading``): the kernel's buffers and then TCP push back on the server.  The held messages
    are what :meth:`waiting` lists for ``latest.py`` (the receive queue).

Decision: sharing the loop (the read loop's rule, kept in time)
    A read can hold thousands of small messages (picows' read buffer grows to fit a camera frame and stays
    that size) and a link that fell behind holds several camera frames.  So a turn takes messages until
    they add up to :data:`YIELD_BYTES` (4 kB, about 64 small messages) without reading the clock; then the
    Receiver reads the clock every YIELD_BYTES of messages, and once they have taken more than
    :data:`TURN_BUDGET` (1 ms) -- and before a message of 32 kB or more (``heavy``) that is not the first
    of its turn -- it holds the rest and gives the event loop a turn (``await asyncio.sleep(0)`` in its
    task): due timers (a teleop pad's 20 Hz command), writes and the other robots' links on the same loop
    wait for 4 kB of messages and about 1 ms more, or one big message, not for the whole backlog.  One
    comparison a message keeps the rule: the message's size against what is left of the turn's 4 kB
    (``room``): a heavy message never fits, and the clock is read (:meth:`_spent`) only when the room is
    used up.  (The rule counted 64 messages: 64 messages of 31 kB, 2 MB of JSON, passed between two clock
    reads; and one comparison a message replaces two, the count and the size.  The clock is read only
    then: on this kind of machine a clock read costs about as much as a small message.)

    A turn ends where the loop runs again.  After a read the loop runs before the next read, except where
    the transport reads again at once: picows' socket layer (aiofastnet) reads up to 256 kB in one cycle of
    the loop while each read fills the buffer it was given (``pwlink.py`` tells :meth:`read_done` so: its
    reads of a flood are capped at 32 kB).  The turn then goes on into that read while the turn so far and
    one more read as long as the last fit in its budget; otherwise reading waits until the loop has had a
    turn (:meth:`_wait_turn`: ``pause_reading``, and ``resume_reading`` from a callback of the loop's next
    turn), so what is left waits in the kernel, not copied into the Receiver.  (Every read was a turn:
    a flood then kept the loop for eight reads, 256 kB, 6 to 9 ms, measured; the waits cost a flood about
    1 % of its CPU.)  Once held messages are all handled, the next read also waits for the loop's next
    turn.

Decision: a text message that is not UTF-8 closes the link
    As the WebSocket rule says (and websockets' own reader did): the link is failed with code 1007 and
    the client reconnects; the messages still held are dropped with it.
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections import deque
from collections.abc import Awaitable, Callable
from typing import Any

from orjson import JSONDecodeError
from orjson import loads as _loads

from .errors import NotUtf8
from .safety import safe_text

log = logging.getLogger(__name__)

#: held messages above which the transport stops reading (websockets' own receive queue held 16 frames)
HOLD_MAX = 16
#: bytes of messages a turn takes before its clock is first read, and between two reads of it (about 64
#: small messages)
YIELD_BYTES = 4096
#: seconds of messages one turn of the loop may take before the rest waits for the next turn
TURN_BUDGET = 0.001
_sleep = asyncio.sleep
_clock = time.thread_time


class Receiver:
    """One connection's messages in (see the module docstring).  ``take(raw, text)`` and
    ``heavy`` come from the client's ``Inbound``; the adapter sets ``pause``, ``resume`` and ``fail``."""

    __slots__ = ("take", "deliver", "topics", "traffic", "failed", "heavy", "held", "busy", "room", "started",
                 "mark", "paused", "waiting_turn", "pause", "resume", "fail", "task", "closed", "flood")

    def __init__(self, inbound: Any) -> None:
        self.take: Callable[[Any, bool], Awaitable[None] | None] = inbound.take
        self.deliver: Callable[[Any], Awaitable[None] | None] = inbound.deliver
        self.topics: dict[str, Any] = inbound.topics
        self.traffic = inbound.traffic  # bytes in by topic (``traffic.py``), counted here on the hot path
        self.failed: Callable[[BaseException], None] = inbound.bad.failed
        self.heavy: int = inbound.heavy
        self.held: deque[tuple[bytes | str, bool]] = deque()
        self.busy = False
        #: bytes this turn still takes before its clock is read (:meth:`_over`); YIELD_BYTES at a turn's start
        self.room = YIELD_BYTES
        self.started = 0.0  # when this turn's clock started (at its first read, YIELD_BYTES in)
        self.mark = 0.0  # when the turn's last read ended, for a turn that goes on into the next read
        self.paused = False  # reading stopped: more than HOLD_MAX messages held
        self.waiting_turn = False  # reading stopped until the loop has had a turn (:meth:`read_done`)
        self.pause: Callable[[], None] = _nothing
        self.resume: Callable[[], None] = _nothing
        self.fail: Callable[[int, str], None] = _fail_nothing
        self.task: asyncio.Task[None] | None = None
        self.closed = False
        #: the last read brought more than YIELD_BYTES of messages (its clock was read), or left some held
        self.flood = False

    def detach(self) -> None:
        """The connection is over: forget its transport's callbacks and the held messages, so nothing here
        keeps the dead connection (and its buffers) alive in a reference cycle (``Link.release``)."""
        self.pause = self.resume = _nothing
        self.fail = _fail_nothing
        self.held.clear()

    def message(self, raw: Any, text: bool, last: bool) -> None:
        """One whole message (``raw``: bytes-like, a text message's UTF-8 bytes unchecked; valid only during
        this call); ``last``: the last one of this read.  The hot path: a text message that fits in the turn's
        room (one comparison: it is smaller than ``heavy`` and the turn's clock need not be read) is parsed
        and, when it is a publish of a subscribed topic, counted (the entry's ``tally``, ``traffic.py``) and
        delivered here (``Inbound.take`` and ``Inbound.deliver`` inlined: one call less per message); a
        message past the room goes to :meth:`_over`."""
        if self.busy:
            held = self.held
            held.append((raw if raw.__class__ is bytes else bytes(raw), text))
            if len(held) > HOLD_MAX and not self.paused and not self.closed:
                self.paused = True
                self.pause()
        else:
            size = len(raw)
            room = self.room - size
            if room > 0:
                self.room = room
            elif size >= self.heavy or self._spent():
                self._over(raw, text, size)
                if last:
                    self.read_done()
                return
            if text:
                try:
                    m = _loads(raw)
                except JSONDecodeError:
                    self._start(self._take(raw, text))
                else:
                    try:
                        entry = self.topics[m["topic"]] if m["op"] == "publish" else None
                        msg = m["msg"]
                    except (KeyError, TypeError):
                        entry = None
                    if entry is not None and msg.__class__ is dict:
                        c = entry.tally
                        if c is None:  # the topic's first message: its row of the traffic counts
                            c = entry.tally = self.traffic.row(entry.topic)
                        c.nbytes += size
                        c.frames += 1
                        try:
                            entry.fast(msg)
                        except Exception:
                            entry.callback_failed()
                    else:
                        self._slow(m, size)
            else:
                self._start(self._take(raw, text))
        if last:
            self.read_done()

    def frame_callback(self, text_type: Any, binary_type: Any,
                       other: Callable[[Any, Any], None]) -> Callable[[Any, Any], None] | None:
        """picows' per-frame callback bound straight to this Receiver (``pwlink.py`` installs it as its
        listener's ``on_ws_frame``): :meth:`message`'s hot path with the listener's step folded in, one
        Python call a message less (about 0.1 us a small message in A/B floods of a million).  A whole text
        frame that fits in the turn's room, a subscribed topic's publish, is parsed, counted and delivered
        here; every other frame, and every frame while this Receiver holds messages, goes to ``other`` (the
        listener's own ``on_ws_frame``, which calls :meth:`message`).  The steps are :meth:`message`'s, in
        the same order: keep the two in step (every bridge test runs on both transports).  ``frame`` is
        duck-typed (``msg_type``, ``fin``, ``get_payload_as_bytes``): this module does not import picows."""
        topics = self.topics
        heavy = self.heavy
        row = self.traffic.row
        spent = self._spent
        r = self

        def on_frame(transport: Any, frame: Any) -> None:
            if frame.msg_type is text_type and frame.fin and not r.busy:
                raw = frame.get_payload_as_bytes()
                size = len(raw)
                room = r.room - size
                if room > 0:
                    r.room = room
                elif size >= heavy or spent():
                    r._over(raw, True, size)
                    return
                try:
                    m = _loads(raw)
                except JSONDecodeError:
                    r._start(r._take(raw, True))
                    return
                try:
                    entry = topics[m["topic"]] if m["op"] == "publish" else None
                    msg = m["msg"]
                except (KeyError, TypeError):
                    entry = None
                if entry is not None and msg.__class__ is dict:
                    c = entry.tally
                    if c is None:  # the topic's first message: its row of the traffic counts
                        c = entry.tally = row(entry.topic)
                    c.nbytes += size
                    c.frames += 1
                    try:
                        entry.fast(msg)
                    except Exception:
                        entry.callback_failed()
                else:
                    r._slow(m, size)
            else:
                other(transport, frame)

        return on_frame

    def read_done(self, more: bool = False) -> None:
        """The read's messages are all in (:meth:`message` with ``last``, or the transport says so after
        each read: picows' adapter, one argument less per message).  The next read is a new turn, but for a
        read with ``more`` after it: the transport reads again before the loop runs (``pwlink.py``: a read
        that filled the buffer it was given), so the turn goes on into that read while the turn so far and
        one more read like the last fit in its budget; otherwise reading waits until the loop has had its
        turn (:meth:`_wait_turn`)."""
        if more and not self.busy:
            if not self.started:  # under YIELD_BYTES of messages so far: the turn goes on, clock unread
                return
            now = _clock()
            if 2 * now - self.started - (self.mark or self.started) <= TURN_BUDGET:
                self.mark = now  # the end of this read: the next one's length is measured from here
                self.flood = True
                return
            self._wait_turn()
        self.flood = self.started != 0.0 or self.busy
        self.room = YIELD_BYTES
        self.started = self.mark = 0.0

    def _wait_turn(self, paused: bool = False) -> None:
        """Stop reading (``paused``: it is stopped already) until the loop has had a turn: what the transport
        has not read waits in the kernel, nothing is held."""
        if self.waiting_turn or self.closed:
            return
        self.waiting_turn = True
        if not paused:
            self.pause()
        asyncio.get_running_loop().call_soon(self._turn_over)

    def _turn_over(self) -> None:
        self.waiting_turn = False
        if not self.paused and not self.closed:
            self.resume()

    def _over(self, raw: Any, text: bool, size: int) -> None:
        """Not the hot path: a message past the turn's room that does not fit in this turn.  One of ``heavy``
        size or more is a turn of its own: taken now when it is the first of its turn (the next message then
        reads the clock), else held for the next turn.  A smaller one came once the turn had taken its
        budget (:meth:`_spent` said so): it and the rest wait for the next turn."""
        if size >= self.heavy and self.room == YIELD_BYTES and not self.started:  # the first of its turn
            self.room = 0
            self._start(self._take(raw, text))
        else:
            self._yield(raw, text)

    def _slow(self, m: Any, size: int) -> None:
        """A parsed message that is not a publish of a subscribed topic: counted, then ``Inbound.deliver``."""
        try:  # the frame boundary: nothing raised while handling one frame ends the link
            self.traffic.count(m, size)
        except Exception as exc:
            self.failed(exc)
            return
        self._start(self.deliver(m))

    def _yield(self, raw: Any, text: bool) -> None:
        """This turn is over: hold ``raw`` and the rest, and go on after the loop had a turn."""
        self.busy = True
        self.held.append((raw if raw.__class__ is bytes else bytes(raw), text))
        self.task = asyncio.ensure_future(self._drain(None))

    def _take(self, raw: Any, text: bool) -> Awaitable[None] | None:
        try:
            return self.take(raw, text)
        except NotUtf8 as exc:
            self._not_utf8(exc)
            return None

    def _spent(self) -> bool:
        """The turn's room is used up: has it taken its budget since its clock started (at the first call of a
        turn)?  The room is YIELD_BYTES again.  (The clock is read only here, about every YIELD_BYTES of
        messages: a clock read costs as much as a small message.)"""
        self.room = YIELD_BYTES
        now = _clock()
        if not self.started:
            self.started = now
            return False
        return now - self.started > TURN_BUDGET

    def waiting(self) -> list[bytes | str]:
        """The messages held (received, not handled yet), oldest first: the receive queue ``latest.py``
        looks into."""
        return [raw for raw, _text in self.held]

    def lost(self) -> None:
        """The connection is gone: nothing more comes; what is held is still handled in order."""
        self.closed = True

    def cancel(self) -> None:
        """Stop now (the client is closing): held messages are dropped."""
        self.held.clear()
        task, self.task = self.task, None
        if task is not None:
            task.cancel()

    # -- holding -------------------------------------------------------------------------------------

    def _start(self, job: Awaitable[None] | None) -> None:
        """Run ``job`` (when there is one) before the next message."""
        if job is not None:
            self.busy = True
            self.task = asyncio.ensure_future(self._drain(job))

    async def _drain(self, job: Awaitable[None] | None) -> None:
        held = self.held
        take = self.take
        heavy = self.heavy
        try:
            if job is None:
                await _sleep(0)  # the turn's budget is spent: let the loop run first
            else:
                await self._run(job)
            first, room, started = True, YIELD_BYTES, _clock()  # the turn's state, as the hot path's
            while held:
                raw, text = held.popleft()
                if self.paused and len(held) <= HOLD_MAX // 2:
                    self.paused = False
                    self.resume()
                size = len(raw)
                room -= size
                if room <= 0:
                    if not first and (size >= heavy or _clock() - started > TURN_BUDGET):
                        await _sleep(0)
                        started = _clock()
                    room = YIELD_BYTES - size
                first = False
                try:
                    job = take(raw, text)
                except NotUtf8 as exc:
                    self._not_utf8(exc)
                    return
                if job is not None:
                    await self._run(job)
                    first, room, started = True, YIELD_BYTES, _clock()
        finally:
            self.busy = False
            self.task = None
            paused, self.paused = self.paused, False
            self._wait_turn(paused)  # the next read waits for the loop's next turn, then reading resumes

    async def _run(self, job: Awaitable[None]) -> None:
        try:
            await job
        except NotUtf8 as exc:
            self._not_utf8(exc)
        except asyncio.CancelledError:
            raise
        except Exception as exc:  # the frame boundary: nothing raised while handling one frame ends the link
            self.failed(exc)

    def _not_utf8(self, exc: NotUtf8) -> None:
        self.held.clear()
        log.warning("the server sent a text message that is not UTF-8 (%s); closing the link (1007)", safe_text(exc))
        self.fail(1007, "invalid UTF-8 in a text message")


def _nothing() -> None:
    pass


def _fail_nothing(code: int, reason: str) -> None:
    pass
