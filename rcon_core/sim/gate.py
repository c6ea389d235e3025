"""Frame limits of the sim, and its authentication gate (``SimServer(auth_secret=...)``, ``rcon sim --auth``).

Without auth, every message may be up to ``max_frame`` bytes (websockets closes the connection with
1009 "message too big" beyond that).

With auth, nothing but one small ``auth`` op is read before the client is authenticated:

* the first message may be at most ``auth_frame_limit`` bytes (4 KB): a bigger one closes the connection
  (1009) before it is buffered;
* it must be exactly one JSON object ``{"op": "auth", ...}`` with a valid MAC; anything else closes the
  connection with code 4001 and a reason that says what was wrong;
* a client that does not send it within ``auth_timeout`` seconds is closed (4001 "authentication timed
  out");
* an address that failed :data:`~rcon_core.sim.auth.MAX_FAILURES` times within a minute is locked out: its
  connections are closed with 4001 before anything is read, for a minute (:func:`authenticate`,
  ``auth.AuthLockout``).

rosbridge sends no reply to ``auth``, so clients send their next frames right behind it (an image a
latched publisher restores, for instance). Those frames may already be read by websockets before the
handler sees the auth op, so the limit must be raised the moment the first message is complete: the
connection class below checks the first message in websockets' frame callback, synchronously, and raises
the limit to ``max_frame`` only when it is a valid ``auth`` op. (It wraps the sans-I/O protocol's
``recv_frame``; ``tests/test_sim_limits.py`` proves a pipelined big frame right after the auth op is
accepted, so a websockets upgrade that changes this is caught.)
"""

from __future__ import annotations

import asyncio
import contextlib
import functools
import logging
import math
from collections.abc import Callable
from typing import Any

import orjson
from websockets.asyncio.server import ServerConnection
from websockets.exceptions import ConnectionClosed
from websockets.frames import Frame, Opcode

from .auth import AuthLockout, check_auth

__all__ = ["first_frame_problem", "gated_connection", "GatedConnection", "PENDING", "DEFAULT_MAX_FRAME", "AUTH_FRAME_LIMIT",
           "AUTH_TIMEOUT_S", "close_reason", "authenticate"]

log = logging.getLogger("rcon.sim")

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
    try:
        return check_auth(secret, msg)
    except Exception as exc:  # noqa: BLE001 - never a 1011 and a traceback: a refusal that says why
        return f"the auth op cannot be checked ({type(exc).__name__})"


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


async def authenticate(ws: ServerConnection, timeout: float, lockout: AuthLockout) -> bool:
    """Read the one small ``auth`` op (judged by :class:`GatedConnection` as it arrived); close the
    connection (4001, with the reason) unless it was valid. An address locked out for failing too often is
    closed before anything is read."""
    peer = str(ws.remote_address[0]) if ws.remote_address else "?"
    locked = lockout.locked(peer)
    if locked:
        problem = f"too many failed authentication attempts from {peer}; try again in {math.ceil(locked):d} s"
    else:
        try:
            async with asyncio.timeout(timeout):
                await ws.recv()
        except TimeoutError:
            problem = f"authentication timed out (no auth op within {timeout:g} s)"
        except ConnectionClosed:
            return False  # gone, or its first message was too big (closed with 1009)
        else:
            verdict = getattr(ws, "auth_problem", PENDING)
            if verdict is None:
                lockout.succeeded(peer)
                log.info("client %s has authenticated.", ws.remote_address)
                return True
            lockout.failed(peer)
            problem = f"authentication failed: {verdict}"
    log.warning("client %s: %s. Closing connection.", ws.remote_address, problem)
    with contextlib.suppress(Exception):
        await ws.close(4001, close_reason(problem))
    return False
