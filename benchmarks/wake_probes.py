"""How late a thread of the app wakes for something due at a set time: what delays a teleop command.

Each probe keeps a 50 Hz schedule (like the teleop pad's ticker: a call late by more than a tenth of a
period restarts the schedule from its own time) and records how late each call ran after its due time,
and how much of that its thread spent waiting on a run queue for a core (Linux ``schedstat``); what is
left is the GIL (and, on the bridge loop, the callbacks that ran before it). All probes run at once in
the same process, so they are compared under the same load:

- ``loop_timer``: a timer on the bridge loop (``call_at``), where the pad's ticker ran before;
- ``thread``: a plain Python thread sleeping until the due time (the GIL and a core, nothing else);
- ``thread_raised``: the same after :func:`rcon_core.priority.raise_this_thread`;
- ``raised_to_loop``: a raised thread that hands the call to the bridge loop at the due time
  (``call_soon_threadsafe``): the lateness is measured when the loop runs it.
"""

from __future__ import annotations

import asyncio
import threading
import time
from typing import Any

PERIOD = 0.02


def run_queue_wait_s() -> float:
    """How long the calling thread has waited on a run queue for a core, in total (s; Linux, else 0)."""
    try:
        with open("/proc/thread-self/schedstat") as f:
            return int(f.read().split()[1]) / 1e9
    except (OSError, IndexError, ValueError):
        return 0.0


def _next_due(due: float, now: float) -> float:
    due += PERIOD
    return now + PERIOD if now - (due - PERIOD) > PERIOD * 0.1 else due


def pct(values: list[float], q: float) -> float:
    if not values:
        return float("nan")
    values = sorted(values)
    return values[min(len(values) - 1, int(q / 100 * len(values)))]


class WakeProbes:
    """The probes named in ``kinds`` (see the module docstring), on ``loop`` (the bridge loop)."""

    def __init__(self, loop: asyncio.AbstractEventLoop, kinds: tuple[str, ...]) -> None:
        self.loop = loop
        self.kinds = kinds
        self.rows: dict[str, list[tuple[float, float]]] = {k: [] for k in kinds}  # (late ms, core wait ms)
        self._stop = threading.Event()
        self._threads: list[threading.Thread] = []
        self._handle: Any = None

    def start(self) -> None:
        for kind in self.kinds:
            if kind == "loop_timer":
                self.loop.call_soon_threadsafe(self._loop_start)
            else:
                t = threading.Thread(target=self._thread, args=(kind,), name=f"bench-probe-{kind}", daemon=True)
                t.start()
                self._threads.append(t)

    def stop(self) -> None:
        self._stop.set()
        for t in self._threads:
            t.join(1)
        if self._handle is not None:
            self.loop.call_soon_threadsafe(self._handle.cancel)

    # -- on the bridge loop
    def _loop_start(self) -> None:
        due = time.monotonic() + PERIOD
        self._loop_arm(due, run_queue_wait_s())

    def _loop_arm(self, due: float, w0: float) -> None:
        # loop.time() is time.monotonic() for asyncio's loops
        self._handle = self.loop.call_at(due, self._loop_tick, due, w0)

    def _loop_tick(self, due: float, w0: float) -> None:
        now = time.monotonic()
        w1 = run_queue_wait_s()
        self.rows["loop_timer"].append(((now - due) * 1000, (w1 - w0) * 1000))
        if not self._stop.is_set():
            self._loop_arm(_next_due(due, now), w1)

    # -- on a thread of its own
    def _thread(self, kind: str) -> None:
        if kind in ("thread_raised", "raised_to_loop"):
            from rcon_core.priority import raise_this_thread

            raise_this_thread()
        rows = self.rows[kind]
        due = time.monotonic() + PERIOD
        while not self._stop.is_set():
            w0 = run_queue_wait_s()
            delay = due - time.monotonic()
            if delay > 0:
                time.sleep(delay)
            now = time.monotonic()
            if kind.endswith("_to_loop"):
                self.loop.call_soon_threadsafe(self._ran_on_loop, kind, due)
            else:
                rows.append(((now - due) * 1000, (run_queue_wait_s() - w0) * 1000))
            due = _next_due(due, now)

    def _ran_on_loop(self, kind: str, due: float) -> None:
        self.rows[kind].append(((time.monotonic() - due) * 1000, 0.0))

    def figures(self) -> dict[str, dict[str, float]]:
        """Per probe: p50/p99 lateness (ms), and over the worst 5 % the share spent waiting for a core."""
        out: dict[str, dict[str, float]] = {}
        for kind, rows in self.rows.items():
            late = sorted(rows)[int(0.95 * len(rows)):] if rows else []
            total = sum(a for a, _ in late)
            out[kind] = {"n": len(rows), "p50_ms": round(pct([a for a, _ in rows], 50), 2),
                         "p99_ms": round(pct([a for a, _ in rows], 99), 2),
                         "worst5pc_core_wait_share": round(sum(min(w, a) for a, w in late) / total, 2)
                         if total > 0 and not kind.endswith("_to_loop") else float("nan")}
        return out
