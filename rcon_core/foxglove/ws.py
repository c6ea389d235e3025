"""The seam between the Foxglove link and its WebSocket library (``websockets`` today).

Everything the Foxglove client does with the connection goes through :func:`open_connection` and
:class:`FrameLink`, so moving this link onto another WebSocket library (the bridge's transport adapters)
touches this module alone.  Unlike the rosbridge link's ``wslink.Link`` it writes both text frames (JSON
ops) and binary frames (client messages, service call requests).

Decision: direct writes, in order
    As ``rcon_core/bridge/wslink.py``: a frame is handed to the transport before the call that made it
    returns unless frames are already queued or the transport is above its high-water mark; then it waits
    in a queue the writer task drains with ``ws.send``.  A command (a publish with a freshness limit)
    waiting in the queue carries its deadline and is dropped once it passed (``freshness.TimedFrame``).
"""

from __future__ import annotations

import asyncio
import ssl
import time
from collections import deque
from collections.abc import Awaitable, Callable
from typing import Any

from websockets.asyncio.client import ClientConnection, connect
from websockets.exceptions import ConnectionClosed
from websockets.protocol import State

from rcon_core.bridge.freshness import LinkWatch, TimedFrame, cut

_OPEN = State.OPEN
_monotonic = time.monotonic

__all__ = ["ConnectionClosed", "FrameLink", "open_connection"]


async def open_connection(url: str, subprotocols: list[str] | None, *, ssl_context: ssl.SSLContext | None,
                          open_timeout: float, max_size: int) -> ClientConnection:
    """Open one WebSocket connection offering ``subprotocols`` (the server's pick is ``ws.subprotocol``)."""
    return await connect(url, ssl=ssl_context, compression=None, ping_interval=None, open_timeout=open_timeout,
                         max_size=max_size, close_timeout=2,
                         subprotocols=[s for s in subprotocols] if subprotocols else None)  # type: ignore[misc]


def chosen_subprotocol(ws: ClientConnection) -> str | None:
    return ws.subprotocol


class FrameLink:
    """One open connection: text and binary frames out (now or queued, in order), the writer task."""

    def __init__(self, ws: ClientConnection, on_stale: Callable[[Any], None]) -> None:
        self.ws = ws
        self.recv: Callable[[], Awaitable[str | bytes]] = ws.recv
        self.queue: deque[str | bytes | TimedFrame] = deque()
        self.event = asyncio.Event()
        self.watch: LinkWatch | None = None
        self.degraded = False
        self.on_stale = on_stale
        protocol = getattr(ws, "protocol", None)
        transport = getattr(ws, "transport", None)
        self._direct = protocol is not None and transport is not None and hasattr(ws, "send_data")
        self._high = transport.get_write_buffer_limits()[1] if transport is not None else 0

    def _write_now(self, data: str | bytes) -> bool:
        if not self._direct:
            return False
        ws = self.ws
        transport = ws.transport
        if ws.protocol.state is not _OPEN or transport.is_closing() or transport.get_write_buffer_size() > self._high:
            return False
        if isinstance(data, str):
            ws.protocol.send_text(data.encode())
        else:
            ws.protocol.send_binary(data)
        ws.send_data()
        return True

    def write(self, data: str | bytes) -> None:
        if not self.queue and self._write_now(data):
            return
        self.queue.append(data)
        self.event.set()

    def send_command(self, data: bytes, pub: Any, max_age: float) -> bool:
        now = _monotonic()
        watch = self.watch
        if self.degraded or (watch is not None and watch.overdue(now) > max_age):
            return False
        if not self.queue and self._write_now(data):
            if watch is not None:
                watch.command(now)
        else:
            self.queue.append(TimedFrame(data, now + max_age, pub))
            self.event.set()
        return True

    async def run_writer(self) -> None:
        out, event, ws = self.queue, self.event, self.ws
        try:
            while True:
                while out:
                    item = out.popleft()
                    if isinstance(item, TimedFrame):
                        now = _monotonic()
                        if now > item.deadline or self.degraded:
                            self.on_stale(item.pub)
                            continue
                        if self.watch is not None:
                            self.watch.command(now)
                        item = item.data
                    await ws.send(item)
                event.clear()
                await event.wait()
        except ConnectionClosed:
            pass

    def drop_queue(self) -> int:
        n = len(self.queue)
        self.queue.clear()
        return n

    async def ping(self) -> Awaitable[float]:
        return await self.ws.ping()

    async def close(self) -> None:
        await self.ws.close()

    def abort(self) -> None:
        self.ws.transport.abort()

    def cut(self) -> None:
        cut(self.ws.transport)

    def buffered(self) -> int:
        return self.ws.transport.get_write_buffer_size()

    @property
    def close_reason(self) -> str:
        return self.ws.close_reason or str(self.ws.close_code or "no close frame")
