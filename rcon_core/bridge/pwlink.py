"""The picows transport: the one module that imports ``picows``.

Decision: picows' core frame API, where it pays
    picows parses frames in its own read buffer and calls the listener once per frame with a view into
    that buffer.  A whole message goes to the :class:`~rcon_core.bridge.receive.Receiver` at once, and a
    small publish is parsed and delivered before the callback returns: no task, no future per message.
    A text message goes as ``bytes`` (a copy of its payload), a binary one as a ``memoryview`` of the
    buffer: for a small message the copy is the cheaper of the two (one allocation, where a memoryview
    is two objects the garbage collector tracks: about 0.07 us a small message less in A/B floods of a
    million), and a big text message is copied anyway (it is held, or decoded in the worker); a binary one
    is decoded in place where that pays (the Foxglove link's CDR).  The end of each read is told once,
    after picows has parsed it (``Receiver.read_done``, from the :class:`_CappedReads` wrapper), not with
    every message.  Continuation frames are joined here, within ``max_size`` (the message
    limit; a longer message fails the link with 1009, as websockets did); picows' own frame limit (10 MiB
    by default) is raised to the same ``max_size``.  Control frames: picows answers pings itself; pongs
    answer :meth:`PicowsLink.ping`; a close frame is answered and the connection closed.
    Reading pauses through the asyncio transport's ``pause_reading`` while the Receiver holds too much.

Decision: reads of a flood are capped
    picows reads into its own buffer as much as it has room for, and its buffer grows (never shrinks)
    while reads fill it: a flood of small messages grows it to megabytes, and one read then holds tens of
    thousands of messages, far more than one turn of the loop may take (``receive.py``): the Receiver
    would copy all but the first millisecond of them to hold them for later turns, doubling their cost.
    So while the last read brought more than a turn's first 4 kB of messages (``Receiver.flood``), one
    read takes at most :data:`READ_CAP` (32 kB, about 0.5 ms of small messages), and otherwise
    :data:`BIG_READ_CAP` (256 kB: five reads for a 640x480 camera frame); the transport's protocol is
    wrapped (``transport.set_protocol``, asyncio's public API) to hand picows a shorter view of its buffer.
    The cap also bounds the buffer: a camera stream that fell behind grew it to tens of megabytes (reads
    as large as the kernel's backlog), kept for the connection's life; it now stays near twice the largest
    message.  A capped read that fills its buffer is followed at once by another, in the same cycle of the
    loop: aiofastnet reads on while reads fill the buffer, up to :data:`CYCLE` (256 kB) a cycle.  The
    wrapper says so to the Receiver after each read (``Receiver.read_done(more)``), which carries the turn
    on into that read or stops reading until the loop has had its turn (``receive.py``).

Decision: which socket layer
    picows' default, ``aiofastnet`` (its own socket transport), for ``ws://``; the event loop's own TLS
    for ``wss://``, so certificate errors are the ``ssl`` module's (``reasons.py`` names them) and the
    context built from ``ca_file`` and the client certificate is used as it is.  No HTTP proxy.
"""

from __future__ import annotations

import asyncio
import ssl as _ssl
from typing import Any

import picows
from picows import WSCloseCode, WSListener, WSMsgType

from .errors import BadUrlError, HandshakeError
from .linkbase import Drain, Link, Pings

_TEXT, _BINARY, _CONT = WSMsgType.TEXT, WSMsgType.BINARY, WSMsgType.CONTINUATION
_PONG, _CLOSE = WSMsgType.PONG, WSMsgType.CLOSE
#: the transport's write buffer high-water mark (as the websockets transport)
WRITE_LIMIT = 32 << 10
#: the most one read takes while small messages arrive as a flood (about 0.5 ms of them)
READ_CAP = 32 << 10
#: the most one read takes otherwise (picows' buffer then grows to about twice the largest message only)
BIG_READ_CAP = 256 << 10
#: the bytes picows' socket layer (aiofastnet) reads in one cycle of the loop while each read fills its buffer
CYCLE = 256 << 10
CLOSE_TIMEOUT = 2.0


