"""The websockets transport: the one module that imports ``websockets`` on the client side.

Decision: websockets' documented Sans-I/O protocol under RCON's own asyncio protocol
    ``websockets.client.ClientProtocol`` builds the handshake and the frames and parses what arrives;
    this module owns the socket (an ``asyncio.Protocol``), so the direct write, the write buffer size,
    the abort and the TCP-reset cut use the asyncio transport's public API, and nothing reaches into
    websockets' asyncio connection (its ``protocol``, ``transport`` or receive queue were used before).
    Only the public Sans-I/O API is used: ``connect``/``send_request``, ``receive_data``/``receive_eof``,
    ``events_received``, ``data_to_send``, ``send_text``/``send_ping``/``send_close``/``fail``,
    ``state``, ``close_code``/``close_reason``, ``handshake_exc``; tested with the range pinned in
    ``pyproject.toml`` (and the newest release by ``tox -e newest``).
    Frames are joined into messages here (websockets enforces ``max_size`` on the message); each whole
    message goes to the :class:`~rcon_core.bridge.receive.Receiver`.  No compression extension is
    offered (as before), and no HTTP proxy is used (the robot's link is direct).
"""

from __future__ import annotations

import asyncio
import ssl as _ssl
from typing import Any

from websockets.client import ClientProtocol
from websockets.exceptions import InvalidHandshake, InvalidMessage, InvalidStatus, InvalidURI
from websockets.frames import Frame, Opcode
from websockets.http11 import Response
from websockets.protocol import State
from websockets.typing import Subprotocol
from websockets.uri import parse_uri

from .errors import BadUrlError, HandshakeError, LinkClosedError
from .linkbase import Drain, Link, Pings

_OPEN = State.OPEN
_TEXT, _BINARY, _CONT, _PONG = Opcode.TEXT, Opcode.BINARY, Opcode.CONT, Opcode.PONG
#: the transport's write buffer high-water mark (websockets' own default write limit)
WRITE_LIMIT = 32 << 10
CLOSE_TIMEOUT = 2.0


class WebsocketsLink(Link):
    """One connection over websockets' Sans-I/O protocol."""

    name = "websockets"

    def __init__(self, protocol: ClientProtocol, receiver: Any, on_stale: Any) -> None:
        super().__init__(on_stale)
        self.protocol = protocol
        self.receiver = receiver
        self.drain = Drain()
        self.pings = Pings()
        self.opened: asyncio.Future[None] = asyncio.get_running_loop().create_future()
        self._parts: list[bytes] = []  # a fragmented message being joined
        self._text = False
        receiver.fail = self.fail

    # -- the asyncio protocol's events --------------------------------------------------------------

    def made(self, transport: asyncio.Transport) -> None:
        self.transport = transport
        transport.set_write_buffer_limits(high=WRITE_LIMIT)
        self.receiver.pause = transport.pause_reading
        self.receiver.resume = transport.resume_reading
        protocol = self.protocol
        protocol.send_request(protocol.connect())
        self._flush()

    def data(self, data: bytes) -> None:
        protocol = self.protocol
        protocol.receive_data(data)
        events = protocol.events_received()
        self._flush()
        if not events:
            return
        message = self.receiver.message
        last = len(events) - 1
        for i, event in enumerate(events):
            if not isinstance(event, Frame):
                if isinstance(event, Response):
                    self._opened()
                continue
            opcode = event.opcode
            if opcode is _TEXT or opcode is _BINARY:
                if event.fin:
                    message(event.data, opcode is _TEXT, i == last)
                else:
                    self._parts, self._text = [bytes(event.data)], opcode is _TEXT
            elif opcode is _CONT:
                self._parts.append(bytes(event.data))
                if event.fin:
                    whole, self._parts = b"".join(self._parts), []
                    message(whole, self._text, i == last)
            elif opcode is _PONG:
                self.pings.pong(bytes(event.data))
        if protocol.state is State.CLOSED:
            self.transport.close()

    def eof(self) -> None:
        try:
            self.protocol.receive_eof()
        except EOFError:
            return
        self._flush()

    def connection_lost(self, exc: BaseException | None) -> None:
        protocol = self.protocol
        if protocol.state is not State.CLOSED:
            try:
                protocol.receive_eof()
            except EOFError:  # eof_received came first
                pass
        self.drain.lost()
        self.receiver.lost()
        if not self.opened.done():
            error = HandshakeError("connection closed during the handshake", closed=True)
            error.__cause__ = exc
            self.opened.set_exception(error)
        code = protocol.close_code if protocol.close_code is not None else None
        self.lost(code, protocol.close_reason or "")
        self.pings.lost(self.closed_error())

    def _opened(self) -> None:
        exc = self.protocol.handshake_exc
        if self.opened.done():
            return
        if exc is None:
            self.opened.set_result(None)
            return
        self.opened.set_exception(handshake_error(exc))
        self.transport.close()

    def _flush(self) -> None:
        transport = self.transport
        for chunk in self.protocol.data_to_send():
            if chunk:
                transport.write(chunk)
            elif transport.can_write_eof():
                transport.write_eof()

    # -- Link --------------------------------------------------------------------------------------

    def write_now(self, data: bytes, binary: bool = False) -> bool:
        if self.protocol.state is not _OPEN or self.drain.paused or self.transport.is_closing():
            return False
        if binary:
            self.protocol.send_binary(data)
        else:
            self.protocol.send_text(data)
        for chunk in self.protocol.data_to_send():
            self.transport.write(chunk)
        return True

    def send_queued(self, data: bytes, binary: bool = False) -> None:
        if self.protocol.state is not _OPEN or self.transport.is_closing():
            raise self.closed_error()
        if binary:
            self.protocol.send_binary(data)
        else:
            self.protocol.send_text(data)
        self._flush()

    async def drained(self) -> None:
        if self.is_closed:
            raise self.closed_error()
        await self.drain.wait()
        if self.is_closed:
            raise self.closed_error()

    async def ping(self) -> asyncio.Future[float]:
        if self.protocol.state is not _OPEN:
            raise self.closed_error()
        data, waiter = self.pings.new()
        self.protocol.send_ping(data)
        self._flush()
        return waiter

    async def close(self) -> None:
        if self.protocol.state is _OPEN:
            self.protocol.send_close(1000)
            self._flush()
        try:
            await asyncio.wait_for(self.wait_closed(), CLOSE_TIMEOUT)
        except TimeoutError:
            self.abort()
        if not self.is_closed and self.transport is not None:
            self.transport.close()

    def fail(self, code: int, reason: str) -> None:
        if self.protocol.state is _OPEN:
            self.protocol.fail(code, reason)
            self._flush()
        if self.transport is not None:
            self.transport.close()


    def release(self) -> None:
        """Also the websockets protocol's buffers: its frame parser (a generator whose frame refers back to
        the protocol) keeps a reference cycle holding the read buffer and the last frames; closing the
        parser breaks it, so reference counting frees them at once."""
        super().release()
        protocol = self.protocol
        parser = getattr(protocol, "parser", None)
        close = getattr(parser, "close", None)
        if callable(close):
            try:
                close()
            except Exception:  # noqa: BLE001 - a parser that cannot be closed: the collector frees it later
                pass
        if getattr(protocol, "parser_exc", None) is not None:
            protocol.parser_exc = None  # its traceback holds the parser's frame (and the protocol) too


