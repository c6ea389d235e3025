"""``Link``: the one adapter between the bridge and a ``websockets`` connection (it uses that library's
internals, so they are used here and nowhere else).

Decision: direct writes
    There is no batching and no timer: a frame (a publish, a subscribe...) is written to the transport
    before the call that made it returns, unless frames are already queued or the transport's buffer is
    above its high-water mark; then it waits in a queue that the writer task (:meth:`Link.run_writer`)
    drains with ``ws.send`` (which waits for the transport), so frames always leave in order.  asyncio
    turns Nagle off on TCP sockets.

    The direct write does what ``ws.send`` does minus the waiting: websockets' Sans-I/O protocol object
    (``ws.protocol.send_text``) builds the frame and ``ws.send_data()`` hands it to the transport.  Those
    two are internals of ``websockets.asyncio.connection.Connection`` (tested with websockets 13-15); when
    a version lacks them, :func:`direct_writer` returns None and every frame goes through ``ws.send``.

Decision: commands and their freshness limit (see ``freshness.py``)
    A frame with a freshness limit (:meth:`Link.send_command`) is refused at once while the link is
    DEGRADED or a ping has been unanswered for longer than the limit; when it has to wait in the queue it
    carries its deadline (:class:`~rcon_core.bridge.freshness.TimedFrame`) and the writer drops it once
    the deadline passed (``on_stale(pub)`` counts it).

Decision: looking into the receive queue
    :meth:`Link.waiting` lists the frames websockets has received but ``recv`` has not returned yet (its
    ``recv_messages`` assembler, an internal; an empty list when a version lacks it), so the read loop can
    skip a stale frame of a latest-only topic (``latest.py``).  It only reads that queue.

Everything else the bridge does with the connection goes through :class:`Link` too (``ping``, ``close``,
``abort``, ``cut``, the write buffer size for the stall watch), so no other module touches ``ws`` or its
transport.

Test hooks (public, documented): ``link.queued`` (frames waiting for the writer), ``link.buffered()`` (bytes
in the transport's write buffer), ``link.socket`` (the TCP socket).
"""

from __future__ import annotations

import asyncio
import socket as _socket
import time
from collections import deque
from collections.abc import Awaitable, Callable
from typing import Any

from websockets.asyncio.client import ClientConnection
from websockets.exceptions import ConnectionClosed
from websockets.frames import Opcode
from websockets.protocol import State

from .freshness import LinkWatch, TimedFrame, cut

_OPEN = State.OPEN
_DATA = (Opcode.TEXT, Opcode.BINARY)
_monotonic = time.monotonic


def direct_writer(ws: ClientConnection) -> Callable[[bytes], bool] | None:
    """A function that writes one text frame to ``ws`` synchronously and returns True, or returns False
    when it cannot right now (the connection is not open, or the transport is above its high-water mark:
    then the caller queues the frame for ``ws.send``, which waits for the drain).  None when this
    websockets version lacks the pieces (every frame then goes through ``ws.send``)."""
    protocol = getattr(ws, "protocol", None)
    flush = getattr(ws, "send_data", None)
    transport = getattr(ws, "transport", None)
    if protocol is None or flush is None or transport is None or not hasattr(protocol, "send_text"):
        return None
    buffered = transport.get_write_buffer_size
    closing = transport.is_closing
    high = transport.get_write_buffer_limits()[1]

    def write_now(data: bytes) -> bool:
        if protocol.state is not _OPEN or closing() or buffered() > high:
            return False
        protocol.send_text(data)
        flush()
        return True

    return write_now


