"""Messages in from a transport adapter (``pwlink.py``, ``wslink.py``), in order, on the event loop.

Decision: messages are pushed, and most are finished in the callback that brought them
    An adapter calls :meth:`Receiver.message` for every whole message as its parser finds it (bytes, or
    for picows' binary messages a view into its read buffer, valid during the call only) and says when a
    read's messages are all in (``last`` with the read's last message, or :meth:`Receiver.read_done` after
    the read: picows' adapter, one argument less per message).  On picows the Receiver is called straight
    from the parser for a whole text frame (:meth:`Receiver.frame_callback`, installed as the listener's
    ``on_ws_frame``: the same steps as :meth:`Receiver.message`'s hot path, without the listener's call in
    between).  The Receiver hands it to :meth:`Inbound.take <rcon_core.bridge.inbound.Inbound.take>`,
    which parses and delivers a small publish at once.  What needs to wait -- a frame decoded in the
    worker thread (``offload.py``), a frame of a latest-only topic looking for a newer one
    (``latest.py``), a big message completed by fragments -- comes back as an awaitable: the Receiver
    runs it in a task and *holds* (copies) every message that arrives meanwhile, so delivery keeps the
    order of arrival.  While more than :data:`HOLD_MAX` messages are held, the transport stops reading
    (``pause_reading``): the kernel's buffers and then TCP push back on the server.  The held messages
    are what :meth:`waiting` lists for ``latest.py`` (the receive queue).

Decision: sharing the loop (the read loop's rule, kept in time)
    A read can hold thousands of small messages (picows' read buffer grows to fit a camera frame and stays
    that size) and a link that fell behind holds several camera frames.  So past the first
    :data:`~rcon_core.bridge.inbound.YIELD_EVERY` (64) messages of one turn, the Receiver looks at the
    clock every 64 messages, and once they have taken more than :data:`TURN_BUDGET` (1 ms) -- and before
    a message of 32 kB or more that is not the first of its turn -- it holds the rest and gives the event
    loop a turn (``await asyncio.sleep(0)`` in its task): due timers (a teleop pad's 20 Hz command),
    writes and the other robots' links on the same loop wait for 64 small messages and about 1 ms more,
    or one big message, not for the whole backlog.  A new read is a new turn: the loop ran in between.
    (The rule was 64 messages a turn: kept that strictly, it copied every message past the 64th of a read,
    as much work as the rest of the hot path, when a 16 kB read of small messages is about 0.3 ms of
    work.  The clock is read only then: on this kind of machine a clock read costs about as much as a
    small message.)

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
from .inbound import YIELD_EVERY
from .safety import safe_text

log = logging.getLogger(__name__)

#: held messages above which the transport stops reading (websockets' own receive queue held 16 frames)
HOLD_MAX = 16
#: seconds of messages one turn of the loop may take before the rest waits for the next turn
TURN_BUDGET = 0.001
_sleep = asyncio.sleep
_clock = time.thread_time


class Receiver:
    """One connection's messages in (see the module docstring).  ``take(raw, text)`` and
    ``heavy`` come from the client's ``Inbound``; the adapter sets ``pause``, ``resume`` and ``fail``."""

    __slots__ = ("take", "deliver", "topics", "traffic", "failed", "heavy", "held", "busy", "n", "started", "check", "paused",
                 "pause", "resume", "fail", "task", "closed", "flood")

    def __init__(self, inbound: Any) -> None:
        self.take: Callable[[Any, bool], Awaitable[None] | None] = inbound.take
        self.deliver: Callable[[Any], Awaitable[None] | None] = inbound.deliver
        self.topics: dict[str, Any] = inbound.topics
        self.traffic = inbound.traffic  # bytes in by topic (``traffic.py``), counted here on the hot path
        self.failed: Callable[[BaseException], None] = inbound.bad.failed
        self.heavy: int = inbound.heavy
        self.held: deque[tuple[bytes | str, bool]] = deque()
        self.busy = False
        self.n = 0  # messages handled in this turn of the loop
        self.started = 0.0  # when this turn's clock started (at its 65th message)
        self.check = YIELD_EVERY  # the clock is read again after this many messages
        self.paused = False
        self.pause: Callable[[], None] = _nothing
        self.resume: Callable[[], None] = _nothing
        self.fail: Callable[[int, str], None] = _fail_nothing
        self.task: asyncio.Task[None] | None = None
        self.closed = False
        #: the last read brought YIELD_EVERY messages or more (a transport may read less at a time)
        self.flood = False

    def detach(self) -> None:
        """The connection is over: forget its transport's callbacks and the held messages, so nothing here
        keeps the dead connection (and its buffers) alive in a reference cycle (``Link.release``)."""
        self.pause = self.resume = _nothing
        self.fail = _fail_nothing
        self.held.clear()

    def message(self, raw: Any, text: bool, last: bool) -> None:
        """One whole message (``raw``: bytes-like, a text message's UTF-8 bytes unchecked; valid only during
        this call); ``last``: the last one of this read.  The hot path: a small text message is parsed and,
        when it is a publish of a subscribed topic, counted (the entry's ``tally``, ``traffic.py``) and
        delivered here (``Inbound.take`` and ``Inbound.deliver`` inlined: one call less per message); the
        turn's clock is read only past ``check`` (:meth:`_spent`); everything else goes through
        :meth:`_other`."""
        if self.busy:
            held = self.held
            held.append((raw if raw.__class__ is bytes else bytes(raw), text))
            if len(held) > HOLD_MAX and not self.paused and not self.closed:
                self.paused = True
                self.pause()
        else:
            n = self.n = self.n + 1
            size = len(raw)
            if text and size < self.heavy and (n <= self.check or not self._spent()):
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
                        c[0] += size
                        c[1] += 1
                        try:
                            entry.fast(msg)
                        except Exception:
                            entry.callback_failed()
                    else:
                        self._slow(m, size)
            else:
                self._other(raw, text, n, size)
        if last:
            self.read_done()

    def frame_callback(self, text_type: Any, other: Callable[[Any, Any], None]) -> Callable[[Any, Any], None] | None:
        """picows' per-frame callback bound straight to this Receiver (``pwlink.py`` installs it as its
        listener's ``on_ws_frame``): :meth:`message`'s hot path with the listener's step folded in, one
        Python call a message
        less: about 0.1 us a small message in A/B floods of a million).  A whole small text frame of a subscribed topic's publish is
        parsed, counted and delivered here; every other frame, and every frame while this Receiver holds
        messages, goes to ``other`` (the listener's own ``on_ws_frame``, which calls :meth:`message`).  The
        steps are :meth:`message`'s, in the same order: keep the two in step (every bridge test runs on both
        transports).  ``frame`` is duck-typed (``msg_type``, ``fin``, ``get_payload_as_bytes``): this
        module does not import picows."""
        topics = self.topics
        heavy = self.heavy
        row = self.traffic.row
        spent = self._spent
        r = self

        def on_frame(transport: Any, frame: Any) -> None:
            if frame.msg_type is text_type and frame.fin and not r.busy:
                raw = frame.get_payload_as_bytes()
                n = r.n = r.n + 1
                size = len(raw)
                if size < heavy and (n <= r.check or not spent()):
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
                        c[0] += size
                        c[1] += 1
                        try:
                            entry.fast(msg)
                        except Exception:
                            entry.callback_failed()
                    else:
                        r._slow(m, size)
                else:
                    r._other(raw, True, n, size)
            else:
                other(transport, frame)

        return on_frame

    def read_done(self) -> None:
        """The read's messages are all in (:meth:`message` with ``last``, or the transport says so after
        each read: picows' adapter, one argument less per message): the next read is a new turn."""
        self.flood = self.n >= YIELD_EVERY or self.busy
        self.n = 0
        self.check = YIELD_EVERY
        self.started = 0.0

    def _other(self, raw: Any, text: bool, n: int, size: int) -> None:
        """Not the hot path: a big message (``heavy`` or more: a turn of its own), a binary one, or a small
        text message once the turn's budget is spent (:meth:`message` read the clock then)."""
        if size >= self.heavy:
            if n > 1:
                self._yield(raw, text)
            else:
                self._start(self._take(raw, text))
        elif text or (n > self.check and self._spent()):
            self._yield(raw, text)
        else:
            self._start(self._take(raw, text))

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
        """Every YIELD_EVERY messages past the first YIELD_EVERY of a turn: has the turn taken its budget
        since then?  (The clock is read only here: a clock read costs as much as a small message.)"""
        self.check = self.n + YIELD_EVERY
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
            n = 0
            started = _clock()
            while held:
                raw, text = held.popleft()
                if self.paused and len(held) <= HOLD_MAX // 2:
                    self.paused = False
                    self.resume()
                n += 1
                if (n > 1 and len(raw) >= heavy) or (n > YIELD_EVERY and _clock() - started > TURN_BUDGET):
                    n = 1
                    await _sleep(0)
                    started = _clock()
                elif n > YIELD_EVERY:
                    n = 1
                try:
                    job = take(raw, text)
                except NotUtf8 as exc:
                    self._not_utf8(exc)
                    return
                if job is not None:
                    await self._run(job)
                    n = 0
                    started = _clock()
        finally:
            self.busy = False
            self.task = None
            if self.paused:
                self.paused = False
                self.resume()

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