class _Protocol(asyncio.Protocol):
    """The asyncio side of a :class:`WebsocketsLink`."""

    def __init__(self, link: WebsocketsLink) -> None:
        self.link = link

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self.link.made(transport)  # type: ignore[arg-type]

    def data_received(self, data: bytes) -> None:
        self.link.data(data)

    def eof_received(self) -> bool | None:
        self.link.eof()
        return None  # close the transport

    def connection_lost(self, exc: Exception | None) -> None:
        self.link.connection_lost(exc)

    def pause_writing(self) -> None:
        self.link.drain.pause()

    def resume_writing(self) -> None:
        self.link.drain.resume()


def handshake_error(exc: BaseException) -> BaseException:
    """RCON's own error for what websockets raised opening a connection (``reasons.describe`` words RCON's
    errors only): ``HandshakeError`` (its ``__cause__`` the TLS error behind it, if any) or ``BadUrlError``;
    anything else as it is.  Also used by the Foxglove link's seam (``rcon_core/foxglove/ws.py``)."""
    if isinstance(exc, InvalidURI):
        return BadUrlError(f"not a valid rosbridge URL: {exc}")
    if isinstance(exc, InvalidStatus):
        error = HandshakeError(f"HTTP {exc.response.status_code}", status=exc.response.status_code)
    elif isinstance(exc, InvalidMessage):
        error = HandshakeError("no valid HTTP answer", closed=isinstance(exc.__cause__, EOFError))
    elif isinstance(exc, InvalidHandshake):
        error = HandshakeError(str(exc))
    else:
        return exc
    error.__cause__ = exc.__cause__ if isinstance(exc.__cause__, _ssl.SSLError) else exc
    return error


async def open_websockets(url: str, receiver: Any, on_stale: Any, *, ssl: _ssl.SSLContext | None,
                          open_timeout: float, max_size: int, subprotocols: list[str] | None = None) -> WebsocketsLink:
    """Open one connection (see ``transport.open_link``); ``subprotocols`` are offered, the server's pick
    is ``link.subprotocol`` (websockets refuses a pick that was not offered)."""
    try:
        uri = parse_uri(url)
    except InvalidURI as exc:
        raise BadUrlError(f"not a valid rosbridge URL: {exc}") from None
    protocol = ClientProtocol(uri, max_size=max_size,
                              subprotocols=[Subprotocol(s) for s in subprotocols] if subprotocols else None)
    link = WebsocketsLink(protocol, receiver, on_stale)
    loop = asyncio.get_running_loop()
    tls = (ssl or _ssl.create_default_context()) if uri.secure else None

    async def go() -> None:
        await loop.create_connection(lambda: _Protocol(link), uri.host, uri.port, ssl=tls,
                                     server_hostname=uri.host if tls is not None else None)
        await link.opened

    try:
        await asyncio.wait_for(go(), open_timeout)
    except BaseException:
        link.abort()
        raise
    link.subprotocol = protocol.subprotocol
    return link


__all__ = ["LinkClosedError", "WebsocketsLink", "handshake_error", "open_websockets"]
