"""ROS 1 binary serialization, driven by FieldDefs (so it works for types learned from a server too).

Little endian; strings and variable arrays carry a uint32 length; fixed arrays do not; ``time`` is
uint32 secs + uint32 nsecs, ``duration`` int32 + int32. The message is NOT prefixed by its total length
(rosbridge's ``cbor-raw`` sends it like that). Deserialized dicts use the wire shape with two
differences from JSON: ``uint8[]``/``char[]`` are ``bytes``, and NaN/inf stay floats.

Per type a decoder and an encoder are compiled once (cached in the :class:`Ros1Codec`, which the registry
keeps until it learns new types): consecutive fixed-size
scalars are read with one ``struct`` call, numeric arrays with ``numpy.frombuffer``.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from .fielddefs import TIME_TYPES, FieldDef, is_binary, primitive
from .values import as_bytes

if TYPE_CHECKING:
    from .lookup import TypeLookup

__all__ = ["Ros1Codec", "serialize", "deserialize", "WireError"]


class WireError(ValueError):
    """Bytes that do not hold the expected message, or a message that cannot be serialized."""


_U32 = struct.Struct("<I")
_TIME = {"time": struct.Struct("<II"), "duration": struct.Struct("<ii")}
_DTYPES = {"b": "<i1", "B": "<u1", "h": "<i2", "H": "<u2", "i": "<i4", "I": "<u4", "q": "<i8", "Q": "<u8",
           "f": "<f4", "d": "<f8", "?": "<u1"}

Decoder = Callable[[Any, int], tuple[Any, int]]
Encoder = Callable[[Any, list[bytes]], None]


class Ros1Codec:
    """ROS 1 serialization of the types a :class:`~rcon_core.msgs.lookup.TypeLookup` knows; what it compiles
    per type is cached here (make a new codec when the lookup learns new definitions)."""

    def __init__(self, types: TypeLookup) -> None:
        self.types = types
        self.ros2 = types.ros2
        self.time_fields = types.time_fields
        self.msgdef = types.msgdef
        self.default_value = types.default_value
        self.wire_name = types.wire_name
        self.cache: dict[tuple[str, str], Any] = {}

    def serialize(self, name: str, msg: dict[str, Any]) -> bytes:
        """Wire-shape dict -> ROS 1 bytes of the message ``name`` (canonical)."""
        return serialize(self, name, msg)

    def deserialize(self, name: str, data: bytes | bytearray | memoryview) -> dict[str, Any]:
        """ROS 1 bytes -> wire-shape dict of the message ``name`` (canonical)."""
        return deserialize(self, name, data)

    def reader(self, name: str) -> Callable[[bytes | bytearray | memoryview], dict[str, Any]]:
        """A function that deserializes the message ``name`` (canonical); see :func:`reader`."""
        return reader(self, name)

    def serializer(self, name: str) -> Callable[[dict[str, Any]], bytes]:
        """A function that serializes the message ``name`` (canonical); see :func:`serializer`."""
        return serializer(self, name)


# ------------------------------------------------------------------------------------------ decoding
def _decoder(reg: Ros1Codec, name: str) -> Decoder:
    key = ("ros1_dec", name)
    dec = reg.cache.get(key)
    if dec is None:
        dec = _compile_decoder(reg, name)
        reg.cache[key] = dec
    return dec


def _compile_decoder(reg: Ros1Codec, name: str) -> Decoder:
    steps: list[Callable[[Any, int, dict[str, Any]], int]] = []
    run: list[tuple[str, str]] = []  # (field name, struct code) of consecutive fixed-size scalars
    ta, tb = reg.time_fields

    def flush() -> None:
        if not run:
            return
        st = struct.Struct("<" + "".join(code for _, code in run))
        fnames = [n for n, _ in run]
        size = st.size

        unpack = st.unpack_from
        if len(fnames) == 1:
            fname = fnames[0]

            def one(buf: Any, off: int, out: dict[str, Any]) -> int:
                out[fname] = unpack(buf, off)[0]
                return off + size

            steps.append(one)
        else:

            def step(buf: Any, off: int, out: dict[str, Any]) -> int:
                out.update(zip(fnames, unpack(buf, off), strict=False))  # same length by construction
                return off + size

            steps.append(step)
        run.clear()

    for f in reg.msgdef(name).fields:
        p = primitive(f.base, reg.ros2)
        if f.array_len is None and p is not None and p.code:
            run.append((f.name, p.code))
            continue
        flush()
        steps.append(_field_decoder(reg, f, ta, tb))
    flush()

    def decode(buf: Any, off: int) -> tuple[dict[str, Any], int]:
        out: dict[str, Any] = {}
        for step in steps:
            off = step(buf, off, out)
        return out, off

    return decode


def _read_string(buf: Any, off: int) -> tuple[str, int]:
    (n,) = _U32.unpack_from(buf, off)
    off += 4
    end = off + n
    if end > len(buf):
        raise WireError(f"a string of {n} bytes runs past the end of the data")
    return bytes(buf[off:end]).decode("utf-8", errors="replace"), end


def _element_reader(reg: Ros1Codec, f: FieldDef, ta: str, tb: str) -> Decoder:
    """Reads one element of the field's base type."""
    if f.base in TIME_TYPES:
        st = _TIME[f.base]

        def read_time(buf: Any, off: int) -> tuple[Any, int]:
            a, b = st.unpack_from(buf, off)
            return {ta: a, tb: b}, off + 8

        return read_time
    p = primitive(f.base, reg.ros2)
    if p is not None and p.kind == "string":
        return _read_string
    if p is not None:
        st = struct.Struct("<" + p.code)

        def read_prim(buf: Any, off: int) -> tuple[Any, int]:
            return st.unpack_from(buf, off)[0], off + st.size

        return read_prim
    base = f.base
    nested: list[Decoder] = []  # compiled on first use (a type may refer to itself)

    def read_msg(buf: Any, off: int) -> tuple[Any, int]:
        if not nested:
            nested.append(_decoder(reg, base))
        return nested[0](buf, off)

    return read_msg