class _Listener(WSListener):  # type: ignore[misc]
    """picows' callbacks for one :class:`PicowsLink`.  The hot path is ``on_ws_frame``, an attribute (picows
    calls what the listener's ``on_ws_frame`` attribute holds): the Receiver's own frame callback
    (``Receiver.frame_callback``: the rosbridge link's whole text frames, the Foxglove link's whole binary
    ones; one Python call a message less), which hands every frame it does not finish to :meth:`frame`; :meth:`frame` itself while a fragmented message is being joined, or when the
    Receiver has no callback of its own.  Slots, not a ``__dict__``: a picows listener subclass's attributes
    are otherwise looked up the slow way.  :meth:`frame` calls ``message`` (``Receiver.message``, or while a
    fragmented message is being joined :meth:`PicowsLink.interrupted_message`, so it needs no ``joining``
    test)."""

    __slots__ = ("link", "message", "joining", "on_ws_frame", "hot")

    def __init__(self, link: PicowsLink) -> None:
        super().__init__()
        self.link = link
        self.message: Any = link.receiver.message
        self.joining = False
        frame = self.frame
        self.hot: Any = link.receiver.frame_callback(_TEXT, _BINARY, frame) or frame
        self.on_ws_frame: Any = self.hot

    def on_ws_connected(self, transport: Any) -> None:
        self.link.connected(transport)

    def frame(self, transport: Any, frame: Any) -> None:
        t = frame.msg_type
        if t is _TEXT:
            if frame.fin:
                self.message(frame.get_payload_as_bytes(), True, False)
                return
        elif t is _BINARY and frame.fin:
            self.message(frame.get_payload_as_memoryview(), False, False)
            return
        self.link.other_frame(frame, t)

    def on_ws_disconnected(self, transport: Any) -> None:
        self.link.disconnected()

    def pause_writing(self) -> None:
        self.link.drain.pause()

    def resume_writing(self) -> None:
        self.link.drain.resume()


class _CappedReads(asyncio.BufferedProtocol):
    """picows' protocol as the asyncio transport sees it, with two changes: one read takes at most
    :data:`BIG_READ_CAP` bytes, and :data:`READ_CAP` while messages arrive as a flood of small ones
    (``Receiver.flood``), and the Receiver is told after each read whether the transport reads again before
    the loop runs (see the module docstring).  Everything else is passed through as it is."""

    def __init__(self, inner: Any, receiver: Any) -> None:
        self.inner = inner
        self.receiver = receiver
        self.size = 0  # the buffer handed for the read under way
        self.cycle = 0  # bytes of this loop cycle's full reads so far

    def get_buffer(self, sizehint: int) -> Any:
        buf = self.inner.get_buffer(sizehint)
        cap = READ_CAP if self.receiver.flood else BIG_READ_CAP
        if len(buf) > cap:
            buf = buf[:cap]
        self.size = len(buf)
        return buf

    def buffer_updated(self, nbytes: int) -> None:
        self.inner.buffer_updated(nbytes)  # picows parses the read and hands over its messages
        more = False
        if nbytes == self.size:  # a full read: the transport reads again, up to CYCLE bytes a cycle
            self.cycle += nbytes
            more = self.cycle < CYCLE
        if not more:
            self.cycle = 0
        self.receiver.read_done(more)

    def eof_received(self) -> bool | None:
        return self.inner.eof_received()  # type: ignore[no-any-return]

    def connection_lost(self, exc: Exception | None) -> None:
        self.inner.connection_lost(exc)

    def pause_writing(self) -> None:
        self.inner.pause_writing()

    def resume_writing(self) -> None:
        self.inner.resume_writing()


