"""The operator PIN, stored hashed: a random salt and scrypt, never the PIN itself (no Qt).

``make_record(pin)`` returns what the app config keeps (``{"kdf": "scrypt", "n", "r", "p", "salt",
"hash"}``, hex strings); ``check_pin(record, pin)`` compares in constant time. A PIN is 4 to 12 digits:
short enough to type on a tablet with gloves, long enough that the lock's back-off makes guessing slow
(see :mod:`rcon_core.app.operator_lock`). A damaged record never matches (the lock then cannot be
opened from the app: the config file says how to reset it, see docs/security.md).
"""

from __future__ import annotations

import hashlib
import hmac
import os
from typing import Any

#: scrypt cost (about 50 ms on a small tablet CPU), block size, parallelism
SCRYPT_N, SCRYPT_R, SCRYPT_P = 2**14, 8, 1
PIN_MIN, PIN_MAX = 4, 12


def pin_problem(pin: str) -> str | None:
    """Why ``pin`` cannot be a PIN, or None."""
    if not pin.isdigit() or not pin.isascii():
        return "the PIN must be digits only"
    if not PIN_MIN <= len(pin) <= PIN_MAX:
        return f"the PIN must have {PIN_MIN} to {PIN_MAX} digits"
    return None


def _derive(pin: str, salt: bytes, n: int, r: int, p: int) -> bytes:
    return hashlib.scrypt(pin.encode("utf-8"), salt=salt, n=n, r=r, p=p, maxmem=64 * 1024 * 1024, dklen=32)


def make_record(pin: str) -> dict[str, Any]:
    """The stored form of a new PIN (raises ValueError for a PIN :func:`pin_problem` refuses)."""
    problem = pin_problem(pin)
    if problem:
        raise ValueError(problem)
    salt = os.urandom(16)
    digest = _derive(pin, salt, SCRYPT_N, SCRYPT_R, SCRYPT_P)
    return {"kdf": "scrypt", "n": SCRYPT_N, "r": SCRYPT_R, "p": SCRYPT_P, "salt": salt.hex(),
            "hash": digest.hex()}


def check_pin(record: Any, pin: str) -> bool:
    """Whether ``pin`` is the PIN ``record`` was made from (False for a damaged record)."""
    try:
        if record.get("kdf") != "scrypt":
            return False
        n, r, p = (int(record[k]) for k in ("n", "r", "p"))
        if not (2 <= n <= 2**20 and 1 <= r <= 32 and 1 <= p <= 16):
            return False
        salt, want = bytes.fromhex(record["salt"]), bytes.fromhex(record["hash"])
        return hmac.compare_digest(_derive(pin, salt, n, r, p), want)
    except (AttributeError, KeyError, TypeError, ValueError):
        return False
