"""Stall detection and command freshness: a command never leaves the client late, a stalled link is seen.

Decisions:

Probes
    A WebSocket ping goes out every ``probe_interval`` (a quarter of ``stall_timeout``, 0.25 s by default)
    whenever none is in flight; its pong confirms that everything written before it reached the server.
    :class:`LinkWatch` keeps that bookkeeping (no I/O): when the ping in flight was sent, when the last
    answered one was sent, when the last freshness-limited command was written, and how long the
    transport's write buffer has not drained.

DEGRADED
    A ping unanswered for ``stall_timeout`` (1 s), or a write buffer that has not drained for as long,
    means the link is stalled although TCP has not noticed (a Wi-Fi stall sends no FIN nor RST).  The
    client then reports ``ConnectionState.DEGRADED`` -- a state of its own so that every state listener
    sees it and treats it as "not usable", while ``client.connected`` stays True (the socket is open and
    subscriptions stay in place; nothing is restored when the link recovers).  The pong that finally
    arrives brings the state back to CONNECTED; ``pong_timeout`` still drops the link for good.

Freshness limits (``max_age``)
    Each publisher has one: by default 0.25 s for non-latched topics (a command), None (no limit) for
    latched ones (a state).  A command is never handed to the transport after its limit: one published
    while the link is DEGRADED, or while a ping has been unanswered for longer than the command's limit
    (the link cannot carry it in time), is dropped at once; one waiting in the outgoing queue (the
    transport was above its high-water mark) past its limit is dropped when its turn comes.  Both are
    counted (``Publisher.dropped``, ``client.stats.stale_dropped``).

Commands already written when a stall starts
    TCP cannot take back what it holds: commands written in the instant before a stall is detected would
    be delivered in one late burst when the link recovers.  So when the link is found stalled while
    commands written since the last answered ping are unconfirmed, the client *cuts* the connection with
    a TCP reset (``SO_LINGER`` 0, then abort): the kernel discards its unsent data and the robot never
    receives them; the client reconnects as after any drop (``client.stats.stall_cuts``).  A stalled
    link that carried no command only goes DEGRADED.  Left open: a stall shorter than ``stall_timeout``
    can still deliver the commands of its first few hundred ms late (by less than ``stall_timeout``).
"""

from __future__ import annotations

import asyncio
import enum
import math
import socket
import struct
import time
from collections.abc import Callable
from typing import Any

#: default freshness limit of a non-latched publisher (seconds)
DEFAULT_MAX_AGE = 0.25


class _Auto:
    __slots__ = ()

    def __repr__(self) -> str:
        return "AUTO"


#: ``max_age`` default: 0.25 s for a non-latched publisher, None for a latched one
AUTO: Any = _Auto()


def resolve_max_age(max_age: Any, latch: bool) -> float | None:
    """The freshness limit a publisher gets for ``max_age`` (``AUTO``, None or seconds > 0)."""
    if max_age is AUTO:
        return None if latch else DEFAULT_MAX_AGE
    if max_age is None:
        return None
    if isinstance(max_age, bool) or not isinstance(max_age, int | float) or not math.isfinite(max_age) \
            or max_age <= 0:
        raise ValueError(f"max_age must be a number of seconds > 0 or None, got {max_age!r}")
    return float(max_age)


class TimedFrame:
    """A command frame waiting in the outgoing queue with the time after which it must not be written."""

    __slots__ = ("data", "deadline", "pub")

    def __init__(self, data: bytes, deadline: float, pub: Any) -> None:
        self.data = data
        self.deadline = deadline
        self.pub = pub


