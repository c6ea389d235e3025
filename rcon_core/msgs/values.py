"""Field values as they arrive from a server: bytes in three spellings, NaN/Inf as ``None``."""

from __future__ import annotations

import base64
import binascii
import math
from collections.abc import Iterable
from typing import Any

__all__ = ["as_bytes", "to_base64", "as_float", "is_missing_number", "floats", "json_safe_float"]


def as_bytes(value: Any) -> bytes:
    """``uint8[]``/``char[]`` as bytes, from base64 text (JSON), bytes (CBOR) or a list of ints.

    ``None`` gives ``b""``. Raises ``ValueError`` for anything else (bad base64, ints outside 0..255).
    """
    if value is None:
        return b""
    if isinstance(value, bytes):
        return value
    if isinstance(value, bytearray | memoryview):
        return bytes(value)
    if isinstance(value, str):
        try:
            return base64.b64decode(value, validate=True)
        except (binascii.Error, ValueError):
            raise ValueError(f"not base64 text: {value[:40]!r}") from None
    if hasattr(value, "tobytes") and getattr(value, "dtype", None) is not None:
        import numpy as np

        return np.asarray(value, dtype=np.uint8).tobytes()
    if isinstance(value, list | tuple):
        try:
            return bytes(value)
        except (TypeError, ValueError):
            raise ValueError("expected a list of integers 0..255") from None
    raise ValueError(f"cannot read bytes from {type(value).__name__}")


def to_base64(data: bytes | bytearray | memoryview) -> str:
    """Bytes -> base64 text, the JSON spelling of ``uint8[]``."""
    return base64.b64encode(bytes(data)).decode("ascii")


def is_missing_number(value: Any) -> bool:
    """True for what NaN/±inf look like after JSON: ``None``, or a non-finite float."""
    return value is None or (isinstance(value, float) and not math.isfinite(value))


def as_float(value: Any, default: float = math.nan) -> float:
    """A float from a field value; ``None`` (NaN/inf sent as JSON null) becomes ``default`` (NaN)."""
    if value is None:
        return default
    if isinstance(value, str):
        return float(value)  # "NaN", "Infinity" (as some decoders spell them)
    return float(value)


def floats(values: Iterable[Any] | None, default: float = math.nan) -> list[float]:
    """A float list from an array field whose NaN/inf entries arrived as ``None``."""
    if values is None:
        return []
    return [default if v is None else float(v) for v in values]


def json_safe_float(value: float) -> float | None:
    """What a JSON server sends for ``value``: ``None`` when it is NaN or infinite."""
    return value if math.isfinite(value) else None