def _field_decoder(reg: Ros1Codec, f: FieldDef, ta: str, tb: str) -> Callable[[Any, int, dict[str, Any]], int]:
    fname = f.name
    if f.array_len is None and f.base not in TIME_TYPES and primitive(f.base, reg.ros2) is None:
        base = f.base
        nested: list[Decoder] = []  # compiled on first use (a type may refer to itself)

        def message(buf: Any, off: int, out: dict[str, Any]) -> int:
            if not nested:
                nested.append(_decoder(reg, base))
            out[fname], off = nested[0](buf, off)
            return off

        return message
    elem = _element_reader(reg, f, ta, tb)
    if f.array_len is None:

        def scalar(buf: Any, off: int, out: dict[str, Any]) -> int:
            out[fname], off = elem(buf, off)
            return off

        return scalar

    fixed = f.array_len

    def count(buf: Any, off: int) -> tuple[int, int]:
        if fixed:
            return fixed, off
        return _U32.unpack_from(buf, off)[0], off + 4

    if is_binary(f.base, f.array_len):

        def binary(buf: Any, off: int, out: dict[str, Any]) -> int:
            n, off = count(buf, off)
            if off + n > len(buf):
                raise WireError(f"{fname}: {n} bytes run past the end of the data")
            out[fname] = bytes(buf[off : off + n])
            return off + n

        return binary

    p = primitive(f.base, reg.ros2)
    if p is not None and p.code:
        dtype = np.dtype(_DTYPES[p.code])
        is_bool = p.kind == "bool"

        if fixed and not is_bool:
            nbytes = fixed * dtype.itemsize
            frombuffer = np.frombuffer

            def fixed_numeric(buf: Any, off: int, out: dict[str, Any]) -> int:
                end = off + nbytes
                if end > len(buf):
                    raise WireError(f"{fname}: {fixed} items run past the end of the data")
                out[fname] = frombuffer(buf, dtype, fixed, off).tolist()
                return end

            return fixed_numeric

        def numeric(buf: Any, off: int, out: dict[str, Any]) -> int:
            n, off = count(buf, off)
            end = off + n * dtype.itemsize
            if end > len(buf):
                raise WireError(f"{fname}: {n} items run past the end of the data")
            arr = np.frombuffer(buf, dtype=dtype, count=n, offset=off)
            out[fname] = [bool(v) for v in arr] if is_bool else arr.tolist()
            return end

        return numeric

    def array(buf: Any, off: int, out: dict[str, Any]) -> int:
        n, off = count(buf, off)
        if n > len(buf):  # every element takes at least one byte
            raise WireError(f"{fname}: {n} items cannot fit in {len(buf)} bytes")
        items = []
        for _ in range(n):
            v, off = elem(buf, off)
            items.append(v)
        out[fname] = items
        return off

    return array


