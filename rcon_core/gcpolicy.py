"""Garbage collection kept short while robots stream (no Qt; the app and the sim use it).

Decision: freeze what has settled
    CPython's cyclic collector stops every thread of the process while it runs (it holds the GIL).  A
    full (generation 2) collection walks every container object alive: in the app with a fleet canvas
    (Qt wrappers, plugins, run-time message classes, the robots' type catalogues) that took 50-76 ms,
    once every few seconds under load (``python benchmarks/bench_app.py --robots 3``,
    ``gc_gen2_pauses_ms``).  For those milliseconds no command leaves, no frame is read, no value is
    painted: the teleop pad's 20 Hz command came 70-100 ms late.

    So objects that have lived through a quiet moment are moved out of the collector's sight
    (``gc.collect()`` then ``gc.freeze()``: :meth:`CollectorPolicy.settle`).  Later collections walk only
    what was made since, and stay around a millisecond.  Frozen objects are still freed by reference
    counting the moment nothing refers to them; only *cyclic* garbage among them waits, until the next
    *full* settle (``gc.unfreeze()`` first), which the app does when a workspace is opened or another
    canvas is shown (the moment widgets are made and dropped, when a pause of some tens of ms is not
    felt: no pad of the new canvas is held yet).  So what a robot link drops must not be left in cycles:
    a dropped connection frozen while it was alive kept its buffers for good (0.85 MB per reconnect) until
    the bridge broke websockets' own cycles and stopped keeping tracebacks (``wslink.Link.release``,
    ``safety.without_traceback``; ``benchmarks/soak.py --parts reconnect``).  Between those, a *light* settle every
    :data:`SETTLE_EVERY` seconds and one a few seconds after a robot connects (its catalogue and message
    classes arrive then) freezes what has been made since, walking only that.

    The sim does one full settle after it starts (``rcon sim``, :func:`keep_settled`) and light ones on
    the same period.

Threading: call it from any one thread (the app: the GUI thread's frame clock).  ``pauses_ms`` (the last
50 settles' pause), ``settles``, ``full_settles`` and ``due`` are for tests and diagnostics.
"""

from __future__ import annotations

import asyncio
import gc
import time
from collections.abc import Callable

#: seconds between two light settles
SETTLE_EVERY = 60.0


class CollectorPolicy:
    """When to run :meth:`settle`: on request (:meth:`soon`) and every ``every`` seconds (:meth:`poll`)."""

    def __init__(self, every: float = SETTLE_EVERY, clock: Callable[[], float] = time.monotonic) -> None:
        self.every = every
        self._clock = clock
        self._last = clock()
        self._due: float | None = None
        self._due_full = False
        self.settles = 0
        self.full_settles = 0
        self.pauses_ms: list[float] = []

    def settle(self, *, full: bool = False) -> float:
        """Collect, then freeze what survived; ``full``: unfreeze first, so every object is walked once
        (cyclic garbage among earlier frozen objects is freed).  Returns the pause in ms."""
        t = time.perf_counter()
        if full:
            gc.unfreeze()
        gc.collect()
        gc.freeze()
        ms = (time.perf_counter() - t) * 1000
        self.settles += 1
        self.full_settles += full
        self.pauses_ms.append(ms)
        del self.pauses_ms[:-50]
        self._last = self._clock()
        return ms

    def soon(self, delay: float = 0.0, *, full: bool = False) -> None:
        """Settle at the first :meth:`poll` at least ``delay`` s from now (the earliest request wins; a
        full request stays full)."""
        due = self._clock() + delay
        self._due = due if self._due is None else min(self._due, due)
        self._due_full = self._due_full or full

    @property
    def due(self) -> float | None:
        """When the requested settle is due (the clock's time), or None when none is asked for."""
        return self._due

    def poll(self, now: float | None = None) -> bool:
        """Settle when one was asked for and is due, or the period passed; True when it did."""
        now = self._clock() if now is None else now
        if self._due is not None and now >= self._due:
            full, self._due, self._due_full = self._due_full, None, False
            self.settle(full=full)
            return True
        if now - self._last >= self.every:
            self.settle()
            return True
        return False


async def keep_settled(policy: CollectorPolicy | None = None) -> None:
    """For a process run by an asyncio loop (the sim): a full settle now, a light one every
    ``policy.every`` seconds after, until cancelled."""
    policy = policy if policy is not None else CollectorPolicy()
    policy.settle(full=True)
    while True:
        await asyncio.sleep(policy.every)
        policy.settle()
