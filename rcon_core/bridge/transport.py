"""The link to the robot, whatever WebSocket library carries it: the choice of transport and the decisions every
adapter keeps (``linkbase.Link`` is the transport-neutral half: frames out, the writer task, the stall watch's
hooks).  One adapter module per library is the only code that
imports it: ``pwlink.py`` (picows) and ``wslink.py`` (websockets); both hand whole messages to a
:class:`~rcon_core.bridge.receive.Receiver` and raise only RCON's own errors (``errors.LinkClosedError``,
``HandshakeError``, ``BadUrlError``; ``ssl`` and ``OSError`` as the system raises them).

Decision: two transports, one contract
    picows (a Cython WebSocket library) is the default wherever it imports: its parser hands each frame
    to the adapter as a view into its read buffer, so a small message is parsed by orjson straight from
    that buffer and delivered in the same callback, with no copy, no task and no future per message.
    websockets stays a second, fully supported transport through its documented Sans-I/O protocol
    (``websockets.client.ClientProtocol``) under RCON's own asyncio protocol; the sim and every server
    side stay on websockets' asyncio server.  Which one: ``BridgeClient(transport=...)``, else the
    ``RCON_TRANSPORT`` environment variable, else ``auto`` (picows where it imports, else websockets).
    Both behave the same to the rest of the bridge (the test suite runs on both): TLS with ``ca_file``
    and client certificates, rosauth, stall detection and the TCP-reset cut, reconnect, the frame and
    message size limit (``max_frame_size``, continuation frames joined by the adapter within it), no
    compression extension, invalid UTF-8 in a text message closing the link (1007, the WebSocket rule),
    and every frame written going through ``guard.admit`` first (``session.py``).

Decision: direct writes
    There is no batching and no timer: a frame (a publish, a subscribe...) is written to the socket
    before the call that made it returns, unless frames are already queued or the transport's buffer is
    above its high-water mark; then it waits in a queue that the writer task (:meth:`Link.run_writer`)
    drains as the transport drains, so frames always leave in order.  Nagle is off on the socket.

Decision: commands and their freshness limit (see ``freshness.py``)
    A frame with a freshness limit (:meth:`Link.send_command`) is refused at once while the link is
    DEGRADED or a ping has been unanswered for longer than the limit; when it has to wait in the queue it
    carries its deadline (:class:`~rcon_core.bridge.freshness.TimedFrame`) and the writer drops it once
    the deadline passed (``on_stale(pub)`` counts it).  The writer checks the deadline after the
    transport drained, just before writing.

The link itself (``linkbase.Link``) and its test hooks: ``linkbase.py``.
"""

from __future__ import annotations

import importlib.util
import os
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from .errors import LinkSettingsError

if TYPE_CHECKING:
    from .linkbase import Link

#: the environment variable that picks the transport when the client is not told
TRANSPORT_ENV = "RCON_TRANSPORT"
TRANSPORTS = ("auto", "picows", "websockets")


def available() -> list[str]:
    """The transports that import here, preferred first."""
    out = ["picows"] if importlib.util.find_spec("picows") is not None else []
    out.append("websockets")
    return out


def choose(setting: str | None = None) -> str:
    """The transport to use for ``setting`` (``auto``, ``picows``, ``websockets``; None: ``$RCON_TRANSPORT``,
    else ``auto``).  Raises :class:`LinkSettingsError` for an unknown name or a library that is missing."""
    name = (setting or os.environ.get(TRANSPORT_ENV) or "auto").strip().lower()
    if name not in TRANSPORTS:
        raise LinkSettingsError(f"unknown transport {name!r}; choose one of {', '.join(TRANSPORTS)}")
    have = available()
    if name == "auto":
        return have[0]
    if name not in have:
        raise LinkSettingsError(f"transport {name!r} is not installed (pip install {name})")
    return name


async def open_link(name: str, url: str, receiver: Any, on_stale: Callable[[Any], None], *,
                    ssl: Any, open_timeout: float, max_size: int, subprotocols: list[str] | None = None) -> Link:
    """Open one connection with transport ``name`` (see :func:`choose`): returns once the WebSocket is open.
    ``receiver`` gets every message (``receive.Receiver``, or one with its interface: the Foxglove link's
    ``rcon_core/foxglove/ws.py``); ``max_size`` bounds a frame and a message; ``subprotocols`` are offered in
    the handshake and the server's pick is ``link.subprotocol``."""
    if name == "picows":
        from .pwlink import open_picows

        return await open_picows(url, receiver, on_stale, ssl=ssl, open_timeout=open_timeout,
                                 max_size=max_size, subprotocols=subprotocols)
    from .wslink import open_websockets

    return await open_websockets(url, receiver, on_stale, ssl=ssl, open_timeout=open_timeout, max_size=max_size,
                                 subprotocols=subprotocols)