def reader(reg: Ros1Codec, name: str) -> Callable[[bytes | bytearray | memoryview], dict[str, Any]]:
    """``read(data) -> dict`` for the message ``name`` (canonical): :func:`deserialize` with the per-type
    work done once."""
    decode = _decoder(reg, name)
    wire = reg.wire_name(name)

    def read(data: bytes | bytearray | memoryview) -> dict[str, Any]:
        buf = data if data.__class__ is bytes else bytes(data)
        try:
            out, end = decode(buf, 0)
        except struct.error:
            raise WireError(f"the data ({len(buf)} bytes) ends before a whole {wire}") from None
        if end != len(buf):
            raise WireError(f"{len(buf) - end} bytes left over after a {wire} ({end} bytes): wrong type?")
        return out

    return read


def deserialize(reg: Ros1Codec, name: str, data: bytes | bytearray | memoryview) -> dict[str, Any]:
    """ROS 1 bytes (no length prefix) -> wire-shape dict of the message ``name`` (canonical)."""
    read = reg.cache.get(("ros1_read", name))
    if read is None:
        read = reg.cache[("ros1_read", name)] = reader(reg, name)
    return read(data)


# ------------------------------------------------------------------------------------------ encoding
def _encoder(reg: Ros1Codec, name: str) -> Encoder:
    key = ("ros1_enc", name)
    enc = reg.cache.get(key)
    if enc is None:
        enc = _compile_encoder(reg, name)
        reg.cache[key] = enc
    return enc


def _num(p: Any, v: Any) -> Any:
    if p.kind == "float":
        return math.nan if v is None else float(v)
    if p.kind == "bool":
        return bool(v)
    if isinstance(v, float) and v.is_integer():
        return int(v)
    return v


def _compile_encoder(reg: Ros1Codec, name: str) -> Encoder:
    md = reg.msgdef(name)
    steps: list[Callable[[dict[str, Any], list[bytes]], None]] = []
    run: list[tuple[FieldDef, Any]] = []

    def flush() -> None:
        if not run:
            return
        st = struct.Struct("<" + "".join(p.code for _, p in run))
        items = [(f.name, p, reg.default_value(f)) for f, p in run]

        def step(msg: dict[str, Any], parts: list[bytes], st=st, items=items) -> None:
            try:
                parts.append(st.pack(*[_num(p, msg.get(n, d)) for n, p, d in items]))
            except (struct.error, TypeError, ValueError) as exc:
                raise WireError(f"cannot serialize {', '.join(n for n, _, _ in items)}: {exc}") from None

        steps.append(step)
        run.clear()

    for f in md.fields:
        p = primitive(f.base, reg.ros2)
        if f.array_len is None and p is not None and p.code:
            run.append((f, p))
            continue
        flush()
        steps.append(_field_encoder(reg, f))
    flush()

    def encode(msg: Any, parts: list[bytes]) -> None:
        if msg is None:
            msg = {}
        if not isinstance(msg, dict):
            raise WireError(f"expected a dict for {reg.wire_name(name)}, got {type(msg).__name__}")
        for step in steps:
            step(msg, parts)

    return encode


def _string_bytes(v: Any) -> bytes:
    if isinstance(v, bytes | bytearray):
        data = bytes(v)
    else:
        data = str(v).encode("utf-8")
    return _U32.pack(len(data)) + data


def _element_writer(reg: Ros1Codec, f: FieldDef) -> Callable[[Any, list[bytes]], None]:
    if f.base in TIME_TYPES:
        st = _TIME[f.base]

        def write_time(v: Any, parts: list[bytes]) -> None:
            from .time import read

            s, ns = read(v if v is not None else {"secs": 0, "nsecs": 0})
            parts.append(st.pack(s, ns))

        return write_time
    p = primitive(f.base, reg.ros2)
    if p is not None and p.kind == "string":

        def write_str(v: Any, parts: list[bytes]) -> None:
            parts.append(_string_bytes("" if v is None else v))

        return write_str
    if p is not None:
        st = struct.Struct("<" + p.code)

        def write_prim(v: Any, parts: list[bytes]) -> None:
            parts.append(st.pack(_num(p, v)))

        return write_prim
    base = f.base

    def write_msg(v: Any, parts: list[bytes]) -> None:
        _encoder(reg, base)(v, parts)

    return write_msg


