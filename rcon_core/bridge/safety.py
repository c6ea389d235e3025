"""Guards for untrusted input from the server: bounded text for logs and PNG header checks.

Decisions:

* Nothing that came from the server is formatted with ``str``/``repr``/``%r`` directly: a JSON value
  nested 1000 deep (orjson accepts up to 1024 levels) makes those recurse past Python's limit, and a large
  one costs its whole size in time and memory for a log line.  :func:`bounded_repr` walks at most
  ``depth`` levels and ``limit`` characters, never recurses further and never raises.
* A service's answer nested deeper than ``MAX_ANSWER_DEPTH`` (100) levels fails the call
  (:func:`nested_deeper`, in ``session.py``), so nothing that walks an answer -- the library, the CLI's
  printing, the app -- ever recurses past Python's limit on one.
* :func:`safe_text` turns an exception into at most ``limit`` characters the same way (an exception's
  message may itself hold untrusted data, e.g. a ``KeyError`` of a deep list).
* A ``png`` frame is checked before it is decoded: :func:`png_decoded_size` reads the IHDR chunk (the
  first 33 bytes; and the chunk headers before the image data, for ``tRNS``) and the frame is refused
  when its pixels, as OpenCV decodes them (a palette as 3 or 4 channels, sub-byte samples as bytes),
  would need more than the largest frame the client accepts (``max_size``) -- a 114-byte PNG may declare
  16000 x 16000 pixels (1.2 GB), a 5.6 KB 1-bit palette PNG 94 MB of BGR.
"""

from __future__ import annotations

import struct
from collections.abc import Iterable
from typing import Any

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
_IHDR = struct.Struct(">I4sIIBBBBB")  # length, b"IHDR", width, height, depth, color type, ...
#: PNG colour type -> samples per pixel
_CHANNELS = {0: 1, 2: 3, 3: 1, 4: 2, 6: 4}


def bounded_repr(value: Any, limit: int = 120, depth: int = 4) -> str:
    """A ``repr``-like text of ``value`` of at most ``limit`` characters, looking at most ``depth`` levels
    into dicts, lists and tuples (deeper parts are shown as ``...``).  Never raises, never recurses
    unbounded: safe for any value parsed from an untrusted frame."""
    out: list[str] = []
    budget = [max(limit, 8) + 1]

    def put(text: str) -> bool:
        if budget[0] <= 0:
            return False
        out.append(text[:budget[0]])
        budget[0] -= len(text)
        return budget[0] > 0

    def walk(v: Any, level: int) -> bool:
        if isinstance(v, dict):
            if level >= depth:
                return put("{...}")
            if not put("{"):
                return False
            for i, (k, item) in enumerate(v.items()):
                if (i and not put(", ")) or not walk(k, level + 1) or not put(": ") or not walk(item, level + 1):
                    return False
            return put("}")
        if isinstance(v, list | tuple):
            open_, close = ("[", "]") if isinstance(v, list) else ("(", ")")
            if level >= depth:
                return put(open_ + "..." + close)
            if not put(open_):
                return False
            for i, item in enumerate(v):
                if (i and not put(", ")) or not walk(item, level + 1):
                    return False
            return put(close)
        if isinstance(v, str | bytes | bytearray):
            return put(repr(v[:limit]))
        if v is None or isinstance(v, bool | int | float):
            text = repr(v) if not isinstance(v, int) or v.bit_length() < 256 else f"<int of {v.bit_length()} bits>"
            return put(text)
        return put(f"<{type(v).__name__}>")

    try:
        walk(value, 0)
    except Exception:  # noqa: BLE001 - a log helper must never raise
        return f"<{type(value).__name__}>"
    text = "".join(out)
    return text if len(text) <= limit else text[:limit - 3] + "..."


#: how deep a server's answer may nest: a ROS message nests a dozen levels; past about 250, str(), YAML,
#: deepcopy and orjson's encoder fail (a 2 KB answer nested 1000 deep raised RecursionError)
MAX_ANSWER_DEPTH = 100
_LEAVES = frozenset({str, int, float, bool, type(None), bytes, bytearray})


def nested_deeper(value: Any, limit: int = MAX_ANSWER_DEPTH) -> bool:
    """Whether ``value`` (dicts and lists from a parsed frame) nests deeper than ``limit`` levels. No
    recursion; a list or dict of plain values is looked at in one C-speed pass over its items' types."""
    stack = [(value, 0)]
    pop, push = stack.pop, stack.append
    while stack:
        v, depth = pop()
        items: Iterable[Any]
        if isinstance(v, dict):
            items = v.values()
        elif isinstance(v, list | tuple):
            items = v
        else:
            continue
        if depth >= limit:
            return True
        if set(map(type, items)) <= _LEAVES:
            continue
        for item in items:
            if item.__class__ not in _LEAVES:
                push((item, depth + 1))
    return False


def json_text_value(text: Any) -> Any:
    """The value of JSON text a server sent inside a string (rosapi's parameter values): ValueError when
    it is not text, not JSON, or nested deeper than ``MAX_ANSWER_DEPTH`` (the standard parser recurses:
    2 KB of ``[`` raised RecursionError)."""
    import json

    if not isinstance(text, str):
        raise ValueError(f"expected JSON text, got {type(text).__name__}")
    try:
        value = json.loads(text)
    except RecursionError:
        raise ValueError(f"JSON text nested deeper than {MAX_ANSWER_DEPTH} levels") from None
    if nested_deeper(value):
        raise ValueError(f"JSON text nested deeper than {MAX_ANSWER_DEPTH} levels")
    return value


