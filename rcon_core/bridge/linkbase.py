"""The transport-neutral half of a link (see ``transport.py`` for the decisions): :class:`Link` -- frames out,
now or queued in order, the writer task, commands and their freshness limit, the end of the connection --
and two helpers the adapters share, :class:`Drain` (write flow control) and :class:`Pings`.

A link carries text frames (``write``, the rosbridge protocol's JSON) and binary frames (``write_binary``;
the Foxglove protocol's client messages and service calls): a binary frame that has to wait in the queue
waits as a :class:`Binary`.  ``link.subprotocol`` is the WebSocket subprotocol the server picked among those
offered (``transport.open_link(subprotocols=...)``), or None.

Test hooks (public, documented): ``link.queued`` (frames waiting for the writer), ``link.buffered()`` (bytes
in the transport's write buffer), ``link.socket`` (the TCP socket), ``link.name`` (the transport).
"""

from __future__ import annotations

import asyncio
import socket as _socket
import time
from collections import deque
from collections.abc import Awaitable, Callable
from typing import Any

from .errors import LinkClosedError
from .freshness import LinkWatch, TimedFrame, cut

_monotonic = time.monotonic


class Binary(bytes):
    """A binary frame waiting in a link's queue (a text frame waits as its plain ``bytes``)."""

    __slots__ = ()


class Link:
    """One open connection: frames out (now or queued, in order), the writer task, the stall watch.

    An adapter subclasses it and provides :meth:`write_now`, :meth:`send_queued`, :meth:`drained`,
    :meth:`ping`, :meth:`close`, ``transport`` (the asyncio transport) and calls :meth:`lost` once when
    the connection is gone."""

    name = ""

    def __init__(self, on_stale: Callable[[Any], None]) -> None:
        self.queue: deque[bytes | TimedFrame] = deque()  # a binary frame waits as a ``Binary``
        self.event = asyncio.Event()
        self.watch: LinkWatch | None = None  # set by the client's pinger when stall detection is on
        self.degraded = False  # the client's state is DEGRADED: commands are refused
        self.on_stale = on_stale  # ``on_stale(pub)``: a queued command passed its deadline (already counted sent)
        self.transport: Any = None  # the asyncio transport under the WebSocket
        self.receiver: Any = None  # the ``receive.Receiver`` its messages go to
        self.close_code: int | None = None
        self.close_reason = ""
        #: the subprotocol the server picked in the handshake (None: none offered, or none picked)
        self.subprotocol: str | None = None
        self._closed: asyncio.Future[None] = asyncio.get_running_loop().create_future()

    # -- what an adapter provides ------------------------------------------------------------------

    def write_now(self, data: bytes, binary: bool = False) -> bool:
        """Write one text frame (a binary one when ``binary``) now and return True, or False when it cannot
        right now (the connection is not open, or the transport is above its high-water mark)."""
        raise NotImplementedError

    def send_queued(self, data: bytes, binary: bool = False) -> None:
        """Write one text frame (a binary one when ``binary``) whatever the buffer holds (the writer task waited for :meth:`drained`);
        raises :class:`LinkClosedError` when the connection is gone."""
        raise NotImplementedError

    async def drained(self) -> None:
        """Return once the transport's write buffer is below its high-water mark; raises
        :class:`LinkClosedError` when the connection is gone."""
        raise NotImplementedError

    async def ping(self) -> Awaitable[float]:
        """Send a WebSocket ping; the result is a waiter that gives the round trip in seconds (it raises
        :class:`LinkClosedError` when the connection goes first)."""
        raise NotImplementedError

    async def close(self) -> None:
        """The close handshake (bounded in time), then the connection is gone."""
        raise NotImplementedError

    def fail(self, code: int, reason: str) -> None:
        """Close at once with ``code`` (a protocol violation by the server, e.g. 1007 for invalid UTF-8)."""
        raise NotImplementedError

    # -- the connection's end ------------------------------------------------------------------------

    def lost(self, code: int | None, reason: str = "") -> None:
        """The adapter says the connection is gone (once): ``code`` of the close frame received, None
        when there was none (1006)."""
        if self._closed.done():
            return
        self.close_code = 1006 if code is None else code
        self.close_reason = reason or ""
        self._closed.set_result(None)
        self.event.set()  # wake the writer so it ends

    @property
    def is_closed(self) -> bool:
        return self._closed.done()

    def closed_error(self) -> LinkClosedError:
        return LinkClosedError(self.close_code or 1006, self.close_reason)

    async def wait_closed(self) -> None:
        """Return once the connection is gone."""
        await asyncio.shield(self._closed)

    # -- writing -----------------------------------------------------------------------------------

    def write(self, data: bytes) -> None:
        """Hand one encoded frame to the connection: written at once when nothing is queued and the
        transport's buffer is below its high-water mark, else queued for the writer task."""
        if not self.queue and self.write_now(data):
            return
        self.queue.append(data)
        self.event.set()

    def write_binary(self, data: bytes) -> None:
        """:meth:`write` for a binary frame."""
        if not self.queue and self.write_now(data, True):
            return
        self.queue.append(Binary(data))
        self.event.set()

    def send_command(self, data: bytes, pub: Any, max_age: float, binary: bool = False) -> bool:
        """Write a frame (a binary one when ``binary``) with a freshness limit (see the module docstring);
        False when it was refused because the link cannot carry it in time."""
        now = _monotonic()
        watch = self.watch
        if self.degraded or (watch is not None and watch.overdue(now) > max_age):
            return False
        if not self.queue and self.write_now(data, binary):
            if watch is not None:
                watch.command(now)
        else:
            self.queue.append(TimedFrame(Binary(data) if binary else data, now + max_age, pub))
            self.event.set()
        return True

    async def run_writer(self) -> None:
        """Drain the queue as the transport drains, until the connection closes."""
        out = self.queue
        event = self.event
        try:
            while not self.is_closed:
                while out:
                    await self.drained()
                    item = out.popleft()
                    if isinstance(item, TimedFrame):  # a command: never written after its freshness limit
                        now = _monotonic()
                        if now > item.deadline or self.degraded:
                            self.on_stale(item.pub)
                            continue
                        if self.watch is not None:
                            self.watch.command(now)
                        item = item.data
                    if item.__class__ is Binary:
                        self.send_queued(item, True)
                    else:
                        self.send_queued(item)
                event.clear()
                await event.wait()
        except LinkClosedError:
            pass

    def drop_queue(self) -> int:
        """Forget every frame still queued (the link is gone); returns how many."""
        n = len(self.queue)
        self.queue.clear()
        return n

    def release(self) -> None:
        """The connection is over: free what it held now (the queue; an adapter adds its own buffers), not
        at the collector's next full pass: the app's collector policy freezes long-lived objects
        (``rcon_core/gcpolicy.py``), so a dead connection's cyclic buffers would wait for a full settle
        (0.85 MB per reconnect, issue 22.7). Idempotent."""
        self.queue.clear()
        if self.receiver is not None:
            self.receiver.detach()  # its callbacks are this link's methods: a cycle through the receiver

    # -- the connection ----------------------------------------------------------------------------

    def abort(self) -> None:
        """Drop the connection at once (no close handshake)."""
        if self.transport is not None:
            self.transport.abort()

    def cut(self) -> None:
        """Drop the connection with a TCP reset, so the kernel discards what it has not sent yet."""
        if self.transport is not None:
            cut(self.transport)

    # -- test hooks ----------------------------------------------------------------------------------

    @property
    def queued(self) -> int:
        """How many frames wait for the writer task."""
        return len(self.queue)

    def buffered(self) -> int:
        """Bytes in the transport's write buffer."""
        return self.transport.get_write_buffer_size() if self.transport is not None else 0

    @property
    def socket(self) -> _socket.socket | None:
        return self.transport.get_extra_info("socket") if self.transport is not None else None