def _field_encoder(reg: Ros1Codec, f: FieldDef) -> Callable[[dict[str, Any], list[bytes]], None]:
    fname = f.name
    fixed = f.array_len
    default = reg.default_value(f)
    elem = _element_writer(reg, f)

    if f.array_len is None:

        def scalar(msg: dict[str, Any], parts: list[bytes]) -> None:
            try:
                elem(msg.get(fname, default), parts)
            except (struct.error, TypeError, ValueError) as exc:
                if isinstance(exc, WireError):
                    raise
                raise WireError(f"cannot serialize {fname}: {exc}") from None

        return scalar

    def length(n: int, parts: list[bytes]) -> None:
        if fixed:
            if n != fixed:
                raise WireError(f"{fname}: expected {fixed} items, got {n}")
        else:
            parts.append(_U32.pack(n))

    if is_binary(f.base, f.array_len):

        def binary(msg: dict[str, Any], parts: list[bytes]) -> None:
            try:
                data = as_bytes(msg.get(fname, default))
            except ValueError as exc:
                raise WireError(f"{fname}: {exc}") from None
            length(len(data), parts)
            parts.append(data)

        return binary

    p = primitive(f.base, reg.ros2)
    if p is not None and p.code:
        dtype = np.dtype(_DTYPES[p.code])

        def numeric(msg: dict[str, Any], parts: list[bytes]) -> None:
            values = msg.get(fname, default)
            if values is None:
                values = []
            if p.kind == "float" and not isinstance(values, np.ndarray):
                values = [math.nan if v is None else v for v in values]
            try:
                arr = values if isinstance(values, np.ndarray) else np.array(values)
            except (TypeError, ValueError, OverflowError) as exc:
                raise WireError(f"{fname}: {exc}") from None
            if arr.size == 0:
                arr = np.zeros(0, dtype)
            if arr.dtype.kind not in "biuf":
                raise WireError(f"{fname}: expected numbers, got {arr.dtype} items")
            if p.kind == "int":
                if arr.dtype.kind == "f" and not np.all(np.mod(arr, 1) == 0):
                    raise WireError(f"{fname}: expected integers for {p.name}")
                if arr.size and arr.dtype.kind != "b" and (arr.min() < p.lo or arr.max() > p.hi):
                    raise WireError(f"{fname}: values out of range for {p.name}")
            arr = arr.astype(dtype)
            length(len(arr), parts)
            parts.append(arr.tobytes())

        return numeric

    def array(msg: dict[str, Any], parts: list[bytes]) -> None:
        values = msg.get(fname, default)
        if values is None:
            values = []
        length(len(values), parts)
        for v in values:
            elem(v, parts)

    return array


def _flat_fields(reg: Ros1Codec, name: str) -> list[tuple[FieldDef, Any]] | None:
    """The fields of ``name`` when every one is a fixed-size primitive (Float64, Twist's parts, Bool...)."""
    out = []
    for f in reg.msgdef(name).fields:
        p = primitive(f.base, reg.ros2)
        if f.array_len is not None or p is None or not p.code:
            return None
        out.append((f, p))
    return out or None


def serializer(reg: Ros1Codec, name: str) -> Callable[[dict[str, Any]], bytes]:
    """``serialize(msg) -> bytes`` of the message ``name`` (canonical), compiled once: what a caller that
    writes many messages of one type keeps (the flight recorder). A message of fixed-size primitives only
    is one ``struct.pack``; the rest as :func:`serialize`, without its per-call lookups."""
    key = ("ros1_ser", name)
    fn = reg.cache.get(key)
    if fn is not None:
        return fn  # type: ignore[no-any-return]
    encode = _encoder(reg, name)

    def general(msg: dict[str, Any]) -> bytes:
        parts: list[bytes] = []
        encode(msg, parts)
        return b"".join(parts)

    fn = general
    flat = _flat_fields(reg, name)
    if flat is not None:
        st = struct.Struct("<" + "".join(p.code for _, p in flat))
        items = [(f.name, p, reg.default_value(f)) for f, p in flat]

        def packed(msg: dict[str, Any]) -> bytes:
            if type(msg) is not dict:
                return general(msg)
            try:
                return st.pack(*[_num(p, msg.get(n, d)) for n, p, d in items])
            except (struct.error, TypeError, ValueError) as exc:
                raise WireError(f"cannot serialize {', '.join(n for n, _, _ in items)}: {exc}") from None

        fn = packed
    reg.cache[key] = fn
    return fn


def serialize(reg: Ros1Codec, name: str, msg: dict[str, Any]) -> bytes:
    """Wire-shape dict -> ROS 1 bytes (no length prefix). Missing fields are written as their default."""
    parts: list[bytes] = []
    _encoder(reg, name)(msg, parts)
    return b"".join(parts)
