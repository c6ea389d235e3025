"""rosauth MAC check for the ``auth`` op (as rosauth's ros_mac_authentication does it), and the lockout of
peers that keep failing it.

The client sends ``mac, client, dest, rand, t, level, end``; ``mac`` must be the hex SHA-512 of
``secret + client + dest + rand + str(t) + level + str(end)`` with ``t``/``end`` in whole seconds,
``t`` within 5 s of the server's clock and ``end`` still in the future. Any text is compared as bytes (a
non-ASCII ``mac`` is a wrong one, not an internal error).

rosauth has no lockout: one process could try 226 secrets a second. :class:`AuthLockout` counts failed
``auth`` ops per peer address; after :data:`MAX_FAILURES` within :data:`WINDOW_S` the address is locked
out for :data:`LOCKOUT_S` (its connections are closed with 4001 unread), and a success clears the count.
"""

from __future__ import annotations

import collections
import hashlib
import hmac
import time
from collections.abc import Callable
from typing import Any

MAX_SKEW_S = 5.0
#: failed auth ops from one address within WINDOW_S that lock it out for LOCKOUT_S
MAX_FAILURES = 5
WINDOW_S = 60.0
LOCKOUT_S = 60.0
#: addresses remembered (the oldest is forgotten first)
MAX_PEERS = 10_000


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
    if not hmac.compare_digest(expected.encode("ascii"), msg["mac"].lower().encode("utf-8", "replace")):
        return "mac does not match"
    return None


class AuthLockout:
    """Failed ``auth`` ops per peer address, and which addresses are locked out (see the module docstring)."""

    def __init__(self, max_failures: int = MAX_FAILURES, window_s: float = WINDOW_S, lockout_s: float = LOCKOUT_S,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.max_failures, self.window_s, self.lockout_s = max_failures, window_s, lockout_s
        self.clock = clock
        self._failures: collections.OrderedDict[str, collections.deque[float]] = collections.OrderedDict()
        self._locked_until: dict[str, float] = {}
        self.lockouts = 0  # times an address was locked out

    def locked(self, peer: str) -> float:
        """Seconds ``peer`` stays locked out (0 when it is not)."""
        until = self._locked_until.get(peer)
        if until is None:
            return 0.0
        left = until - self.clock()
        if left <= 0:
            del self._locked_until[peer]
            return 0.0
        return left

    def failed(self, peer: str) -> None:
        now = self.clock()
        times = self._failures.pop(peer, None) or collections.deque(maxlen=self.max_failures)
        times.append(now)
        self._failures[peer] = times  # most recent last
        while len(self._failures) > MAX_PEERS:
            self._failures.popitem(last=False)
        if len(times) >= self.max_failures and now - times[0] <= self.window_s:
            self._locked_until[peer] = now + self.lockout_s
            times.clear()
            self.lockouts += 1
            if len(self._locked_until) > MAX_PEERS:
                self._locked_until = {p: u for p, u in self._locked_until.items() if u > now}

    def succeeded(self, peer: str) -> None:
        self._failures.pop(peer, None)
