"""Thread helpers shared by the sensor widgets (no Qt).

* :class:`LatestSlot`: a one-item mailbox where the newest item replaces an unread one (latest wins).
* :class:`SlotWorker`: a daemon thread that takes items from a :class:`LatestSlot` and handles them, so
  heavy work (image decoding, JPEG encoding) never runs on the bridge loop or the GUI thread.
* :class:`QueueWorker`: a daemon thread that takes every item, in order, from a bounded queue (video
  packets: each one is needed to decode the next); a queue that overflows is emptied and the handler told.
* :class:`LoopTicker`: a steady periodic call on the running asyncio loop (the bridge loop), used for
  publish rates; it never bursts to catch up.
"""

from __future__ import annotations

import asyncio
import logging
import threading
from collections.abc import Callable
from typing import Any

from rcon_core.priority import lower_this_thread

log = logging.getLogger(__name__)

__all__ = ["LatestSlot", "SlotWorker", "QueueWorker", "LoopTicker"]

#: a LoopTicker call later than this fraction of its period restarts the schedule from its own time
LATE_FRACTION = 0.1

_EMPTY = object()


class LatestSlot:
    """Holds at most one item; ``put`` replaces an item nobody took yet (counted in ``dropped``)."""

    def __init__(self) -> None:
        self._cond = threading.Condition()
        self._item: Any = _EMPTY
        self._closed = False
        self.dropped = 0

    def put(self, item: Any) -> None:
        with self._cond:
            if self._item is not _EMPTY:
                self.dropped += 1
            self._item = item
            self._cond.notify()

    def take(self, timeout: float | None = None) -> tuple[bool, Any]:
        """``(True, item)``, or ``(False, None)`` after ``timeout`` or once closed and empty."""
        with self._cond:
            if self._item is _EMPTY and not self._closed:
                self._cond.wait(timeout)
            if self._item is _EMPTY:
                return False, None
            item, self._item = self._item, _EMPTY
            return True, item

    def close(self) -> None:
        with self._cond:
            self._closed = True
            self._cond.notify_all()

    @property
    def closed(self) -> bool:
        return self._closed


class SlotWorker:
    """A daemon thread feeding each newest item of its slot to ``handle(item)``.

    Exceptions from ``handle`` go to ``on_error(exc)`` (the thread keeps running).  ``background`` (the
    default): the thread runs at a lower OS priority than the GUI and bridge threads
    (:func:`rcon_core.priority.lower_this_thread`): its work is the kind that may wait.
    """

    def __init__(self, name: str, handle: Callable[[Any], None],
                 on_error: Callable[[BaseException], None] | None = None, *, background: bool = True) -> None:
        self.slot = LatestSlot()
        self.background = background
        self._handle = handle
        self._on_error = on_error
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)
        self._thread.start()

    def submit(self, item: Any) -> None:
        self.slot.put(item)

    def _run(self) -> None:
        if self.background:
            lower_this_thread()
        while True:
            ok, item = self.slot.take()
            if not ok:
                if self.slot.closed:
                    return
                continue
            try:
                self._handle(item)
            except Exception as exc:  # noqa: BLE001 - report, keep going with the next item
                if self._on_error is not None:
                    self._on_error(exc)
                else:
                    log.exception("worker %s failed", self._thread.name)

    def close(self, timeout: float = 1.0) -> None:
        """Stop after the item being handled; waits up to ``timeout`` (never from the thread itself)."""
        self.slot.close()
        if threading.current_thread() is not self._thread:
            self._thread.join(timeout)

    @property
    def alive(self) -> bool:
        return self._thread.is_alive()


