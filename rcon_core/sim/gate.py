"""Frame limits of the sim, and its authentication gate (``SimServer(auth_secret=...)``, ``rcon sim --auth``).

Without auth, every message may be up to ``max_frame`` bytes (websockets closes the connection with
1009 "message too big" beyond that).

With auth, nothing but one small ``auth`` op is read before the client is authenticated:

* the first message may be at most ``auth_frame_limit`` bytes (4 KB): a bigger one closes the connection
  (1009) before it is buffered;
* it must be exactly one JSON object ``{"op": "auth", ...}`` with a valid MAC; anything else closes the
  connection with code 4001 and a reason that says what was wrong;
* a client that does not send it within ``auth_timeout`` seconds is closed (4001 "authentication timed
  out").

rosbridge sends no reply to ``auth``, so clients send their next frames right behind it (an image a
latched publisher restores, for instance). Those frames may already be read by websockets before the
handler sees the auth op, so the limit must be raised the moment the first message is complete: the
connection class below checks the first message in websockets' frame callback, synchronously, and raises
the limit to ``max_frame`` only when it is a valid ``auth`` op. (It wraps the sans-I/O protocol's
``recv_frame``; ``tests/test_sim_limits.py`` proves a pipelined big frame right after the auth op is
accepted, so a websockets upgrade that changes this is caught.)
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any

import orjson
from websockets.asyncio.server import ServerConnection
from websockets.frames import Frame, Opcode

from .auth import check_auth

__all__ = ["first_frame_problem", "gated_connection", "GatedConnection", "PENDING", "DEFAULT_MAX_FRAME", "AUTH_FRAME_LIMIT",
           "AUTH_TIMEOUT_S", "close_reason"]

#: the largest message the sim reads: its own use and a client's 1080p rgb8 image publish fit
DEFAULT_MAX_FRAME = 32 * 1024 * 1024
#: the largest message read before authentication (an ``auth`` op is about 300 bytes)
AUTH_FRAME_LIMIT = 4096
#: how long a client may take to send its ``auth`` op
AUTH_TIMEOUT_S = 10.0
#: the verdict while the first message is not complete
PENDING = "pending"

_DATA = (Opcode.TEXT, Opcode.BINARY, Opcode.CONT)


def first_frame_problem(secret: str, data: bytes) -> str | None:
    """None when ``data`` (the first message) is a valid ``auth`` op, else what is wrong with it."""
    try:
        msg = orjson.loads(data)
    except orjson.JSONDecodeError:
        return "the first frame must be an auth op (it is not a JSON object)"
    if not isinstance(msg, dict) or msg.get("op") != "auth":
        op = msg.get("op") if isinstance(msg, dict) else None
        shown = f" (got op {op[:20]!r})" if isinstance(op, str) else ""
        return f"the first frame must be an auth op{shown}"
    return check_auth(secret, msg)


def close_reason(text: str) -> str:
    """A WebSocket close reason: at most 123 bytes of UTF-8."""
    data = text.encode("utf-8")
    return text if len(data) <= 123 else data[:120].decode("utf-8", "ignore") + "..."


class GatedConnection(ServerConnection):
    """A server connection that judges its first message the moment it is complete (see the module
    docstring): ``auth_problem`` is :data:`PENDING`, then None (authenticated: messages of up to
    ``max_frame`` bytes are read from then on) or what was wrong."""

    def __init__(self, protocol: Any, *args: Any, secret: str, max_frame: int, **kwargs: Any) -> None:
        super().__init__(protocol, *args, **kwargs)
        self.auth_problem: str | None = PENDING
        self._secret = secret
        self._max_frame = max_frame
        self._first: list[bytes] = []
        self._recv_frame = protocol.recv_frame
        protocol.recv_frame = self._judge_first

    def _judge_first(self, frame: Frame) -> None:
        self._recv_frame(frame)
        if self.auth_problem != PENDING or frame.opcode not in _DATA:
            return
        self._first.append(bytes(frame.data))
        if frame.fin:
            self.auth_problem = first_frame_problem(self._secret, b"".join(self._first))
            self._first.clear()
            if self.auth_problem is None:
                self.protocol.max_message_size = self._max_frame


def gated_connection(secret: str, max_frame: int) -> Callable[..., ServerConnection]:
    """The ``create_connection`` factory for ``serve``."""
    return functools.partial(GatedConnection, secret=secret, max_frame=max_frame)