class Link:
    """One open connection: frames out (now or queued, in order), the writer task, the stall watch."""

    __slots__ = ("ws", "recv", "queue", "event", "write_now", "watch", "degraded", "on_stale")

    def __init__(self, ws: ClientConnection, on_stale: Callable[[Any], None]) -> None:
        self.ws = ws
        #: ``await recv()``: the next frame (websockets' own method: no wrapper on the read path)
        self.recv: Callable[[], Awaitable[str | bytes]] = ws.recv
        self.queue: deque[bytes | TimedFrame] = deque()
        self.event = asyncio.Event()
        self.write_now = direct_writer(ws)
        self.watch: LinkWatch | None = None  # set by the client's pinger when stall detection is on
        self.degraded = False  # the client's state is DEGRADED: commands are refused
        self.on_stale = on_stale  # ``on_stale(pub)``: a queued command passed its deadline (already counted sent)

    # -- writing -----------------------------------------------------------------------------------

    def write(self, data: bytes) -> None:
        """Hand one encoded frame to the connection: written at once when nothing is queued and the
        transport's buffer is below its high-water mark, else queued for the writer task."""
        if not self.queue:
            write_now = self.write_now
            if write_now is not None and write_now(data):
                return
        self.queue.append(data)
        self.event.set()

    def send_command(self, data: bytes, pub: Any, max_age: float) -> bool:
        """Write a frame with a freshness limit (see the module docstring); False when it was refused
        because the link cannot carry it in time."""
        now = _monotonic()
        watch = self.watch
        if self.degraded or (watch is not None and watch.overdue(now) > max_age):
            return False
        write_now = self.write_now
        if not self.queue and write_now is not None and write_now(data):
            if watch is not None:
                watch.command(now)
        else:
            self.queue.append(TimedFrame(data, now + max_age, pub))
            self.event.set()
        return True

    async def run_writer(self) -> None:
        """Drain the queue with ``ws.send`` (waits for the transport) until the connection closes."""
        out = self.queue
        event = self.event
        ws = self.ws
        try:
            while True:
                while out:
                    item = out.popleft()
                    if isinstance(item, TimedFrame):  # a command: never written after its freshness limit
                        now = _monotonic()
                        if now > item.deadline or self.degraded:
                            self.on_stale(item.pub)
                            continue
                        if self.watch is not None:
                            self.watch.command(now)
                        item = item.data
                    await ws.send(item, text=True)
                event.clear()
                await event.wait()
        except ConnectionClosed:
            pass

    def drop_queue(self) -> int:
        """Forget every frame still queued (the link is gone); returns how many."""
        n = len(self.queue)
        self.queue.clear()
        return n

    # -- reading and the connection ----------------------------------------------------------------

    def waiting(self) -> list[bytes]:
        """The payloads of the complete text and binary frames already received and not yet read by
        ``recv`` (websockets' receive queue), oldest first; read only, for ``latest.py``."""
        assembler = getattr(self.ws, "recv_messages", None)
        frames = getattr(getattr(assembler, "frames", None), "queue", None)
        if not frames:
            return []
        return [f.data for f in frames if f.fin and f.opcode in _DATA]

    async def ping(self) -> Awaitable[float]:
        """Send a WebSocket ping; the result is a waiter that gives the round trip in seconds."""
        return await self.ws.ping()

    async def close(self) -> None:
        await self.ws.close()

    def abort(self) -> None:
        """Drop the connection at once (no close handshake)."""
        self.ws.transport.abort()

    def cut(self) -> None:
        """Drop the connection with a TCP reset, so the kernel discards what it has not sent yet."""
        cut(self.ws.transport)

    def release(self) -> None:
        """The connection is over: free what it held now. websockets' protocol object and its frame parser
        (a generator whose frame refers back to the protocol) form a reference cycle holding the read
        buffer and the last frames; the app's collector policy freezes long-lived objects
        (``rcon_core/gcpolicy.py``), and frozen cyclic garbage waits for a full settle, so every dropped
        connection kept its buffers (0.85 MB per reconnect). Closing the parser breaks the cycle and
        reference counting frees them at once. Idempotent; a websockets version without these parts is
        left alone."""
        self.queue.clear()
        self.write_now = None
        protocol = getattr(self.ws, "protocol", None)
        parser = getattr(protocol, "parser", None)
        close = getattr(parser, "close", None)
        if callable(close):
            try:
                close()
            except Exception:  # noqa: BLE001 - a parser that cannot be closed: the collector frees it later
                pass
        reader = getattr(protocol, "reader", None)
        buffer = getattr(reader, "buffer", None)
        if isinstance(buffer, bytearray):
            buffer.clear()
        events = getattr(protocol, "events", None)
        if isinstance(events, list):
            events.clear()
        if protocol is not None and getattr(protocol, "parser_exc", None) is not None:
            protocol.parser_exc = None  # its traceback holds the parser's frame (and the protocol) too

    # -- test hooks ----------------------------------------------------------------------------------

    @property
    def queued(self) -> int:
        """How many frames wait for the writer task."""
        return len(self.queue)

    def buffered(self) -> int:
        """Bytes in the transport's write buffer."""
        return self.ws.transport.get_write_buffer_size()

    @property
    def socket(self) -> _socket.socket | None:
        return self.ws.transport.get_extra_info("socket")