class Drain:
    """The write side's flow control for an adapter's asyncio protocol: ``pause_writing`` /
    ``resume_writing`` from the transport, ``await wait()`` until it is below its high-water mark."""

    __slots__ = ("paused", "_waiter")

    def __init__(self) -> None:
        self.paused = False
        self._waiter: asyncio.Future[None] | None = None

    def pause(self) -> None:
        self.paused = True

    def resume(self) -> None:
        self.paused = False
        waiter, self._waiter = self._waiter, None
        if waiter is not None and not waiter.done():
            waiter.set_result(None)

    def lost(self) -> None:
        self.resume()

    async def wait(self) -> None:
        if self.paused:
            if self._waiter is None or self._waiter.done():
                self._waiter = asyncio.get_running_loop().create_future()
            await self._waiter


class Pings:
    """Pings in flight and their pongs (a pong answers its ping and every earlier one, as RFC 6455 allows
    a peer to answer only the latest)."""

    __slots__ = ("_waiting", "_n")

    def __init__(self) -> None:
        self._waiting: dict[bytes, tuple[float, asyncio.Future[float]]] = {}
        self._n = 0

    def new(self) -> tuple[bytes, asyncio.Future[float]]:
        self._n += 1
        data = self._n.to_bytes(4, "big")
        fut: asyncio.Future[float] = asyncio.get_running_loop().create_future()
        self._waiting[data] = (_monotonic(), fut)
        return data, fut

    def pong(self, data: bytes) -> None:
        if data not in self._waiting:
            return  # an unsolicited pong: a heartbeat
        now = _monotonic()
        for key in list(self._waiting):
            sent, fut = self._waiting.pop(key)
            if not fut.done():
                fut.set_result(now - sent)
            if key == data:
                break

    def lost(self, error: BaseException) -> None:
        for _sent, fut in self._waiting.values():
            if not fut.done():
                fut.set_exception(error)
                fut.exception()  # retrieved: nobody may be waiting any more
        self._waiting.clear()
