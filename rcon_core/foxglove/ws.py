"""The seam between the Foxglove link and its WebSocket library: the rosbridge link's transports, reused.

Decision: the same two transports as the rosbridge link, through the same adapters
    The Foxglove link opens its connection with ``rcon_core.bridge.transport.open_link``: picows where it
    imports, websockets as the fully supported second, chosen as the rosbridge client chooses
    (``FoxgloveClient(transport=...)``, else ``RCON_TRANSPORT``, else ``auto``).  The adapters
    (``pwlink.py``, ``wslink.py``) and their transport-neutral half (``linkbase.Link``: direct writes in
    order, the writer task, commands with a freshness limit, pings, abort and the TCP-reset cut) are the
    rosbridge link's own; this protocol adds what it needs through their small, general additions: binary
    frames out (``Link.write_binary``, ``send_by(..., binary=True)``) and the subprotocols offered in the
    handshake, the server's pick read back as ``link.subprotocol`` (picows offers them as a
    ``Sec-WebSocket-Protocol`` request header and reads the response's; websockets through its Sans-I/O
    ``ClientProtocol``).  Text frames (JSON ops) go out with ``Link.write``; binary frames (client
    messages, service call requests) with ``write_binary``; a client message with a freshness limit with
    ``send_by(..., binary=True)``.

Decision: messages are pushed, parsed from the transport's buffer
    Like the rosbridge link, messages arrive through a :class:`~rcon_core.bridge.receive.Receiver`:
    :class:`FoxgloveReceiver` keeps its rules for sharing the loop (past 4 kB of messages of one turn the
    clock is read every 4 kB and more than 1 ms of them hands the rest to the next turn; a message of
    32 kB or more that is not the first of its turn waits for the next turn; while more than 16 are held
    the transport stops reading; a flood read by picows several reads a cycle waits for the loop's turn
    between reads) and its 1007 rule (a text message that is not UTF-8 closes the link), with its own hot
    path: a binary message goes to ``FoxgloveSession.receive_binary`` as it is -- on picows a ``memoryview``
    of picows' read buffer, handed over straight from picows' parser (:meth:`FoxgloveReceiver.frame_callback`
    is the listener's ``on_ws_frame``: no listener step, no :meth:`FoxgloveReceiver.message` call), so a
    ``MessageData`` frame is decoded straight from that buffer in the callback that brought it (every
    decoder copies what it keeps: CDR, ROS 1, JSON,
    protobuf, flatbuffer; a raw consumer's payload is copied out, ``delivery.payload_of``).  Held
    messages are copies (the Receiver copies what it holds).  A text message is decoded to ``str`` (its
    UTF-8 checked) and handed to ``FoxgloveSession.receive_text``.  Until the client attached the session
    to the new connection (:meth:`FoxgloveReceiver.start`) every message is held: the server's
    ``serverInfo`` can come in the same read as the handshake's answer.
"""

from __future__ import annotations

import asyncio
import ssl
from collections.abc import Callable
from typing import Any

from rcon_core.bridge.errors import LinkClosedError, NotUtf8
from rcon_core.bridge.latest import MIN_SIZE
from rcon_core.bridge.linkbase import Link
from rcon_core.bridge.receive import Receiver
from rcon_core.bridge.transport import choose, open_link

__all__ = ["FoxgloveReceiver", "LinkClosedError", "Link", "choose", "open_connection"]

#: messages of this size or more wait for a turn of their own (as the rosbridge link's)
HEAVY = MIN_SIZE


class _Counts:
    """What the Receiver's constructor reads from a rosbridge ``Inbound``; the Foxglove link has no rosbridge
    topics table and no per-topic traffic count (:meth:`FoxgloveReceiver.message` never reaches them)."""

    def __init__(self, take: Callable[[Any, bool], None], failed: Callable[[BaseException], None]) -> None:
        self.take = take
        self.deliver = _nothing
        self.topics: dict[str, Any] = {}
        self.traffic = self
        self.bad = self
        self.failed = failed
        self.heavy = HEAVY


