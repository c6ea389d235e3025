"""The operator PIN, stored hashed: a random salt and scrypt, never the PIN itself (no Qt).

``make_record(pin)`` returns what the app config keeps (``{"kdf": "scrypt", "n", "r", "p", "salt",
"hash"}``, hex strings); ``check_pin(record, pin)`` compares in constant time. A PIN is 4 to 20 digits:
short enough to type on a tablet with gloves; the lock's back-off makes guessing at the screen slow (see
:mod:`rcon_core.app.operator_lock`). A damaged record never matches (the lock then cannot be opened from
the app: the config file says how to reset it, see docs/security.md).

Decision: the cost (issue 21.1c)
    Whoever copies ``app.json`` can try PINs offline, as fast as scrypt lets them: the cost per try is the
    only defence there, and each digit more multiplies the work by ten. ``SCRYPT_N`` 2**16 (64 MiB, r=8):
    ``python benchmarks/bench_pin.py`` measured 0.22 s per try on one core of a shared 2-core Xeon VM
    (2**14, the cost before: 0.045 s), so every 4-digit PIN costs about 38 minutes of one core, 6 digits
    about 2.6 days, 8 digits about 260 days; the app verifies one PIN in the same 0.2 s (a slower tablet
    core: proportionally longer, still under a second). Records made with a lower cost still verify
    (older ``app.json`` files) and :func:`needs_upgrade` tells the lock to store the PIN again at the
    current cost once it was entered right.
"""

from __future__ import annotations

import hashlib
import hmac
import os
from typing import Any

#: scrypt cost (memory 128 * r * n bytes = 64 MiB), block size, parallelism
SCRYPT_N, SCRYPT_R, SCRYPT_P = 2**16, 8, 1
PIN_MIN, PIN_MAX = 4, 20
#: the most memory a stored record may make scrypt use (a damaged record never allocates more)
MAX_MEMORY = 256 * 1024 * 1024


def pin_problem(pin: str) -> str | None:
    """Why ``pin`` cannot be a PIN, or None."""
    if not pin.isdigit() or not pin.isascii():
        return "the PIN must be digits only"
    if not PIN_MIN <= len(pin) <= PIN_MAX:
        return f"the PIN must have {PIN_MIN} to {PIN_MAX} digits"
    return None


def _derive(pin: str, salt: bytes, n: int, r: int, p: int) -> bytes:
    return hashlib.scrypt(pin.encode("utf-8"), salt=salt, n=n, r=r, p=p, maxmem=MAX_MEMORY, dklen=32)


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
        if not (2 <= n <= 2**20 and 1 <= r <= 32 and 1 <= p <= 16) or 128 * r * n * 2 > MAX_MEMORY:
            return False
        salt, want = bytes.fromhex(record["salt"]), bytes.fromhex(record["hash"])
        return hmac.compare_digest(_derive(pin, salt, n, r, p), want)
    except (AttributeError, KeyError, TypeError, ValueError, MemoryError):
        return False


def needs_upgrade(record: Any) -> bool:
    """Whether ``record`` (a good one) was made at a lower cost than a new record is."""
    try:
        return int(record["n"]) * int(record["r"]) * int(record["p"]) < SCRYPT_N * SCRYPT_R * SCRYPT_P
    except (KeyError, TypeError, ValueError):
        return False
