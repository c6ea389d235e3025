"""Loopback servers for reliability tests and the soak benchmark (no Qt, no mocks: real sockets).

- :class:`HostileServer`: a scriptable rosbridge-protocol WebSocket server that sends whatever frames a
  test wants (invalid UTF-8, deep JSON, bad png/cbor...) and records every op the client sent.
- :class:`StallProxy`: a TCP proxy in front of any server that can *stall* (forward nothing, like a Wi-Fi
  link that stops carrying packets, with no FIN nor RST) and *cut* (reset every connection and refuse new
  ones for a while, like a link that drops).

Both listen on 127.0.0.1 only, on a free port.
"""

from __future__ import annotations

import asyncio
import contextlib
import socket
import struct
from collections.abc import Callable, Iterable
from typing import Any

import orjson
from websockets.asyncio.server import ServerConnection, serve

Frame = str | bytes


class HostileServer:
    """A rosbridge-protocol server under the test's control.

    ``received`` holds every op a client sent (parsed), ``connections`` counts accepted connections.
    ``on_subscribe(op) -> frames`` (optional) answers a subscribe with frames (each a ``str``, ``bytes``
    or ``(payload, text)``); ``send(frame, text=None)``
    pushes a frame to the current connection (``bytes`` with ``text=True`` is sent as a text frame without
    any UTF-8 check: the way to send invalid UTF-8).  ``drop()`` closes the current connection.
    """

    def __init__(self) -> None:
        self.received: list[dict[str, Any]] = []
        self.connections = 0
        self.ws: ServerConnection | None = None
        self.on_subscribe: Callable[[dict[str, Any]], Iterable[Frame | tuple[Frame, bool]]] | None = None
        self._server: Any = None
        self._changed = asyncio.Event()

    @property
    def url(self) -> str:
        return f"ws://127.0.0.1:{self.port}"

    async def start(self) -> HostileServer:
        self._server = await serve(self._handle, "127.0.0.1", 0, max_size=None, compression=None,
                                   ping_interval=None)
        self.port = self._server.sockets[0].getsockname()[1]
        return self

    async def stop(self) -> None:
        if self._server is not None:
            self._server.close()
            await self._server.wait_closed()

    async def __aenter__(self) -> HostileServer:
        return await self.start()

    async def __aexit__(self, *exc: object) -> None:
        await self.stop()

    async def _handle(self, ws: ServerConnection) -> None:
        self.ws = ws
        self.connections += 1
        self._notify()
        try:
            async for message in ws:
                try:
                    op = orjson.loads(message)
                except orjson.JSONDecodeError:
                    continue
                if not isinstance(op, dict):
                    continue
                self.received.append(op)
                self._notify()
                if op.get("op") == "subscribe" and self.on_subscribe is not None:
                    for frame in self.on_subscribe(op):
                        if isinstance(frame, tuple):  # (payload, text)
                            await self._send(ws, *frame)
                        else:
                            await self._send(ws, frame)
        except Exception:  # noqa: BLE001 - a dropped connection ends this handler, nothing else
            pass
        finally:
            if self.ws is ws:
                self.ws = None
            self._notify()

    def _notify(self) -> None:
        self._changed.set()
        self._changed = asyncio.Event()

    @staticmethod
    async def _send(ws: ServerConnection, frame: Frame, text: bool | None = None) -> None:
        if text is None:
            text = isinstance(frame, str)
        await ws.send(frame, text=text)

    async def send(self, frame: Frame | dict[str, Any], text: bool | None = None) -> None:
        """Send one frame (a dict is sent as JSON text) on the current connection."""
        ws = self.ws
        if ws is None:
            raise ConnectionError("no client is connected")
        if isinstance(frame, dict):
            frame = orjson.dumps(frame).decode()
        await self._send(ws, frame, text)

    async def drop(self) -> None:
        if self.ws is not None:
            await self.ws.close()

    def ops(self, op: str, **match: Any) -> list[dict[str, Any]]:
        return [m for m in self.received if m.get("op") == op and all(m.get(k) == v for k, v in match.items())]

    async def wait(self, predicate: Callable[[], bool], timeout: float = 5.0) -> None:
        async with asyncio.timeout(timeout):
            while not predicate():
                await self._changed.wait()

    async def wait_for(self, op: str, count: int = 1, timeout: float = 5.0, **match: Any) -> list[dict[str, Any]]:
        await self.wait(lambda: len(self.ops(op, **match)) >= count, timeout)
        return self.ops(op, **match)


