"""Bytes in, by topic: what each subscription costs the link (no Qt).

Decision: counted where messages come in, read by anyone
    :class:`Traffic` is written only on the bridge's loop as messages come in (``receive.py``,
    ``inbound.py``; on the hot path the count is inlined: two additions to slots of the topic's
    :class:`Tally`, which its ``TopicEntry`` keeps as ``tally``, no dict lookup), by the frame's
    size as it came off the socket (JSON text or CBOR, before decoding; a frame skipped as stale is counted too: it crossed the link). Publishes count under their
    topic, everything else under its op in brackets (``(fragment)``, ``(service_response)``...). At most
    :data:`MAX_KEYS` names are kept; the rest add up under ``(other topics)``, so a server inventing topic
    names cannot grow it. Readers on other threads take :meth:`Traffic.snapshot` (copies made under the GIL,
    no lock on the hot path) and turn two snapshots into rates (:class:`TrafficRates`).
"""

from __future__ import annotations

import collections
import time
from collections.abc import Callable
from typing import Any

__all__ = ["Tally", "Traffic", "TrafficRates", "MAX_KEYS", "rate_text"]

#: names counted one by one; more add up under OTHER
MAX_KEYS = 500
OTHER = "(other topics)"


class Tally:
    """One name's counts: bytes and frames received.  The hot path adds to a subscribed topic's in place (its
    ``TopicEntry`` keeps it as ``tally``): two additions to slots, no lookup."""

    __slots__ = ("nbytes", "frames")

    def __init__(self) -> None:
        self.nbytes = 0
        self.frames = 0


class Traffic:
    """Bytes and frames received per topic (cumulative, since the connection object was made)."""

    __slots__ = ("counts",)

    def __init__(self) -> None:
        #: name -> its :class:`Tally`; every frame counts under exactly one name, so the totals are its sums
        #: (summed when read: two additions fewer per message on the hot path)
        self.counts: dict[str, Tally] = {}

    @property
    def total_bytes(self) -> int:
        return sum(v.nbytes for v in list(self.counts.values()))

    @property
    def total_frames(self) -> int:
        return sum(v.frames for v in list(self.counts.values()))

    def count(self, m: Any, size: int) -> None:
        """A decoded frame ``m`` of ``size`` bytes (the read loop; never raises)."""
        try:
            op = m["op"]
            key = m["topic"] if op == "publish" else f"({op})" if isinstance(op, str) else "(other)"
        except (KeyError, TypeError, IndexError):
            key = "(other)"
        self.count_name(key if isinstance(key, str) else "(other)", size)

    def count_name(self, key: str | None, size: int) -> None:
        entry = self.row(key or "(other)")
        entry.nbytes += size
        entry.frames += 1

    def row(self, key: str) -> Tally:
        """The :class:`Tally` that ``key``'s frames are added to (:data:`OTHER`'s once :data:`MAX_KEYS` names
        are kept).  The hot path keeps a topic's on its ``TopicEntry`` (``tally``) and adds to it in place: no
        dict lookup per message."""
        entry = self.counts.get(key)
        if entry is None:
            if len(self.counts) >= MAX_KEYS:
                key = OTHER
            entry = self.counts.setdefault(key, Tally())
        return entry

    def snapshot(self) -> tuple[int, dict[str, tuple[int, int]]]:
        """``(total bytes, {name: (bytes, frames)})`` now (any thread)."""
        # one C-level copy of the dict (atomic under the GIL), then each tally's two counts
        counts = {k: (v.nbytes, v.frames) for k, v in dict(self.counts).items()}
        return sum(v[0] for v in counts.values()), counts


class TrafficRates:
    """Rates over the last ``window`` seconds from snapshots taken by :meth:`update` (the reader's thread).

    ``source`` changing (a new connection object) starts over. ``total`` is bytes per second; ``topics``
    ``[(name, bytes/s, messages/s)]``, biggest first, names that brought nothing in the window left out.
    """

    def __init__(self, window: float = 2.0, clock: Callable[[], float] = time.monotonic) -> None:
        self.window = window
        self._clock = clock
        self._source: Any = None
        self._history: collections.deque[tuple[float, int, dict[str, tuple[int, int]]]] = collections.deque()
        self.total = 0.0
        self.topics: list[tuple[str, float, float]] = []

    def update(self, traffic: Traffic | None) -> None:
        if traffic is not self._source:
            self._source = traffic
            self._history.clear()
            self.total, self.topics = 0.0, []
        if traffic is None:
            return
        now = self._clock()
        total, counts = traffic.snapshot()
        hist = self._history
        hist.append((now, total, counts))
        while len(hist) > 2 and now - hist[1][0] >= self.window:
            hist.popleft()
        t0, total0, counts0 = hist[0]
        span = now - t0
        if span <= 0:
            return
        self.total = (total - total0) / span
        rows = []
        for name, (nbytes, frames) in counts.items():
            b0, f0 = counts0.get(name, (0, 0))
            if nbytes > b0:
                rows.append((name, (nbytes - b0) / span, (frames - f0) / span))
        rows.sort(key=lambda r: -r[1])
        self.topics = rows


def rate_text(bytes_per_s: float) -> str:
    """``812 B/s``, ``64 kB/s``, ``9.2 MB/s`` (decimal units, as links are sold)."""
    if bytes_per_s < 1000:
        return f"{bytes_per_s:.0f} B/s"
    if bytes_per_s < 10_000:
        return f"{bytes_per_s / 1000:.1f} kB/s"
    if bytes_per_s < 1_000_000:
        return f"{bytes_per_s / 1000:.0f} kB/s"
    return f"{bytes_per_s / 1_000_000:.1f} MB/s"
