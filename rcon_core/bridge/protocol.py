"""The rosbridge v2 wire codec: text (JSON) frames, binary (CBOR) frames, ``png`` frames and fragments.

Decisions (the recordings in ``shared/rosbridge-ros1`` are the ground truth):

* Text frames are parsed with one ``orjson.loads``.  rosbridge escapes ``/`` and non-ASCII characters;
  that is plain JSON and needs nothing special.  NaN/Inf mostly arrive as ``null`` and stay ``None``.
  But rosbridge 2.x writes NaN and infinities inside fixed-size arrays (an Imu's covariances, numpy arrays
  inside rclpy) as the bare tokens ``NaN``/``Infinity``/``-Infinity``, which is not JSON
  (``rosbridge-ros2-2.1.0/publish_json.jsonl:62``; a ``NaN`` id comes back the same way,
  ``malformed.jsonl:34``).  A frame orjson refuses is parsed again with Python's own ``json`` module, which
  reads those tokens as float NaN/inf (:func:`loads_text`), so such a message is delivered, not dropped.
* Binary frames are CBOR (``compression: "cbor"`` and ``"cbor-raw"``).  RFC 8746 typed arrays (tags
  64-87) are decoded with numpy into **plain lists** by default, so a message looks the same whichever
  compression carried it; uint8 arrays (tags 64 and 68) become ``bytes`` (the same value a CBOR byte
  string gives, and what ``rcon_core.msgs.values.as_bytes`` accepts).  ``typed_arrays="numpy"`` keeps
  numpy arrays instead, for consumers that want them.  CBOR keeps real NaN and Infinity.
* A binary frame that is not CBOR but JSON text (rosbridge itself accepts that) is parsed as JSON.
* ``png`` frames hold a base64 PNG whose RGB pixel bytes are the JSON text of the real frame padded with
  ``\\n``; it is decoded with OpenCV (imported lazily) and the padding is ignored by the JSON parser.
  Its IHDR header is checked first (``safety.check_png``): a PNG whose pixels would exceed the largest
  frame the client accepts is refused without decoding (a PNG bomb), and anything OpenCV cannot read is a
  ``ProtocolError``, never an OpenCV exception.
* ``fragment`` frames: ``total`` may be a float (rosbridge 0.11 computes it that way); the number of
  fragments is ``floor(total)``, ``num`` runs from 0.  ``id`` is 0 for every message, so fragments are
  reassembled by arrival order per id: a ``num == 0`` starts a new message and drops any unfinished
  one.  Unfinished messages not added to for ``timeout`` are dropped (the client also sweeps them on a
  timer, so they go without new fragments too), a message may not exceed ``max_bytes`` nor
  ``max_fragments``, all unfinished messages together may not exceed ``max_total`` bytes (the oldest
  are dropped first; 64 unfinished 32 MB messages held 2 GB), and a lost connection drops them all
  (``clear``: the next connection never completes a message the last one started).
"""

from __future__ import annotations

import base64
import binascii
import json as _stdlib_json
import logging
import math
import time
from collections.abc import Callable
from typing import Any

import cbor2
import numpy as np
import orjson

from .errors import ProtocolError
from .safety import PngRefused, PngTooLarge, check_png, safe_text

log = logging.getLogger(__name__)

dumps = orjson.dumps
loads = orjson.loads

#: compression modes a subscription may ask for
COMPRESSIONS = ("none", "png", "cbor", "cbor-raw")


def loads_text(raw: str | bytes | memoryview) -> Any:
    """Parse one text frame: orjson, else -- only for text holding bare ``NaN``/``Infinity`` tokens, as
    rosbridge 2.x writes them (see the module docstring) -- Python's ``json``.  Raises ProtocolError."""
    try:
        return loads(raw)
    except orjson.JSONDecodeError as exc:
        error = exc
    if isinstance(raw, memoryview):  # a png frame's text, read in place from the decoded image
        raw = raw.tobytes()
    text = raw.decode("utf-8", "replace") if isinstance(raw, bytes | bytearray) else raw
    if "NaN" in text or "Infinity" in text:
        try:
            return _stdlib_json.loads(text)
        except Exception:  # ValueError, RecursionError on absurd nesting...
            pass
    raise ProtocolError(f"not valid JSON ({error})")