class QueueWorker:
    """A daemon thread handing everything queued so far, in order, to ``handle(items, overflowed)``.

    Unlike :class:`SlotWorker` nothing is replaced: a video stream needs every packet. ``max_items``
    bounds the queue: an item that finds it full empties it (those items are lost, counted in
    ``dropped``) and the next call of ``handle`` gets ``overflowed=True``, so a decoder that cannot keep up
    starts again from a keyframe instead of falling further behind (no growing backlog). Exceptions from
    ``handle`` go to ``on_error`` (the thread keeps running); the thread runs at a lower OS priority unless
    ``background`` is False.
    """

    def __init__(self, name: str, handle: Callable[[list[Any], bool], None],
                 on_error: Callable[[BaseException], None] | None = None, *, max_items: int = 120,
                 background: bool = True) -> None:
        self.max_items = max_items
        self.background = background
        self.dropped = 0
        self.overflows = 0
        self._items: list[Any] = []
        self._overflowed = False
        self._closed = False
        self._cond = threading.Condition()
        self._handle = handle
        self._on_error = on_error
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)
        self._thread.start()

    def submit(self, item: Any) -> None:
        with self._cond:
            if len(self._items) >= self.max_items:
                self.dropped += len(self._items)
                self.overflows += 1
                self._items = []
                self._overflowed = True
            self._items.append(item)
            self._cond.notify()

    @property
    def queued(self) -> int:
        """Items waiting now (not counting the batch being handled)."""
        with self._cond:
            return len(self._items)

    def _run(self) -> None:
        if self.background:
            lower_this_thread()
        while True:
            with self._cond:
                while not self._items and not self._closed:
                    self._cond.wait()
                if self._closed:
                    return
                items, self._items = self._items, []
                overflowed, self._overflowed = self._overflowed, False
            try:
                self._handle(items, overflowed)
            except Exception as exc:  # noqa: BLE001 - report, keep going with the next items
                if self._on_error is not None:
                    self._on_error(exc)
                else:
                    log.exception("worker %s failed", self._thread.name)

    def close(self, timeout: float = 1.0) -> None:
        """Stop after the batch being handled (what is still queued is dropped); waits up to ``timeout``."""
        with self._cond:
            self._closed = True
            self._cond.notify_all()
        if threading.current_thread() is not self._thread:
            self._thread.join(timeout)

    @property
    def alive(self) -> bool:
        return self._thread.is_alive()


class LoopTicker:
    """Calls ``fn()`` every ``period`` seconds on the running asyncio loop, steadily (no catch-up bursts).

    A call that runs more than ``LATE_FRACTION`` of a period late (the loop was busy) restarts the schedule
    from that moment: the next call comes a whole period later, not early to keep the old phase (two
    commands 20 ms apart after one 80 ms late at 20 Hz would be two jitters instead of one).  Smaller
    lateness keeps the phase, so the average rate holds.

    ``start`` and ``stop`` must be called on the loop thread. ``clock``: what the ticks are timed and
    scheduled on instead of the running loop, anything with a loop's ``time()`` and ``call_at(when, fn)``
    (tests pass ``rcon_core.testing.ManualClock`` so a rate is checked without the wall clock).
    """

    def __init__(self, period: float, fn: Callable[[], None], *, clock: Any = None) -> None:
        if not period > 0:
            raise ValueError(f"period must be positive, got {period}")
        self.period = period
        self._fn = fn
        self._clock = clock
        self._loop: Any = None  # the running asyncio loop, or the injected clock
        self._handle: Any = None  # the pending call's handle (has cancel())
        self._due = 0.0

    @property
    def running(self) -> bool:
        return self._handle is not None

    def start(self, first_delay: float | None = None) -> None:
        if self._handle is not None:
            return
        try:
            self._loop = self._clock if self._clock is not None else asyncio.get_running_loop()
        except RuntimeError:
            raise RuntimeError("a periodic publisher needs the bridge loop: call it there "
                               "(pass dispatch=BridgeThread.call to the model)") from None
        self._due = self._loop.time() + (self.period if first_delay is None else first_delay)
        self._handle = self._loop.call_at(self._due, self._tick)

    def stop(self) -> None:
        if self._handle is not None:
            self._handle.cancel()
            self._handle = None

    def _tick(self) -> None:
        assert self._loop is not None
        now = self._loop.time()
        late = now - self._due
        self._due += self.period
        if late > self.period * LATE_FRACTION:  # woke up late (a busy loop): start the period from now, so
            self._due = now + self.period  # the next call is a whole period away, never a short catch-up
        self._handle = self._loop.call_at(self._due, self._tick)
        try:
            self._fn()
        except Exception:  # noqa: BLE001 - one failed tick must not end the rate
            log.exception("periodic call failed")