class PicowsLink(Link):
    """One connection over picows."""

    name = "picows"

    def __init__(self, receiver: Any, on_stale: Any, max_size: int) -> None:
        super().__init__(on_stale)
        self.receiver = receiver
        self.max_size = max_size
        self.drain = Drain()
        self.pings = Pings()
        self.ws: Any = None
        self.listener: Any = _Listener(self)
        self._parts: list[bytes] = []
        self._size = 0
        self._text = False
        receiver.fail = self.fail

    def release(self) -> None:
        """Also the cycle through picows: the link holds picows' transport and listener, the listener holds
        the link."""
        super().release()
        listener = self.listener
        if listener is not None:  # and the listener's own: its frame callbacks hold it
            listener.on_ws_frame = listener.hot = _dropped
        self.ws = self.listener = None

    # -- picows' events ------------------------------------------------------------------------------

    def connected(self, ws: Any) -> None:
        self.ws = ws
        transport = self.transport = ws.underlying_transport
        transport.set_write_buffer_limits(high=WRITE_LIMIT)
        transport.set_protocol(_CappedReads(transport.get_protocol(), self.receiver))
        self.receiver.pause = transport.pause_reading
        self.receiver.resume = transport.resume_reading

    def other_frame(self, frame: Any, t: Any) -> None:
        """Everything but a whole data message: fragments, pongs, close."""
        listener = self.listener
        if listener is None:  # released: the connection is over, what still arrives goes nowhere
            return
        if t is _TEXT or t is _BINARY or t is _CONT:
            if t is not _CONT:
                if listener.joining:
                    self.interrupted()
                    return
                listener.joining, self._text, self._parts, self._size = True, t is _TEXT, [], 0
                listener.message = self.interrupted_message
                listener.on_ws_frame = listener.frame
            elif not listener.joining:
                self.fail(1002, "a continuation frame without a message")
                return
            self._size += frame.payload_size
            if self._size > self.max_size:
                self.fail(1009, f"message over {self.max_size} bytes")
                return
            self._parts.append(frame.get_payload_as_bytes())
            if frame.fin:
                whole, self._parts = b"".join(self._parts), []
                listener.joining = False
                listener.message = self.receiver.message
                listener.on_ws_frame = listener.hot
                self.receiver.message(whole, self._text, False)
        elif t is _PONG:
            self.pings.pong(frame.get_payload_as_bytes())
        elif t is _CLOSE:
            ws = self.ws
            code = frame.get_close_code()
            if not ws.is_close_frame_sent:
                ws.send_close(code if code is not WSCloseCode.NO_INFO else WSCloseCode.OK)
            ws.disconnect()

    def interrupted(self) -> None:
        self.fail(1002, "a new message began before the last one ended")

    def interrupted_message(self, raw: Any, text: bool, last: bool) -> None:
        """The listener's ``message`` while a fragmented message is being joined: a whole data message
        then is a protocol error."""
        self.interrupted()

    def disconnected(self) -> None:
        self.drain.lost()
        self.receiver.lost()
        code: int | None = None
        reason = ""
        handshake = self.ws.close_handshake if self.ws is not None else None
        if handshake is not None and handshake.recv is not None:
            recv = handshake.recv
            code = 1005 if recv.code is WSCloseCode.NO_INFO else int(recv.code.value)
            reason = recv.reason or ""
        self.lost(code, reason)
        self.pings.lost(self.closed_error())

    # -- Link --------------------------------------------------------------------------------------

    def write_now(self, data: bytes, binary: bool = False) -> bool:
        if self.drain.paused or self.is_closed or self.ws.is_close_frame_sent:
            return False
        self.ws.send(_BINARY if binary else _TEXT, data)
        return True

    def send_queued(self, data: bytes, binary: bool = False) -> None:
        if self.is_closed or self.ws.is_close_frame_sent:
            raise self.closed_error()
        self.ws.send(_BINARY if binary else _TEXT, data)

    async def drained(self) -> None:
        if self.is_closed:
            raise self.closed_error()
        await self.drain.wait()
        if self.is_closed:
            raise self.closed_error()

    async def ping(self) -> asyncio.Future[float]:
        if self.is_closed or self.ws.is_close_frame_sent:
            raise self.closed_error()
        data, waiter = self.pings.new()
        self.ws.send_ping(data)
        return waiter

    async def close(self) -> None:
        ws = self.ws
        if not self.is_closed and not ws.is_close_frame_sent:
            ws.send_close(WSCloseCode.OK)
        try:
            await asyncio.wait_for(self.wait_closed(), CLOSE_TIMEOUT)
        except TimeoutError:
            self.abort()

    def fail(self, code: int, reason: str) -> None:
        ws = self.ws
        if ws is None or self.is_closed:
            return
        if not ws.is_close_frame_sent:
            ws.send_close(WSCloseCode(code), reason.encode())
        ws.disconnect()


def _dropped(transport: Any, frame: Any) -> None:
    """A released link's listener: what still arrives goes nowhere."""


async def open_picows(url: str, receiver: Any, on_stale: Any, *, ssl: _ssl.SSLContext | None,
                      open_timeout: float, max_size: int, subprotocols: list[str] | None = None) -> PicowsLink:
    """Open one connection (see ``transport.open_link``).  ``subprotocols`` are offered in the
    ``Sec-WebSocket-Protocol`` request header (picows passes extra headers as they are) and the server's
    pick is read from its response (``link.subprotocol``); a pick that was not offered fails the handshake,
    as websockets does."""
    link = PicowsLink(receiver, on_stale, max_size)
    secure = url.startswith("wss://")
    headers = {"Sec-WebSocket-Protocol": ", ".join(subprotocols)} if subprotocols else None
    try:
        ws, listener = await asyncio.wait_for(picows.ws_connect(
            lambda: link.listener, url, ssl_context=(ssl or _ssl.create_default_context()) if secure else None,
            websocket_handshake_timeout=open_timeout, enable_auto_ping=False, enable_auto_pong=True,
            max_frame_size=max_size, logger_name="rcon", use_aiofastnet=False if secure else None,
            extra_headers=headers), open_timeout)
    except picows.WSInvalidURL as exc:
        raise BadUrlError(f"not a valid rosbridge URL: {exc}") from None
    except picows.WSHandshakeError as exc:
        response = exc.response
        status = int(response.status) if response is not None and response.status is not None else None
        raise HandshakeError(f"HTTP {status}" if status else str(exc), status=status) from exc
    except BaseException:
        link.abort()
        raise
    if listener is None or link.is_closed:  # picows returns no listener when the server hung up
        raise HandshakeError("connection closed during the handshake", closed=True)
    picked = ws.response.headers.getall("Sec-WebSocket-Protocol", []) if ws.response is not None else []
    if picked:
        if len(picked) > 1 or picked[0] not in (subprotocols or ()):
            link.abort()
            raise HandshakeError(f"the server picked the subprotocol {', '.join(picked)[:100]!r}, "
                                 f"which was not offered")
        link.subprotocol = picked[0]
    return link


__all__ = ["PicowsLink", "open_picows"]