def encode(op: dict[str, Any]) -> bytes:
    """One outgoing frame as UTF-8 JSON bytes (sent as a *text* frame)."""
    return dumps(op, option=orjson.OPT_SERIALIZE_NUMPY)


# --------------------------------------------------------------------------- typed arrays (RFC 8746)


def typed_array_dtype(tag: int) -> np.dtype | None:
    """The numpy dtype of an RFC 8746 typed-array tag (64-87), or None for tags numpy cannot hold."""
    if not 64 <= tag <= 87:
        return None
    bits = tag - 64
    is_float = bits >> 4 & 1
    signed = bits >> 3 & 1
    little = bits >> 2 & 1
    ll = bits & 3
    order = "<" if little else ">"
    if is_float:
        size = 2 << ll  # 2, 4, 8, 16 bytes
        if size == 16:
            return None  # float128 has no portable numpy type
        return np.dtype(f"{order}f{size}")
    size = 1 << ll
    return np.dtype(f"{order}{'i' if signed else 'u'}{size}")


# cbor2 5.x calls tag_hook(decoder, tag); cbor2 6.x calls tag_hook(tag, immutable): accept both.


def _tag_hook_list(a: Any, b: Any) -> Any:
    tag = a if a.__class__ is cbor2.CBORTag else b
    t = tag.tag
    if t == 64 or t == 68:
        return bytes(tag.value)
    dtype = typed_array_dtype(t)
    if dtype is None or not isinstance(tag.value, bytes | bytearray):
        return tag
    return np.frombuffer(tag.value, dtype=dtype).tolist()


def _tag_hook_numpy(a: Any, b: Any) -> Any:
    tag = a if a.__class__ is cbor2.CBORTag else b
    t = tag.tag
    if t == 64 or t == 68:
        return bytes(tag.value)
    dtype = typed_array_dtype(t)
    if dtype is None or not isinstance(tag.value, bytes | bytearray):
        return tag
    return np.frombuffer(tag.value, dtype=dtype)


