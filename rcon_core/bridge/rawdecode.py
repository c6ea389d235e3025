"""ROS 1 binary deserialization for ``compression: "cbor-raw"`` frames, driven by rosapi typedefs.

A cbor-raw frame's ``msg`` is ``{secs, nsecs, bytes}``: ``bytes`` is the ROS 1 serialized message
(little-endian, no 4-byte length prefix).  The server's own ``/rosapi/message_details`` typedefs describe
exactly what it serialized, so the decoder is compiled from them (one closure per type, cached); it works
for any type the server knows, including types no local registry has.  Output is the same dict shape as
the JSON path (``uint8[]``/``char[]`` as ``bytes``, times as ``{"secs", "nsecs"}``), with real NaN/Inf.
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from typing import Any

import numpy as np

from .errors import ProtocolError

_SCALARS: dict[str, str] = {
    "bool": "?", "int8": "b", "byte": "b", "uint8": "B", "char": "B",
    "int16": "h", "uint16": "H", "int32": "i", "uint32": "I", "int64": "q", "uint64": "Q",
    "float32": "f", "float64": "d",
}
_U32 = struct.Struct("<I")
_TIME = struct.Struct("<II")
_DURATION = struct.Struct("<ii")

Decoder = Callable[[memoryview, int], tuple[Any, int]]


def _short(name: str) -> str:
    """``pkg/msg/Type`` -> ``pkg/Type`` so both spellings find the same typedef."""
    parts = name.split("/")
    return f"{parts[0]}/{parts[-1]}" if len(parts) == 3 else name


def typedef_index(typedefs: list[dict[str, Any]]) -> dict[str, dict[str, Any]]:
    """Index rosapi typedefs by type name (both spellings)."""
    index: dict[str, dict[str, Any]] = {}
    for td in typedefs:
        name = td.get("type")
        if isinstance(name, str):
            index[name] = td
            index[_short(name)] = td
    return index


def has_fixed_arrays(type_name: str, typedefs: list[dict[str, Any]]) -> bool:
    """True when the type (or any nested type) has a fixed-size array field (``fieldarraylen`` > 0)."""
    return any(any(n > 0 for n in td.get("fieldarraylen", [])) for td in typedefs)


class RawDecoder:
    """Compiles ROS 1 deserializers from typedefs; ``decode(type_name, data) -> dict``."""

    def __init__(self) -> None:
        self._typedefs: dict[str, dict[str, Any]] = {}
        self._compiled: dict[str, Decoder] = {}

    def knows(self, type_name: str) -> bool:
        return _short(type_name) in self._typedefs

    def add_typedefs(self, typedefs: list[dict[str, Any]]) -> None:
        self._typedefs.update(typedef_index(typedefs))

    def decode(self, type_name: str, data: bytes | bytearray | memoryview) -> dict[str, Any]:
        fn = self._compiled.get(type_name)
        if fn is None:
            fn = self._compiled[type_name] = self._compile(_short(type_name), ())
        view = memoryview(data)
        try:
            value, end = fn(view, 0)
        except (struct.error, IndexError, ValueError, UnicodeDecodeError) as exc:
            raise ProtocolError(f"cbor-raw {type_name}: cannot deserialize {len(view)} bytes ({exc})") from None
        if end != len(view):
            raise ProtocolError(f"cbor-raw {type_name}: {len(view) - end} bytes left over after the message")
        return value

    # ------------------------------------------------------------------ compilation

    def _compile(self, name: str, stack: tuple[str, ...]) -> Decoder:
        if name in stack:
            raise ProtocolError(f"recursive type definition: {' -> '.join(stack + (name,))}")
        td = self._typedefs.get(name)
        if td is None:
            raise ProtocolError(f"no typedef for {name}")
        names = td.get("fieldnames", [])
        types = td.get("fieldtypes", [])
        lens = td.get("fieldarraylen", [])
        fields = [(fname, self._field(ftype, alen, stack + (name,)))
                  for fname, ftype, alen in zip(names, types, lens, strict=True)]

        def decode_msg(buf: memoryview, pos: int) -> tuple[Any, int]:
            out = {}
            for fname, fdec in fields:
                out[fname], pos = fdec(buf, pos)
            return out, pos

        return decode_msg

    def _field(self, ftype: str, alen: int, stack: tuple[str, ...]) -> Decoder:
        elem = self._element(ftype, stack)
        if alen is None or alen < 0:
            return elem
        if ftype in ("uint8", "char"):
            return _bytes_array(alen)
        code = _SCALARS.get(ftype)
        if code is not None and code != "?":
            return _numeric_array(np.dtype("<" + code), alen)
        return _generic_array(elem, alen)

    def _element(self, ftype: str, stack: tuple[str, ...]) -> Decoder:
        code = _SCALARS.get(ftype)
        if code is not None:
            st = struct.Struct("<" + code)
            size = st.size
            unpack = st.unpack_from

            def scalar(buf: memoryview, pos: int) -> tuple[Any, int]:
                return unpack(buf, pos)[0], pos + size

            return scalar
        if ftype == "string":
            return _string
        if ftype == "time":
            return _time
        if ftype == "duration":
            return _duration
        nested: list[Decoder] = []

        def lazy(buf: memoryview, pos: int) -> tuple[Any, int]:
            if not nested:
                nested.append(self._compile(_short(ftype), stack))
            return nested[0](buf, pos)

        return lazy


def _string(buf: memoryview, pos: int) -> tuple[str, int]:
    (n,) = _U32.unpack_from(buf, pos)
    pos += 4
    if pos + n > len(buf):
        raise ValueError("string runs past the end")
    return str(buf[pos:pos + n], "utf-8"), pos + n


def _time(buf: memoryview, pos: int) -> tuple[dict[str, int], int]:
    s, ns = _TIME.unpack_from(buf, pos)
    return {"secs": s, "nsecs": ns}, pos + 8


def _duration(buf: memoryview, pos: int) -> tuple[dict[str, int], int]:
    s, ns = _DURATION.unpack_from(buf, pos)
    return {"secs": s, "nsecs": ns}, pos + 8


def _length(buf: memoryview, pos: int, fixed: int) -> tuple[int, int]:
    if fixed > 0:
        return fixed, pos
    return _U32.unpack_from(buf, pos)[0], pos + 4


def _bytes_array(fixed: int) -> Decoder:
    def dec(buf: memoryview, pos: int) -> tuple[bytes, int]:
        n, pos = _length(buf, pos, fixed)
        if pos + n > len(buf):
            raise ValueError("byte array runs past the end")
        return bytes(buf[pos:pos + n]), pos + n

    return dec


def _numeric_array(dtype: np.dtype, fixed: int) -> Decoder:
    size = dtype.itemsize

    def dec(buf: memoryview, pos: int) -> tuple[list, int]:
        n, pos = _length(buf, pos, fixed)
        end = pos + n * size
        if end > len(buf):
            raise ValueError("array runs past the end")
        return np.frombuffer(buf[pos:end], dtype=dtype).tolist(), end

    return dec


def _generic_array(elem: Decoder, fixed: int) -> Decoder:
    def dec(buf: memoryview, pos: int) -> tuple[list, int]:
        n, pos = _length(buf, pos, fixed)
        if n > len(buf):
            raise ValueError("array length larger than the message")
        out = []
        for _ in range(n):
            v, pos = elem(buf, pos)
            out.append(v)
        return out, pos

    return dec
