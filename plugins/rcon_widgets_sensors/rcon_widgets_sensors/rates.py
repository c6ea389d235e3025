"""Bytes and frames per second over the last few seconds (no Qt; any thread)."""

from __future__ import annotations

import collections
import threading
import time
from collections.abc import Callable

__all__ = ["RateMeter", "human_rate", "human_bits"]


class RateMeter:
    """Counts ``add(nbytes)`` calls and their bytes over a sliding ``window`` (seconds).

    ``add`` is a lock, a clock read and a deque append: cheap enough for the bridge loop.
    """

    def __init__(self, window: float = 2.0, clock: Callable[[], float] = time.monotonic) -> None:
        self.window = window
        self._clock = clock
        self._lock = threading.Lock()
        self._events: collections.deque[tuple[float, int]] = collections.deque()
        self._bytes = 0
        self.total_bytes = 0
        self.total_count = 0

    def add(self, nbytes: int) -> None:
        now = self._clock()
        with self._lock:
            self._events.append((now, nbytes))
            self._bytes += nbytes
            self.total_bytes += nbytes
            self.total_count += 1
            self._trim(now)

    def _trim(self, now: float) -> None:
        ev = self._events
        while ev and now - ev[0][0] > self.window:
            self._bytes -= ev.popleft()[1]

    def rates(self) -> tuple[float, float]:
        """(bytes per second, items per second) over the window; (0, 0) before two items came."""
        now = self._clock()
        with self._lock:
            self._trim(now)
            ev = self._events
            if len(ev) < 2:
                return 0.0, 0.0
            span = max(now - ev[0][0], ev[-1][0] - ev[0][0], 1e-6)
            # the first item opens the span: its bytes came before it
            return (self._bytes - ev[0][1]) / span, (len(ev) - 1) / span


def human_rate(bytes_per_s: float) -> str:
    """``812 B/s``, ``64 kB/s``, ``9.2 MB/s`` (decimal units, as links are sold)."""
    if bytes_per_s < 1000:
        return f"{bytes_per_s:.0f} B/s"
    if bytes_per_s < 1_000_000:
        return f"{bytes_per_s / 1000:.0f} kB/s" if bytes_per_s >= 10_000 else f"{bytes_per_s / 1000:.1f} kB/s"
    return f"{bytes_per_s / 1_000_000:.1f} MB/s"


def human_bits(bytes_per_s: float) -> str:
    """A bit rate: ``480 kbit/s``, ``2.4 Mbit/s``."""
    bits = bytes_per_s * 8
    if bits < 1_000_000:
        return f"{bits / 1000:.0f} kbit/s"
    return f"{bits / 1_000_000:.1f} Mbit/s"
