"""rosauth MAC check for the ``auth`` op (as rosauth's ros_mac_authentication does it).

The client sends ``mac, client, dest, rand, t, level, end``; ``mac`` must be the hex SHA-512 of
``secret + client + dest + rand + str(t) + level + str(end)`` with ``t``/``end`` in whole seconds,
``t`` within 5 s of the server's clock and ``end`` still in the future.
"""

from __future__ import annotations

import hashlib
import hmac
import time
from typing import Any

MAX_SKEW_S = 5.0


def _seconds(value: Any) -> int | None:
    if isinstance(value, bool):
        return None
    if isinstance(value, int | float):
        return int(value)
    if isinstance(value, dict):
        secs = value.get("secs", value.get("sec"))
        if isinstance(secs, int) and not isinstance(secs, bool):
            return secs
    return None


def make_mac(secret: str, client: str, dest: str, rand: str, t: int, level: str, end: int) -> str:
    """The MAC a client must send (also handy for clients and tests)."""
    text = f"{secret}{client}{dest}{rand}{t}{level}{end}"
    return hashlib.sha512(text.encode("utf-8")).hexdigest()


def check_auth(secret: str, msg: dict[str, Any], now: float | None = None) -> str | None:
    """None when the ``auth`` frame is valid, else what is wrong with it."""
    now = time.time() if now is None else now
    for key in ("mac", "client", "dest", "rand", "level"):
        if not isinstance(msg.get(key), str):
            return f"field {key} must be a string"
    t = _seconds(msg.get("t"))
    end = _seconds(msg.get("end"))
    if t is None or end is None:
        return "fields t and end must be times in seconds"
    if abs(t - now) >= MAX_SKEW_S:
        return "t is more than 5 s away from the server's clock"
    if end <= now:
        return "the authentication has expired (end is in the past)"
    expected = make_mac(secret, msg["client"], msg["dest"], msg["rand"], t, msg["level"], end)
    if not hmac.compare_digest(expected, msg["mac"].lower()):
        return "mac does not match"
    return None