class LogBudget:
    """At most ``burst`` log lines at once and ``per_second`` after that (a token bucket); what it holds
    back is counted and said with the next line let through. For lines a server can cause at will (its
    ``status`` messages: 200 MB of log in 8 s)."""

    def __init__(self, per_second: float = 5.0, burst: int = 20, clock: Any = None) -> None:
        import time

        self.per_second = per_second
        self.burst = burst
        self.clock = clock or time.monotonic
        self._tokens = float(burst)
        self._at = self.clock()
        #: lines held back since the last one let through, and in all
        self.held = 0
        self.held_total = 0

    def take(self) -> int | None:
        """None when a line must be held back now; else how many were held back before it (then reset)."""
        now = self.clock()
        self._tokens = min(float(self.burst), self._tokens + (now - self._at) * self.per_second)
        self._at = now
        if self._tokens < 1.0:
            self.held += 1
            self.held_total += 1
            return None
        self._tokens -= 1.0
        held, self.held = self.held, 0
        return held


def clip(text: str, limit: int) -> str:
    """``text`` cut to ``limit`` characters, saying how long it was."""
    if len(text) <= limit:
        return text
    return f"{text[:limit]}… ({len(text):,} characters)"


def without_traceback(exc: BaseException, most: int = 8) -> BaseException:
    """``exc`` (and the exceptions it was raised from) with no traceback, to be kept: a kept traceback
    holds the frames it went through and their locals (a connection, its buffers, the last frame read)
    in reference cycles, which the app's collector policy may freeze for good (``gcpolicy.py``)."""
    seen: set[int] = set()
    e: BaseException | None = exc
    while e is not None and id(e) not in seen and len(seen) < most:
        seen.add(id(e))
        e.__traceback__ = None
        e = e.__cause__ or e.__context__
    return exc


def safe_text(exc: BaseException, limit: int = 200) -> str:
    """``"Type: message"`` of an exception, at most ``limit`` characters; never raises."""
    try:
        text = str(exc)
    except Exception:  # noqa: BLE001 - e.g. RecursionError while formatting a deep argument
        text = bounded_repr(exc.args, limit)
    if len(text) > limit:
        text = text[:limit - 3] + "..."
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


class PngRefused(ValueError):
    """A ``png`` frame whose header is missing, broken, or declares too many pixels."""


class PngTooLarge(PngRefused):
    """A PNG whose header declares more pixel bytes than the client accepts (a PNG bomb)."""


def png_decoded_size(png: bytes) -> int:
    """Bytes the decoded pixels of ``png`` need as OpenCV gives them (``IMREAD_UNCHANGED``), from its
    header alone: width x height x channels x bytes per sample, where a palette image becomes 3 channels
    (4 with a ``tRNS`` chunk), colour with ``tRNS`` 4, grey+alpha 4, and samples of 1, 2 or 4 bits
    become bytes (16 bits: 2 bytes). A 5.6 KB 1-bit palette PNG passed the old one-channel-per-pixel
    check and decoded to hundreds of MB. Raises :class:`PngRefused` when ``png`` does not start like a PNG."""
    if len(png) < len(PNG_SIGNATURE) + _IHDR.size:
        raise PngRefused(f"data is not a PNG image ({len(png)} bytes, too short for a PNG header)")
    if not png.startswith(PNG_SIGNATURE):
        raise PngRefused("data is not a PNG image (no PNG signature)")
    _, name, width, height, bit_depth, color_type, *_ = _IHDR.unpack_from(png, len(PNG_SIGNATURE))
    channels = _CHANNELS.get(color_type)
    if name != b"IHDR" or channels is None or bit_depth not in (1, 2, 4, 8, 16):
        raise PngRefused("data is not a PNG image (broken IHDR header)")
    if width == 0 or height == 0:
        raise PngRefused(f"PNG image is {width} x {height} pixels (empty)")
    if color_type == 3:
        channels = 3  # the palette's colours
    if color_type in (2, 3) and _has_chunk_before_data(png, b"tRNS"):
        channels = 4  # transparency becomes an alpha channel (OpenCV keeps grey with tRNS one channel)
    elif color_type == 4:
        channels = 4  # grey+alpha comes out as BGRA
    return width * height * channels * (2 if bit_depth == 16 else 1)


def _has_chunk_before_data(png: bytes, kind: bytes, most: int = 64) -> bool:
    """Whether a chunk ``kind`` comes before the first ``IDAT`` (looks at the chunk headers only)."""
    at = len(PNG_SIGNATURE)
    for _ in range(most):
        if at + 8 > len(png):
            return False
        length, name = struct.unpack_from(">I4s", png, at)
        if name == kind:
            return True
        if name == b"IDAT":
            return False
        at += 12 + length
    return True  # too many chunks to look through: assume the worst


def check_png(png: bytes, max_bytes: int) -> None:
    """Refuse ``png`` (raise :class:`PngRefused`) when it is not a PNG or its decoded pixels would exceed
    ``max_bytes``; the check reads only the header, before any decoding."""
    size = png_decoded_size(png)
    if size > max_bytes:
        raise PngTooLarge(f"PNG image would decode to {size} bytes, more than the {max_bytes} bytes the client "
                         "accepts in one frame; refused")
