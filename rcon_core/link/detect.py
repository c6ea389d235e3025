"""Which protocol a robot speaks, from the URL alone: the WebSocket subprotocol it picks.

Decision: one URL, no setting to get wrong
    RCON offers ``foxglove.sdk.v1`` and ``foxglove.websocket.v1`` in the opening handshake; a server that
    picks one speaks the Foxglove WebSocket protocol, one that picks none (rosbridge ignores the offer)
    speaks rosbridge.  :func:`detect` makes that one handshake and closes (a connection the robot sees
    come and go, nothing sent on it); the client for the answer then connects as usual.  ``--protocol``
    (``protocol=`` here) skips the question.  A URL that cannot be reached raises what connecting raised
    (the caller words it with ``rcon_core.bridge.reasons.describe``).  The handshake goes through the
    transport the client would use (``transport=``, else ``RCON_TRANSPORT``, else picows where it imports):
    both offer subprotocols and read the server's pick (``rcon_core/foxglove/ws.py``).
"""

from __future__ import annotations

from typing import Any

from rcon_core.bridge.secure import ssl_context
from rcon_core.foxglove.wire import SUBPROTOCOLS
from rcon_core.foxglove.ws import FoxgloveReceiver, choose, open_connection

from .iface import PROTOCOLS


def check_protocol(protocol: str | None) -> str | None:
    if protocol is not None and protocol not in PROTOCOLS:
        raise ValueError(f"protocol must be one of {', '.join(PROTOCOLS)} (or none: detected); got {protocol!r}")
    return protocol


async def detect(url: str, *, ca_file: str | None = None, client_cert: str | None = None,
                 client_key: str | None = None, open_timeout: float = 10.0, transport: str | None = None) -> str:
    """``"foxglove"`` or ``"rosbridge"`` (see the module docstring)."""
    ctx = ssl_context(ca_file, client_cert, client_key) if url.startswith("wss://") else None
    receiver = FoxgloveReceiver(_ignore, _ignore, _ignore)  # never started: what arrives is held, then dropped
    link = await open_connection(choose(transport), url, list(SUBPROTOCOLS), receiver, _ignore, ssl_context=ctx,
                                 open_timeout=open_timeout, max_size=1 << 20)
    try:
        return "foxglove" if link.subprotocol in SUBPROTOCOLS else "rosbridge"
    finally:
        receiver.cancel()
        await link.close()
        link.release()


def _ignore(_item: Any) -> None:
    return None


def make_client(url: str, protocol: str, **options: Any) -> Any:
    """A client of ``protocol`` for ``url`` (``BridgeClient`` or ``FoxgloveClient``), not connected yet."""
    check_protocol(protocol)
    if protocol == "foxglove":
        from rcon_core.foxglove import FoxgloveClient

        return FoxgloveClient(url, **options)
    from rcon_core.bridge import BridgeClient

    return BridgeClient(url, **options)


async def open_client(url: str, protocol: str | None = None, **options: Any) -> Any:
    """A client for ``url``, of ``protocol`` or of the one the server picks (:func:`detect`)."""
    check_protocol(protocol)
    if protocol is None:
        protocol = await detect(url, ca_file=options.get("ca_file"), client_cert=options.get("client_cert"),
                                client_key=options.get("client_key"), transport=options.get("transport"))
    return make_client(url, protocol, **options)