class LinkWatch:
    """Liveness bookkeeping of one connection (times from ``time.monotonic``); no I/O of its own."""

    __slots__ = ("stall_timeout", "probe_interval", "probe_sent", "last_probe", "confirmed", "last_command",
                 "buffer_size", "buffer_since", "degraded")

    def __init__(self, stall_timeout: float, probe_interval: float, now: float) -> None:
        self.stall_timeout = stall_timeout
        self.probe_interval = probe_interval
        self.probe_sent: float | None = None  # the ping in flight
        self.last_probe = -math.inf  # when the last ping was sent
        self.confirmed = now  # everything written before this time reached the server
        self.last_command: float | None = None  # last freshness-limited write
        self.buffer_size = 0
        self.buffer_since: float | None = None  # write buffer non-empty and not shrinking since
        self.degraded = False

    def probe_due(self, now: float) -> bool:
        return self.probe_sent is None and now - self.last_probe >= self.probe_interval

    def sent(self, now: float) -> None:
        self.probe_sent = self.last_probe = now

    def answered(self, sent: float) -> None:
        if self.probe_sent == sent:
            self.probe_sent = None
        self.confirmed = max(self.confirmed, sent)

    def overdue(self, now: float) -> float:
        """How long the ping in flight has waited (0 when none is in flight)."""
        sent = self.probe_sent
        return 0.0 if sent is None else now - sent

    def command(self, now: float) -> None:
        self.last_command = now

    def at_risk(self) -> bool:
        """True when a command written since the last answered ping is not known to have arrived."""
        return self.last_command is not None and self.last_command > self.confirmed

    def buffer(self, size: int, now: float) -> None:
        """Record the transport's write buffer size; it is stuck when non-empty and not shrinking."""
        if size == 0:
            self.buffer_since = None
        elif self.buffer_since is None or size < self.buffer_size:
            self.buffer_since = now
        self.buffer_size = size

    def stalled(self, now: float) -> str | None:
        """Why the link looks stalled (a sentence), or None."""
        if self.overdue(now) >= self.stall_timeout:
            return f"no pong for {self.overdue(now):.1f} s"
        if self.buffer_since is not None and now - self.buffer_since >= self.stall_timeout:
            return f"{self.buffer_size} bytes not drained for {now - self.buffer_since:.1f} s"
        return None


def cut(transport: Any) -> None:
    """Close a connection with a TCP reset, so the kernel drops what it has not sent yet."""
    sock = transport.get_extra_info("socket")
    if sock is not None:
        try:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
        except OSError:
            pass
    transport.abort()


class LinkEvent(enum.StrEnum):
    """What the watchdog reports about one connection (a ``str`` too)."""

    LATENCY = "latency"  #: a pong came: the detail is the round trip (s)
    STALLED = "stalled"  #: nothing moves: the detail is why
    RECOVERED = "recovered"  #: it moves again
    CUT = "cut"  #: stalled with commands in flight: cut so they are never delivered late (detail: why)
    TIMEOUT = "timeout"  #: no pong within the timeout: dropped (detail: why)


#: ``report(event, detail) -> bool``: True when a stall counts (the link was CONNECTED)
Report = Callable[[LinkEvent, Any], bool]


async def watch_link(link: Any, watch: LinkWatch, pong_timeout: float, report: Report) -> None:
    """Probe one connection (a ``wslink.Link``) until it closes: pings, stall and recovery reports, the cut
    and the timeout."""
    probes: set[asyncio.Task[None]] = set()
    try:
        while True:
            now = time.monotonic()
            watch.buffer(link.buffered(), now)
            if watch.probe_due(now):
                watch.sent(now)
                task = asyncio.ensure_future(_probe(link, watch, now, report))
                probes.add(task)
                task.add_done_callback(probes.discard)
            if watch.overdue(now) >= pong_timeout:
                report(LinkEvent.TIMEOUT, f"no pong within {pong_timeout:g} s")
                link.abort()
                return
            why = watch.stalled(now)
            if why is not None and not watch.degraded:
                if report(LinkEvent.STALLED, why):
                    watch.degraded = True
                    if watch.at_risk():
                        report(LinkEvent.CUT, why)
                        link.cut()
                        return
            elif why is None and watch.degraded:
                watch.degraded = False
                report(LinkEvent.RECOVERED, None)
            await asyncio.sleep(watch.probe_interval / 2)
    finally:
        for task in probes:
            task.cancel()


async def _probe(link: Any, watch: LinkWatch, sent: float, report: Report) -> None:
    from websockets.exceptions import ConnectionClosed

    try:
        waiter = await link.ping()
        latency = await waiter
    except ConnectionClosed:
        return
    watch.answered(sent)
    report(LinkEvent.LATENCY, latency)
    if watch.degraded and watch.stalled(time.monotonic()) is None:
        watch.degraded = False
        report(LinkEvent.RECOVERED, None)