class FoxgloveReceiver(Receiver):
    """One Foxglove connection's messages in (see the module docstring).  ``text(s)`` gets a text message
    as ``str``, ``binary(raw)`` a binary one as a bytes-like valid during the call only; neither may raise
    (an exception is counted as a bad frame through ``failed``)."""

    __slots__ = ("binary",)

    def __init__(self, text: Callable[[str], None], binary: Callable[[Any], None],
                 failed: Callable[[BaseException], None]) -> None:
        def take(raw: Any, is_text: bool) -> None:
            if is_text:
                try:
                    s = str(raw, "utf-8")
                except UnicodeDecodeError as exc:
                    raise NotUtf8(f"text message is not UTF-8 ({exc})") from None
                try:
                    text(s)
                except Exception as exc:  # the frame boundary: one frame never ends the link
                    failed(exc)
                return
            try:
                binary(raw)
            except Exception as exc:
                failed(exc)

        super().__init__(_Counts(take, failed))
        self.binary = binary
        self.busy = True  # messages are held until start(): the session is not attached yet

    def start(self) -> None:
        """The session is attached: hand it what arrived with the handshake (held, in order), then every
        message as it comes.  Messages can arrive before the connection is handed over: picows delivers the
        frames that came in the same read as the handshake's answer."""
        if self.held:
            self.task = asyncio.ensure_future(self._drain(None))
        else:
            self.busy = False

    def frame_callback(self, text_type: Any, binary_type: Any,
                       other: Callable[[Any, Any], None]) -> Callable[[Any, Any], None] | None:
        """picows' per-frame callback (see ``Receiver.frame_callback``): a whole binary frame that fits in the
        turn's room goes to the session's ``receive_binary`` as a view of picows' read buffer, straight from
        picows' parser (the listener's step and :meth:`message` folded in: two Python calls a message less);
        every other frame, and every frame while messages are held, goes to ``other`` (the listener's own
        step, which calls :meth:`message`).  The steps are :meth:`message`'s, in the same order."""
        binary = self.binary
        failed = self.failed
        heavy = self.heavy
        spent = self._spent
        r = self

        def on_frame(transport: Any, frame: Any) -> None:
            if frame.msg_type is binary_type and frame.fin and not r.busy:
                view = frame.get_payload_as_memoryview()
                size = len(view)
                room = r.room - size
                if room > 0:
                    r.room = room
                elif size >= heavy or spent():
                    r._over(view, False, size)
                    return
                try:
                    binary(view)
                except Exception as exc:  # the frame boundary: one frame never ends the link
                    failed(exc)
            else:
                other(transport, frame)

        return on_frame

    def message(self, raw: Any, text: bool, last: bool) -> None:
        """One whole message (see ``Receiver.message``); the hot path hands it to the session at once."""
        if self.busy:
            Receiver.message(self, raw, text, last)  # held, in order, as the rosbridge link holds them
            return
        size = len(raw)
        room = self.room - size
        if room > 0:
            self.room = room
        elif size >= self.heavy or self._spent():  # a heavy message, or the turn's budget is spent
            self._over(raw, text, size)
            if last:
                self.read_done()
            return
        if text:
            self._take(raw, text)  # never returns a job: nothing here waits
        else:  # the hot path: MessageData, decoded from the buffer in place
            try:
                self.binary(raw)
            except Exception as exc:  # the frame boundary: one frame never ends the link
                self.failed(exc)
        if last:
            self.read_done()

async def open_connection(transport: str, url: str, subprotocols: list[str] | None, receiver: Any,
                          on_stale: Callable[[Any], None], *, ssl_context: ssl.SSLContext | None,
                          open_timeout: float, max_size: int) -> Link:
    """Open one connection with ``transport`` (``transport.choose``) offering ``subprotocols``; the server's
    pick is ``link.subprotocol``.  What the library raises about the URL or the handshake comes out as
    RCON's own errors (``HandshakeError``, ``BadUrlError``), which ``reasons.describe`` words."""
    link = await open_link(transport, url, receiver, on_stale, ssl=ssl_context, open_timeout=open_timeout,
                           max_size=max_size, subprotocols=subprotocols)
    link.receiver = receiver
    return link


def _nothing(*_args: Any) -> None:
    return None
