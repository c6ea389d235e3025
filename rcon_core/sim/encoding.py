"""Wire encodings of outgoing frames: JSON text, CBOR (typed arrays), PNG, fragments.

Messages inside the sim are plain dicts.  ``bytes`` values stand for ``uint8[]``/``char[]`` and numpy
arrays for other numeric arrays, so each encoding can render them the way rosbridge does: base64 text and
plain JSON lists (float32 widened to double, NaN/inf as ``null``) in JSON; byte strings and RFC 8746
typed arrays in CBOR.

A camera image's pixels are most of its message (a 640x480 rgb8 frame is 900 KB). ``cbor_dumps`` encodes
such a message with each long byte string replaced by a short placeholder and splices the bytes in at the
end, one copy, instead of letting the CBOR encoder copy them through its growing buffer (several times
slower, and on the sim's event loop). The output is byte for byte what ``cbor2.dumps`` gives. For JSON the
cost is the base64 text of those bytes; a ``Base64Bytes`` value brings it along, made in the thread that
drew the picture.
"""

from __future__ import annotations

import base64
import json
import math
import os
import struct
import zlib
from collections.abc import Iterator
from typing import Any

import cbor2
import numpy as np
import orjson

# RFC 8746 typed-array tags (little endian)
_CBOR_TAGS: dict[str, int] = {
    "uint8": 64,
    "uint16": 69,
    "uint32": 70,
    "uint64": 71,
    "int8": 72,
    "int16": 77,
    "int32": 78,
    "int64": 79,
    "float32": 85,
    "float64": 86,
}


class Base64Bytes(bytes):
    """Bytes that carry their own base64 text, made ahead of time: a camera's drawing thread makes it when a
    JSON (``none``/``png``) subscriber is there, so 900 KB of pixels are not base64-encoded on the loop."""

    base64: str

    @classmethod
    def of(cls, data: Any) -> Base64Bytes:
        """A copy of the buffer ``data`` (bytes, a C-contiguous numpy array...) with its base64 text."""
        out = cls(data)
        out.base64 = base64.b64encode(out).decode("ascii")
        return out


def _json_default(value: Any) -> Any:
    if isinstance(value, Base64Bytes):
        return value.base64
    if isinstance(value, bytes | bytearray | memoryview):
        return base64.b64encode(bytes(value)).decode("ascii")
    if isinstance(value, np.ndarray):
        if value.dtype == np.float32:
            return value.astype(np.float64).tolist()
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"cannot encode {type(value).__name__} as JSON")


def dumps(obj: Any) -> str:
    """Compact JSON text; NaN and infinities become ``null`` (as rosbridge's ujson does). A string with a
    lone surrogate (a client's ``\\udcff`` escape, echoed in an ``id``) is written as that escape again."""
    try:
        return orjson.dumps(obj, default=_json_default).decode("utf-8")
    except orjson.JSONEncodeError as exc:
        if "surrogates" not in str(exc):
            raise
        return json.dumps(obj, default=_json_default, separators=(",", ":"))


def bounded(text: str, limit: int = 200) -> str:
    """``text`` cut to ``limit`` characters for a log line (with how much was left out)."""
    return text if len(text) <= limit else f"{text[:limit]}... ({len(text) - limit} more characters)"


def loads(text: str | bytes) -> Any:
    return orjson.loads(text)


def cbor_default(encoder: cbor2.CBOREncoder, value: Any) -> None:
    """cbor2's ``default`` hook: numpy arrays as typed arrays, numpy scalars as numbers, buffers as bytes."""
    if isinstance(value, np.ndarray):
        name = value.dtype.name
        tag = _CBOR_TAGS.get(name)
        if tag is None:
            encoder.encode(value.tolist())
            return
        data = value.astype(value.dtype.newbyteorder("<"), copy=False).tobytes()
        encoder.encode(cbor2.CBORTag(tag, data))
        return
    if isinstance(value, np.generic):
        encoder.encode(value.item())
        return
    if isinstance(value, bytearray | memoryview):
        encoder.encode(bytes(value))
        return
    raise cbor2.CBOREncodeTypeError(f"cannot encode {type(value).__name__} as CBOR")


#: byte strings at least this long are spliced into the CBOR output rather than encoded by cbor2
SPLICE_MIN = 32 * 1024
SPLICE_TOKEN = b"rcon-splice:" + os.urandom(8)  # never inside a real message (and checked)