class _Pipe:
    """One direction of a proxied connection."""

    def __init__(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        self.reader, self.writer = reader, writer
        self.held: list[bytes] = []
        self.reset = False  # the source reset the connection (its unacked data died with it)
        self.eof = False


class StallProxy:
    """A loopback TCP proxy to ``(host, port)`` that can stall and cut.

    ``stall()``: from now on nothing is forwarded in either direction.  Bytes that arrive meanwhile are
    held, as a real link's unacknowledged data waits in the sender's kernel: ``resume()`` delivers them --
    unless their sender reset the connection during the stall (a TCP reset throws away what the sender's
    kernel had not got acknowledged, so the proxy discards it too and resets the other side).  ``cut()``
    resets every connection; ``refuse(True)`` makes new connections fail until ``refuse(False)``.
    ``discarded`` counts bytes thrown away that way, ``forwarded`` bytes delivered.
    """

    def __init__(self, host: str, port: int) -> None:
        self.target = (host, port)
        self.stalled = False
        self.refusing = False
        self.discarded = 0
        self.forwarded = 0
        self.connections = 0
        self._resumed = asyncio.Event()
        self._resumed.set()
        self._links: set[tuple[asyncio.StreamWriter, asyncio.StreamWriter]] = set()
        self._server: asyncio.Server | None = None
        self._tasks: set[asyncio.Task[Any]] = set()
        self._pipes: set[tuple[_Pipe, _Pipe]] = set()

    @property
    def port(self) -> int:
        assert self._server is not None
        return self._server.sockets[0].getsockname()[1]

    @property
    def url(self) -> str:
        return f"ws://127.0.0.1:{self.port}"

    async def start(self) -> StallProxy:
        self._server = await asyncio.start_server(self._accept, "127.0.0.1", 0)
        return self

    async def stop(self) -> None:
        self.cut()
        if self._server is not None:
            self._server.close()
            await self._server.wait_closed()
        for task in list(self._tasks):
            task.cancel()
        await asyncio.gather(*self._tasks, return_exceptions=True)

    async def __aenter__(self) -> StallProxy:
        return await self.start()

    async def __aexit__(self, *exc: object) -> None:
        await self.stop()

    def stall(self) -> None:
        self.stalled = True
        self._resumed.clear()

    def resume(self) -> None:
        """End the stall: deliver what each side sent meanwhile, unless that side reset the connection."""
        self.stalled = False
        for pipe, other in list(self._pipes):
            held, pipe.held = pipe.held, []
            if pipe.reset:
                self.discarded += sum(map(len, held))
                _reset(pipe.writer)
                _reset(other.writer)
                continue
            for chunk in held:
                pipe.writer.write(chunk)
                self.forwarded += len(chunk)
            if pipe.eof:
                with contextlib.suppress(OSError, RuntimeError):
                    pipe.writer.write_eof()
        self._resumed.set()

    def refuse(self, on: bool) -> None:
        self.refusing = on

    def cut(self) -> None:
        for a, b in list(self._links):
            _reset(a)
            _reset(b)
        self._links.clear()

    async def _accept(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        if self.stalled:  # a stalled link answers nothing: the connection waits for it to come back
            await self._resumed.wait()
        if self.refusing:
            _reset(writer)
            return
        try:
            up_reader, up_writer = await asyncio.open_connection(*self.target)
        except OSError:
            _reset(writer)
            return
        self.connections += 1
        link = (writer, up_writer)
        self._links.add(link)
        there, back = _Pipe(reader, up_writer), _Pipe(up_reader, writer)
        tasks = [asyncio.ensure_future(self._pump(there, back)), asyncio.ensure_future(self._pump(back, there))]
        self._tasks.update(tasks)
        try:
            await asyncio.gather(*tasks, return_exceptions=True)
        finally:
            self._tasks.difference_update(tasks)
            self._links.discard(link)
            _reset(writer)
            _reset(up_writer)

    async def _pump(self, pipe: _Pipe, other: _Pipe) -> None:
        """Copy ``pipe.reader`` to ``pipe.writer``; while stalled, hold it (``resume`` settles what is held)."""
        pipes = (pipe, other)
        self._pipes.add(pipes)
        try:
            while True:
                try:
                    data = await pipe.reader.read(65536)
                except (ConnectionError, OSError):
                    data, pipe.reset = b"", True
                if not data:
                    pipe.eof = True
                if self.stalled:
                    if data:
                        pipe.held.append(data)
                        continue
                    await self._resumed.wait()  # resume() delivers or discards what was held
                    return
                if pipe.reset:
                    _reset(pipe.writer)
                    _reset(other.writer)
                    return
                if pipe.eof:
                    with contextlib.suppress(OSError, RuntimeError):
                        pipe.writer.write_eof()
                    return
                await self._write(pipe.writer, data)
        finally:
            self._pipes.discard(pipes)

    async def _write(self, writer: asyncio.StreamWriter, data: bytes) -> None:
        writer.write(data)
        self.forwarded += len(data)
        try:
            await writer.drain()
        except (ConnectionError, OSError):
            pass


def _reset(writer: asyncio.StreamWriter) -> None:
    """Close with a TCP reset (SO_LINGER 0)."""
    sock = writer.get_extra_info("socket")
    if sock is not None:
        with contextlib.suppress(OSError):
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
    writer.transport.abort()


def png_data(payload: bytes, width: int, height: int) -> str:
    """The base64 ``data`` of a ``png`` frame: an 8-bit RGB PNG of ``width`` x ``height`` pixels whose bytes
    are ``payload`` padded with ``\\n`` (zlib squeezes the padding to almost nothing: a small frame may
    declare a huge image)."""
    import base64
    import zlib

    raw_len = width * height * 3
    data = payload + b"\n" * (raw_len - len(payload))
    stride = width * 3
    comp = zlib.compressobj(9)
    parts = [comp.compress(b"\x00" + data[row * stride:(row + 1) * stride]) for row in range(height)]
    parts.append(comp.flush())

    def chunk(kind: bytes, body: bytes) -> bytes:
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF)

    png = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
           + chunk(b"IDAT", b"".join(parts)) + chunk(b"IEND", b""))
    return base64.b64encode(png).decode("ascii")