def decode_cbor(data: bytes, typed_arrays: str = "list", budget: int | None = None) -> Any:
    """Decode one CBOR frame; typed arrays become lists (or numpy arrays with ``typed_arrays="numpy"``).
    ``budget``: the bytes of Python objects the decoded frame may take; the typed arrays made lists and
    the maps are counted as they are decoded, and going over raises :class:`RefusedFrame`."""
    hook = _tag_hook_numpy if typed_arrays == "numpy" else _tag_hook_list
    if budget is None:
        return cbor2.loads(data, tag_hook=hook)
    spent = [len(data)]

    def spend(n: int) -> None:
        spent[0] += n
        if spent[0] > budget:
            raise DecodedTooBig(f"CBOR frame of {len(data)} bytes decodes to more than the {budget >> 20} MB of "
                               "objects the client allows for one frame; refused")

    def counted_tag(a: Any, b: Any) -> Any:
        tag = a if a.__class__ is cbor2.CBORTag else b
        dtype = typed_array_dtype(tag.tag)
        if typed_arrays != "numpy" and dtype is not None and isinstance(tag.value, bytes | bytearray) \
                and tag.tag not in (64, 68):
            spend(len(tag.value) // dtype.itemsize * (32 if dtype.kind == "f" else 36))
        return hook(a, b)

    def counted_map(a: Any, b: Any) -> Any:  # cbor2 5.x: (decoder, value); 6.x: (value, immutable)
        value = b if isinstance(b, dict) else a
        spend(100 + 16 * len(value))
        return value

    try:
        return cbor2.loads(data, tag_hook=counted_tag, object_hook=counted_map)
    except cbor2.CBORDecodeError as exc:
        if isinstance(exc.__cause__, RefusedFrame):
            raise exc.__cause__ from None
        raise


#: the most bytes of objects one byte of JSON text can count for in :func:`json_decoded_size` (``{},`` is
#: 3 + 200 + 8 for 3 bytes): a frame shorter than the budget over this cannot be over it, and is not counted
JSON_MOST_PER_BYTE = 71


def json_decoded_size(raw: str | bytes) -> int:
    """About how many bytes of Python objects a JSON frame decodes to, counted in its text before
    parsing: its length, plus a slot per ``,``, a float per ``.``, a dict per ``{``, a list per ``[``, a
    string object per pair of ``"``. An upper estimate but for integers above 256 (each counted as a slot,
    8 bytes, where it takes 36) and floats written without a ``.`` (``1e-05``): a frame of those may take
    up to about four times the estimate. (Exponents are not counted: a two-byte search costs three times a
    one-byte count, and counting them made the estimate cost ten times the parse of a JSON camera frame.)"""
    if isinstance(raw, str):
        c = raw.count
        return len(raw) + 8 * c(",") + 24 * c(".") + 200 * c("{") + 56 * c("[") + 25 * c('"')
    b = raw.count
    return len(raw) + 8 * b(b",") + 24 * b(b".") + 200 * b(b"{") + 56 * b(b"[") + 25 * b(b'"')


def check_json_size(raw: str | bytes, budget: int | None) -> None:
    """Refuse (:class:`RefusedFrame`) a JSON frame whose objects would take more than ``budget`` bytes. A
    frame too short to be over it is not counted (:data:`JSON_MOST_PER_BYTE`)."""
    if budget is None or len(raw) * JSON_MOST_PER_BYTE <= budget:
        return
    size = json_decoded_size(raw)
    if size > budget:
        raise DecodedTooBig(f"JSON frame of {len(raw)} bytes would decode to about {size >> 20} MB of objects, "
                           f"more than the {budget >> 20} MB the client allows for one frame; refused")


def decode_binary(data: bytes, typed_arrays: str = "list", budget: int | None = None) -> Any:
    """Decode a binary frame: CBOR, or JSON text sent in a binary frame.  Raises ProtocolError
    (:class:`RefusedFrame` when the decoded objects would take more than ``budget`` bytes)."""
    if not data:
        raise ProtocolError("empty binary frame")
    first = data[0]
    if first in (0x7B, 0x5B):  # '{' or '[': JSON text in a binary frame (a CBOR map never starts so)
        check_json_size(data, budget)
        try:
            return loads_text(data)
        except ProtocolError:
            pass
    try:
        return decode_cbor(data, typed_arrays, budget)
    except RefusedFrame:
        raise
    except Exception as exc:  # cbor2 raises several types (CBORDecodeError, ValueError, ...)
        raise ProtocolError(f"binary frame is neither CBOR nor JSON ({exc})") from None


# --------------------------------------------------------------------------- png frames


class RefusedFrame(ProtocolError):
    """A frame refused because it would need more memory than the client accepts (e.g. a PNG bomb)."""


class DecodedTooBig(RefusedFrame):
    """A frame whose decoded objects would take more than the client's decoded-size budget."""



def png_to_text(data_b64: str, max_bytes: int = 64 << 20) -> bytes:
    """The JSON bytes hidden in a ``png`` frame's ``data`` (base64 PNG of the text's bytes as RGB pixels);
    see :func:`png_view`."""
    return bytes(png_view(data_b64, max_bytes))


def png_view(data_b64: str, max_bytes: int = 64 << 20) -> memoryview:
    """The JSON bytes hidden in a ``png`` frame's ``data``, as a view onto the decoded image (one copy of
    the pixels in all, where there were four).

    The trailing ``\\n`` padding is stripped.  Raises ProtocolError when the data is not a PNG, or when its
    header declares pixels of more than ``max_bytes`` (checked before decoding: a PNG bomb is refused).
    """
    try:
        png = base64.b64decode(data_b64, validate=False)
    except (binascii.Error, ValueError, TypeError) as exc:
        raise ProtocolError(f"png frame: data is not base64 ({exc})") from None
    try:
        check_png(png, max_bytes)
    except PngRefused as exc:
        raise (RefusedFrame if isinstance(exc, PngTooLarge) else ProtocolError)(f"png frame: {exc}") from None
    import cv2  # lazily: OpenCV is only needed by png subscriptions

    try:
        img = cv2.imdecode(np.frombuffer(png, np.uint8), cv2.IMREAD_UNCHANGED)
    except Exception as exc:  # cv2.error on data OpenCV cannot read
        raise ProtocolError(f"png frame: OpenCV cannot decode the image ({safe_text(exc, 120)})") from None
    if img is None:
        raise ProtocolError("png frame: data is not a PNG image")
    # OpenCV gives BGR(A); the payload bytes are in RGB(A) order: swapped in place, no copy of the image
    if img.ndim == 3 and img.shape[2] == 3 and img.dtype == np.uint8:
        cv2.cvtColor(img, cv2.COLOR_BGR2RGB, dst=img)
    elif img.ndim == 3 and img.shape[2] == 4 and img.dtype == np.uint8:
        cv2.cvtColor(img, cv2.COLOR_BGRA2RGBA, dst=img)
    elif img.ndim == 3:
        img = img[:, :, [2, 1, 0, 3][: img.shape[2]]] if img.shape[2] in (3, 4) else img
    flat = np.ascontiguousarray(img).reshape(-1).view(np.uint8)
    return memoryview(flat.data)[: _text_end(flat)]


def _text_end(flat: np.ndarray) -> int:
    """Where the text ends in the decoded bytes: before the trailing ``\\n`` / NUL padding (looked for
    from the end, a chunk at a time, without a copy of the whole image)."""
    end = len(flat)
    step = 1 << 16
    while end > 0:
        tail = flat[max(0, end - step):end]
        keep = np.flatnonzero((tail != 10) & (tail != 0))
        if len(keep):
            return end - len(tail) + int(keep[-1]) + 1
        end -= len(tail)
    return 0


def decode_png(data_b64: str, max_bytes: int = 64 << 20) -> Any:
    """Decode a (complete) ``png`` frame's payload into the frame it carries (``max_bytes``: see
    :func:`png_to_text`)."""
    text = png_view(data_b64, max_bytes)
    try:
        return loads_text(text)
    except ProtocolError as exc:
        raise ProtocolError(f"png frame: embedded text is {exc}") from None


# --------------------------------------------------------------------------- fragments


class _Partial:
    __slots__ = ("parts", "count", "size", "started", "updated")

    def __init__(self, count: int, now: float) -> None:
        self.parts: list[str] = []
        self.count = count
        self.size = 0
        self.started = now
        self.updated = now


class FragmentAssembler:
    """Joins ``fragment`` (and fragmented ``png``) frames back into the text they were cut from.

    ``add(frame)`` returns the joined text when the last fragment arrives, else None.  Problems (a gap, a
    fragment without a start, a message larger than ``max_bytes``) drop the partial message and raise
    ProtocolError with a specific reason; the caller logs it.  Nothing here can grow without bound.
    """

    def __init__(self, timeout: float = 10.0, max_bytes: int = 64 << 20, max_fragments: int = 100_000,
                 max_partials: int = 64, warn: Callable[[str], None] | None = None,
                 max_total: int | None = None) -> None:
        self.warn = warn or log.warning
        self.timeout = timeout
        self.max_bytes = max_bytes
        #: bytes of every unfinished message together (default: twice ``max_bytes``)
        self.max_total = 2 * max_bytes if max_total is None else max_total
        self._total = 0
        self.max_fragments = max_fragments
        self.max_partials = max_partials
        self._partials: dict[Any, _Partial] = {}
        self.dropped = 0
        self.completed = 0

    def __len__(self) -> int:
        return len(self._partials)

    @property
    def buffered_bytes(self) -> int:
        return self._total

    def _drop(self, fid: Any) -> _Partial:
        part = self._partials.pop(fid)
        self._total -= part.size
        return part

    def clear(self) -> int:
        """Drop every unfinished message (the connection they came on is gone); returns how many."""
        n = len(self._partials)
        self._partials.clear()
        self._total = 0
        self.dropped += n
        return n

    def oldest_update(self) -> float | None:
        """``time.monotonic()`` of the least recently added-to unfinished message, or None."""
        return min((p.updated for p in self._partials.values()), default=None)

    def expire(self, now: float | None = None) -> int:
        """Drop unfinished messages not updated for ``timeout`` seconds; returns how many were dropped."""
        now = time.monotonic() if now is None else now
        stale = [k for k, p in self._partials.items() if now - p.updated > self.timeout]
        for k in stale:
            self._drop(k)
        self.dropped += len(stale)
        if stale:
            self.warn(f"dropped {len(stale)} unfinished fragmented message(s) after {self.timeout:g} s "
                      "without a fragment")
        return len(stale)

    def add(self, frame: dict[str, Any], now: float | None = None) -> str | None:
        now = time.monotonic() if now is None else now
        if self._partials:
            self.expire(now)
        fid = frame.get("id")
        data = frame.get("data")
        num = frame.get("num")
        total = frame.get("total")
        if not isinstance(data, str):
            raise ProtocolError(f"fragment id={fid!r}: 'data' must be a string, got {type(data).__name__}")
        if isinstance(num, bool) or not isinstance(num, int) or num < 0:
            raise ProtocolError(f"fragment id={fid!r}: 'num' must be a non-negative integer, got {num!r}")
        if isinstance(total, bool) or not isinstance(total, int | float) or not math.isfinite(total):
            raise ProtocolError(f"fragment id={fid!r}: 'total' must be a number, got {total!r}")
        count = math.floor(total)
        if count < 1 or count > self.max_fragments:
            raise ProtocolError(f"fragment id={fid!r}: total {total!r} is out of range "
                                f"(1..{self.max_fragments} fragments)")
        try:
            hash(fid)
        except TypeError:
            raise ProtocolError(f"fragment: 'id' must be a string or number, got {type(fid).__name__}") from None
        part = self._partials.get(fid)
        if num == 0:
            if part is not None:
                self._drop(fid)
                self.dropped += 1
                self.warn(f"fragment id={fid!r}: a new message started before the previous one was complete "
                          f"({len(part.parts)} of {part.count} fragments); dropped the incomplete one")
            if len(self._partials) >= self.max_partials:
                oldest = min(self._partials, key=lambda k: self._partials[k].updated)
                self._drop(oldest)
                self.dropped += 1
                self.warn(f"too many unfinished fragmented messages; dropped the oldest (id={oldest!r})")
            part = self._partials[fid] = _Partial(count, now)
        elif part is None:
            raise ProtocolError(f"fragment id={fid!r} num={num}: no message was started (num 0 missing); ignored")
        elif num != len(part.parts) or count != part.count:
            self._drop(fid)
            self.dropped += 1
            raise ProtocolError(f"fragment id={fid!r}: expected num {len(part.parts)} of {part.count}, got "
                                f"num {num} of {count}; dropped the incomplete message")
        if part.size + len(data) > self.max_bytes:
            self._drop(fid)
            self.dropped += 1
            raise ProtocolError(f"fragment id={fid!r}: message exceeds {self.max_bytes} bytes; dropped")
        while self._total + len(data) > self.max_total and len(self._partials) > 1:
            oldest = min((k for k in self._partials if k != fid), key=lambda k: self._partials[k].updated)
            self._drop(oldest)
            self.dropped += 1
            self.warn(f"unfinished fragmented messages hold more than {self.max_total} bytes; dropped the "
                      f"oldest (id={oldest!r})")
        part.size += len(data)
        self._total += len(data)
        part.parts.append(data)
        part.updated = now
        if len(part.parts) == part.count:
            self._drop(fid)
            self.completed += 1
            return "".join(part.parts)
        return None