def cbor_dumps(obj: Any) -> bytes:
    """CBOR bytes: ``bytes`` as byte strings, numeric numpy arrays as typed arrays, floats as doubles."""
    spliced: list[bytes | bytearray] = []
    lifted = _lift(obj, spliced)
    if not spliced:
        return cbor2.dumps(obj, default=cbor_default)
    out = cbor2.dumps(lifted, default=cbor_default)
    parts: list[bytes | bytearray] = []
    at = 0
    for i, value in enumerate(spliced):
        mark = cbor2.dumps(SPLICE_TOKEN + i.to_bytes(4, "big"))
        found = out.find(mark, at)
        if found < 0 or out.find(mark, found + len(mark)) >= 0:  # cannot happen; never splice blindly
            return cbor2.dumps(obj, default=cbor_default)
        parts += (out[at:found], _bytes_head(len(value)), value)
        at = found + len(mark)
    parts.append(out[at:])
    return b"".join(parts)


def _lift(obj: Any, spliced: list[bytes | bytearray], depth: int = 2) -> Any:
    """``obj`` with each byte string of SPLICE_MIN bytes or more among its values, or its dict values' values
    (a publish frame's ``msg``: an image's ``data``, cbor-raw's ``bytes``), replaced by a placeholder
    (appended to ``spliced`` in encoding order); ``obj`` itself where there is none. Deeper byte strings are
    left to cbor2: walking a whole message would cost more than it saves on the small ones."""
    if not isinstance(obj, dict):
        return obj
    out = None
    for key, value in obj.items():
        if isinstance(value, bytes | bytearray) and len(value) >= SPLICE_MIN:
            spliced.append(value)
            new: Any = SPLICE_TOKEN + (len(spliced) - 1).to_bytes(4, "big")
        elif depth > 1 and isinstance(value, dict):
            new = _lift(value, spliced, depth - 1)
        else:
            continue
        if new is not value:
            if out is None:
                out = dict(obj)
            out[key] = new
    return obj if out is None else out


def _bytes_head(n: int) -> bytes:
    """The CBOR head of a byte string of ``n`` bytes (major type 2)."""
    if n < 24:
        return bytes([0x40 | n])
    if n < 0x100:
        return struct.pack(">BB", 0x58, n)
    if n < 0x10000:
        return struct.pack(">BH", 0x59, n)
    if n < 0x100000000:
        return struct.pack(">BI", 0x5A, n)
    return struct.pack(">BQ", 0x5B, n)


def publish_frame(topic: str, msg: Any) -> dict[str, Any]:
    return {"op": "publish", "topic": topic, "msg": msg}


def png_frame(text: str) -> str:
    """rosbridge's ``png`` compression: the JSON text as the pixels of an RGB PNG, padded with newlines."""
    data = text.encode("utf-8")
    n = len(data)
    width = max(1, int(math.floor(math.sqrt(n / 3.0))))
    height = max(1, -(-n // (3 * width)))
    data += b"\n" * (width * height * 3 - n)
    stride = width * 3
    raw = b"".join(b"\x00" + data[row * stride : (row + 1) * stride] for row in range(height))

    def chunk(kind: bytes, body: bytes) -> bytes:
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF)

    png = (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
        + chunk(b"IDAT", zlib.compress(raw, 6))
        + chunk(b"IEND", b"")
    )
    return dumps({"op": "png", "data": base64.b64encode(png).decode("ascii")})


#: a message is cut in at most this many fragments, whatever fragment size a client asks for
MAX_FRAGMENTS = 1000


def fragment_size_for(length: int, size: int) -> int:
    """The fragment size a message of ``length`` characters is cut with when a client asks for ``size``:
    ``size`` itself unless that would make more than :data:`MAX_FRAGMENTS` fragments. rosbridge honours
    any size (``fragment_size: 1`` on a 1.2 MB camera image: 1.2 million frames a picture, which saturated
    the sim); the recorded small sizes (30, 100 characters on short messages) are kept as they are."""
    return max(size, -(-length // MAX_FRAGMENTS))


def iter_fragments(text: str, size: int, fid: Any = 0) -> Iterator[str]:
    """The rosbridge ``fragment`` frames of a JSON text, made one at a time (see :func:`fragments`)."""
    size = fragment_size_for(len(text), size)
    count = max(1, -(-len(text) // size))
    rest = len(text) % size
    total = float(count) if rest == 0 else count + round(rest / size, 2)
    if total >= count + 1:  # rounding up to the next whole number would mislead floor(total)
        total = count + 0.99
    for i in range(count):
        yield dumps({"op": "fragment", "id": fid, "data": text[i * size : (i + 1) * size], "num": i, "total": total})


def fragments(text: str, size: int, fid: Any = 0) -> list[str]:
    """Split a JSON text into rosbridge ``fragment`` frames (at most :data:`MAX_FRAGMENTS`).

    Like rosbridge, ``total`` is a float whose floor is the number of fragments, and ``id`` is ``fid``: 0
    for a publish (which has no id), the request's id for a reply
    (``rosbridge-ros2-2.1.0/subscribe_options.jsonl:22-35``).
    """
    return list(iter_fragments(text, size, fid))
