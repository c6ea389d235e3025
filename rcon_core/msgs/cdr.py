"""ROS 2 CDR serialization (what rosbridge 2.x sends for ``cbor-raw``), driven by FieldDefs.

The bytes are a 4-byte encapsulation header (``00 01 00 00``: plain CDR, little endian) and the message.
Rules of the body (offsets count from the end of the header):

* every primitive is aligned to its own size (1, 2, 4 or 8 bytes); ``bool``, ``byte``, ``char`` take one;
* a string is a 4-aligned uint32 length *including* a terminating NUL, the UTF-8 bytes, the NUL;
* a sequence (``T[]``, ``T[<=N]``) is a 4-aligned uint32 count and its elements; a fixed array
  (``T[N]``) is its N elements alone;
* ``builtin_interfaces/Time`` and ``Duration`` (``time``/``duration`` here) are int32 ``sec`` and uint32
  ``nanosec``;
* a message is its fields in order, nothing around them; a message without fields is one zero byte
  (the IDL's placeholder member).

A big-endian header (``00 00``) is read too.  A few zero bytes of padding after the message (some
middlewares round the size up to 4) are accepted.  Per type a decoder is compiled once (cached in the
:class:`CdrCodec`); consecutive fixed-size scalars are read with one ``struct`` call (a layout per start alignment
modulo 8), numeric arrays with ``numpy.frombuffer``.  Deserialized dicts have the ROS 2 wire shape with
``uint8[]``/``char[]``/``byte[]`` as ``bytes`` and NaN/inf as floats, like ``ros1_wire``.
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

__all__ = ["CdrCodec", "serialize", "deserialize", "CdrError", "HEADER_LE"]

HEADER_LE = b"\x00\x01\x00\x00"
_HEADER_BE = b"\x00\x00\x00\x00"
_SIZES = {"?": 1, "b": 1, "B": 1, "h": 2, "H": 2, "i": 4, "I": 4, "q": 8, "Q": 8, "f": 4, "d": 8}


class CdrError(ValueError):
    """Bytes that do not hold the expected message, or a message that cannot be serialized."""


Reader = Callable[[Any, int], tuple[Any, int]]
Writer = Callable[[Any, bytearray], None]


class CdrCodec:
    """CDR of the types a :class:`~rcon_core.msgs.lookup.TypeLookup` knows; what it compiles per type is
    cached here (make a new codec when the lookup learns new definitions)."""

    def __init__(self, types: TypeLookup) -> None:
        self.types = types
        self.ros2 = types.ros2
        self.time_fields = types.time_fields
        self.msgdef = types.msgdef
        self.default_value = types.default_value
        self.wire_name = types.wire_name
        self.cache: dict[Any, Any] = {}

    def serialize(self, name: str, msg: dict[str, Any]) -> bytes:
        """Wire-shape dict -> CDR bytes (with the header) of the message ``name`` (canonical)."""
        return serialize(self, name, msg)

    def deserialize(self, name: str, data: bytes | bytearray | memoryview) -> dict[str, Any]:
        """CDR bytes (with the header) -> wire-shape dict of the message ``name`` (canonical)."""
        return deserialize(self, name, data)


def _pad(pos: int, size: int) -> int:
    return pos + (-pos % size)


# ------------------------------------------------------------------------------------------ decoding
class _Dec:
    """Readers for one byte order, compiled per type and cached in the codec."""

    def __init__(self, reg: CdrCodec, little: bool) -> None:
        self.reg = reg
        self.order = "<" if little else ">"
        self.u32 = struct.Struct(self.order + "I")
        self.time = struct.Struct(self.order + "iI")
        self.ta, self.tb = reg.time_fields

    def message(self, name: str) -> Reader:
        key = ("cdr_dec", self.order, name)
        fn = self.reg.cache.get(key)
        if fn is None:
            fn = self.reg.cache[key] = self._compile(name)
        return fn

    def _compile(self, name: str) -> Reader:
        fields = self.reg.msgdef(name).fields
        if not fields:
            def empty(buf: Any, pos: int) -> tuple[dict[str, Any], int]:
                return {}, pos + 1

            return empty
        steps: list[Callable[[Any, int, dict[str, Any]], int]] = []
        run: list[tuple[str, str]] = []  # consecutive fixed-size scalars: (name, struct code or "T" for time)
        for f in fields:
            p = primitive(f.base, True)
            if f.array_len is None and (f.base in TIME_TYPES or (p is not None and p.code)):
                run.append((f.name, "T" if f.base in TIME_TYPES else p.code))  # type: ignore[union-attr]
                continue
            if run:
                steps.append(self._run(run))
                run = []
            steps.append(self._step(f.name, self._field(f)))
        if run:
            if not steps and len(run) == 1 and run[0][1] != "T":
                return self._one(*run[0])  # one plain scalar (std_msgs/Float64...): no loop over steps
            steps.append(self._run(run))

        def decode(buf: Any, pos: int) -> tuple[dict[str, Any], int]:
            out: dict[str, Any] = {}
            for step in steps:
                pos = step(buf, pos, out)
            return out, pos

        return decode

    @staticmethod
    def _step(fname: str, read: Reader) -> Callable[[Any, int, dict[str, Any]], int]:
        def step(buf: Any, pos: int, out: dict[str, Any]) -> int:
            out[fname], pos = read(buf, pos)
            return pos

        return step

    def _run(self, items: list[tuple[str, str]]) -> Callable[[Any, int, dict[str, Any]], int]:
        """One ``struct`` call for consecutive fixed-size scalars.  The padding between them depends on where
        the run starts modulo 8, so a format is built (once) for each start alignment seen."""
        order, ta, tb = self.order, self.ta, self.tb
        layouts: dict[int, tuple[struct.Struct, list[tuple[str, bool]]]] = {}

        def layout(mod: int) -> tuple[struct.Struct, list[tuple[str, bool]]]:
            fmt, pos, keys = [order], mod, []
            for fname, code in items:
                size, codes = (4, "iI") if code == "T" else (_SIZES[code], code)
                pad = -pos % size
                fmt.append("x" * pad + codes)
                pos += pad + (8 if code == "T" else size)
                keys.append((fname, code == "T"))
            built = layouts[mod] = (struct.Struct("".join(fmt)), keys)
            return built

        def read_run(buf: Any, pos: int, out: dict[str, Any]) -> int:
            mod = pos & 7
            st, keys = layouts.get(mod) or layout(mod)
            values = st.unpack_from(buf, pos)
            i = 0
            for fname, is_time in keys:
                if is_time:
                    out[fname] = {ta: values[i], tb: values[i + 1]}
                    i += 2
                else:
                    out[fname] = values[i]
                    i += 1
            return pos + st.size

        return read_run

    def _one(self, fname: str, code: str) -> Reader:
        """The reader of a message of one plain fixed-size scalar (its padding depends on where it starts)."""
        size = _SIZES[code]
        structs = [struct.Struct(self.order + "x" * (-mod % size) + code) for mod in range(8)]

        def read_one(buf: Any, pos: int) -> tuple[dict[str, Any], int]:
            st = structs[pos & 7]
            return {fname: st.unpack_from(buf, pos)[0]}, pos + st.size

        return read_one

    def _element(self, f: FieldDef) -> Reader:
        if f.base in TIME_TYPES:
            st, ta, tb = self.time, self.ta, self.tb

            def read_time(buf: Any, pos: int) -> tuple[Any, int]:
                pos = _pad(pos, 4)
                a, b = st.unpack_from(buf, pos)
                return {ta: a, tb: b}, pos + 8

            return read_time
        p = primitive(f.base, True)
        if p is not None and p.kind == "string":
            if f.base == "wstring":
                raise CdrError(f"{f.name}: wstring is not supported in CDR here")
            u32 = self.u32

            def read_str(buf: Any, pos: int) -> tuple[str, int]:
                pos = _pad(pos, 4)
                (n,) = u32.unpack_from(buf, pos)
                pos += 4
                if pos + n > len(buf):
                    raise CdrError(f"a string of {n} bytes runs past the end of the data")
                end = pos + n
                text = bytes(buf[pos:end - 1 if n else end]).decode("utf-8", errors="replace")
                return text, end

            return read_str
        if p is not None:
            st = struct.Struct(self.order + p.code)
            size = st.size

            def read_prim(buf: Any, pos: int) -> tuple[Any, int]:
                pos = _pad(pos, size)
                return st.unpack_from(buf, pos)[0], pos + size

            return read_prim
        base = f.base

        def read_msg(buf: Any, pos: int) -> tuple[Any, int]:
            return self.message(base)(buf, pos)

        return read_msg

    def _field(self, f: FieldDef) -> Reader:
        elem = self._element(f)
        if f.array_len is None:
            return elem
        fixed, u32, fname = f.array_len, self.u32, f.name

        def count(buf: Any, pos: int) -> tuple[int, int]:
            if fixed:
                return fixed, pos
            pos = _pad(pos, 4)
            return u32.unpack_from(buf, pos)[0], pos + 4

        if is_binary(f.base, f.array_len) or f.base == "byte":
            def binary(buf: Any, pos: int) -> tuple[bytes, int]:
                n, pos = count(buf, pos)
                if pos + n > len(buf):
                    raise CdrError(f"{fname}: {n} bytes run past the end of the data")
                return bytes(buf[pos:pos + n]), pos + n

            return binary
        p = primitive(f.base, True)
        if p is not None and p.code:
            dtype = np.dtype(self.order + ("u1" if p.code == "?" else p.code))
            size, is_bool = dtype.itemsize, p.kind == "bool"

            def numeric(buf: Any, pos: int) -> tuple[list[Any], int]:
                n, pos = count(buf, pos)
                if n:
                    pos = _pad(pos, size)
                end = pos + n * size
                if end > len(buf):
                    raise CdrError(f"{fname}: {n} items run past the end of the data")
                arr = np.frombuffer(buf, dtype=dtype, count=n, offset=pos)
                return ([bool(v) for v in arr] if is_bool else arr.tolist()), end

            return numeric

        def array(buf: Any, pos: int) -> tuple[list[Any], int]:
            n, pos = count(buf, pos)
            if n > len(buf):
                raise CdrError(f"{fname}: {n} items cannot fit in {len(buf)} bytes")
            items = []
            for _ in range(n):
                v, pos = elem(buf, pos)
                items.append(v)
            return items, pos

        return array


def deserialize(reg: CdrCodec, name: str, data: bytes | bytearray | memoryview) -> dict[str, Any]:
    """CDR bytes (with the 4-byte header) -> wire-shape dict of the message ``name`` (canonical)."""
    raw = bytes(data) if not isinstance(data, bytes) else data
    if len(raw) < 4 or raw[0] != 0 or raw[1] not in (0, 1):
        raise CdrError(f"not CDR data: the header is {raw[:4].hex(' ') or 'missing'} (expected 00 01 00 00)")
    dec = reg.cache.get(("cdr_decoder", raw[1]))
    if dec is None:
        dec = reg.cache[("cdr_decoder", raw[1])] = _Dec(reg, little=raw[1] == 1)
    body = memoryview(raw)[4:]
    try:
        out, end = dec.message(name)(body, 0)
    except struct.error:
        raise CdrError(f"the data ({len(raw)} bytes) ends before a whole {reg.wire_name(name)}") from None
    left = len(body) - end
    if left > 3 or any(body[end:]):
        raise CdrError(f"{left} bytes left over after a {reg.wire_name(name)} ({end} bytes): wrong type?")
    return out


# ------------------------------------------------------------------------------------------ encoding
def _num(kind: str, v: Any) -> Any:
    if kind == "float":
        return math.nan if v is None else float(v)
    if kind == "bool":
        return bool(v)
    if isinstance(v, float) and v.is_integer():
        return int(v)
    return v


def _writer(reg: CdrCodec, name: str) -> Writer:
    key = ("cdr_enc", name)
    fn = reg.cache.get(key)
    if fn is None:
        fn = reg.cache[key] = _compile_writer(reg, name)
    return fn


def _align(out: bytearray, size: int) -> None:
    pad = -(len(out) - 4) % size
    if pad:
        out += b"\x00" * pad


def _compile_writer(reg: CdrCodec, name: str) -> Writer:
    fields = reg.msgdef(name).fields
    if not fields:
        def empty(msg: Any, out: bytearray) -> None:
            out.append(0)

        return empty
    steps = [(f.name, reg.default_value(f), _field_writer(reg, f)) for f in fields]

    def encode(msg: Any, out: bytearray) -> None:
        if msg is None:
            msg = {}
        if not isinstance(msg, dict):
            raise CdrError(f"expected a dict for {reg.wire_name(name)}, got {type(msg).__name__}")
        for fname, default, write in steps:
            try:
                write(msg.get(fname, default), out)
            except (struct.error, TypeError, ValueError, OverflowError) as exc:
                if isinstance(exc, CdrError):
                    raise
                raise CdrError(f"cannot serialize {fname}: {exc}") from None

    return encode


def _element_writer(reg: CdrCodec, f: FieldDef) -> Writer:
    if f.base in TIME_TYPES:
        st = struct.Struct("<iI")

        def write_time(v: Any, out: bytearray) -> None:
            from .time import read

            s, ns = read(v if v is not None else {"sec": 0, "nanosec": 0})
            _align(out, 4)
            out += st.pack(s, ns)

        return write_time
    p = primitive(f.base, True)
    if p is not None and p.kind == "string":
        def write_str(v: Any, out: bytearray) -> None:
            data = bytes(v) if isinstance(v, bytes | bytearray) else str("" if v is None else v).encode("utf-8")
            _align(out, 4)
            out += struct.pack("<I", len(data) + 1) + data + b"\x00"

        return write_str
    if p is not None:
        st = struct.Struct("<" + p.code)
        size, kind = st.size, p.kind

        def write_prim(v: Any, out: bytearray) -> None:
            _align(out, size)
            out += st.pack(_num(kind, v))

        return write_prim
    base = f.base

    def write_msg(v: Any, out: bytearray) -> None:
        _writer(reg, base)(v, out)

    return write_msg


def _field_writer(reg: CdrCodec, f: FieldDef) -> Writer:
    elem = _element_writer(reg, f)
    if f.array_len is None:
        return elem
    fixed, fname = f.array_len, f.name

    def length(n: int, out: bytearray) -> None:
        if fixed:
            if n != fixed:
                raise CdrError(f"{fname}: expected {fixed} items, got {n}")
        else:
            _align(out, 4)
            out += struct.pack("<I", n)

    if is_binary(f.base, f.array_len) or f.base == "byte":
        def binary(v: Any, out: bytearray) -> None:
            data = as_bytes(v if v is not None else b"")
            length(len(data), out)
            out += data

        return binary
    p = primitive(f.base, True)
    if p is not None and p.code:
        dtype = np.dtype("<" + ("u1" if p.code == "?" else p.code))
        kind = p.kind

        def numeric(v: Any, out: bytearray) -> None:
            items = [] if v is None else list(v)
            length(len(items), out)
            if items:
                _align(out, dtype.itemsize)
                out += np.asarray([_num(kind, x) for x in items], dtype=dtype).tobytes()

        return numeric

    def array(v: Any, out: bytearray) -> None:
        items = [] if v is None else list(v)
        length(len(items), out)
        for item in items:
            elem(item, out)

    return array


def serializer(reg: CdrCodec, name: str) -> Callable[[dict[str, Any]], bytes]:
    """``serialize(msg) -> bytes`` of the message ``name`` (canonical), its writer compiled once (as
    :func:`serialize`, without the per-call lookup)."""
    write = _writer(reg, name)

    def ser(msg: dict[str, Any]) -> bytes:
        out = bytearray(HEADER_LE)
        write(msg, out)
        return bytes(out)

    return ser


def serialize(reg: CdrCodec, name: str, msg: dict[str, Any]) -> bytes:
    """A wire-shape dict of the message ``name`` (canonical) -> CDR bytes with the little-endian header."""
    out = bytearray(HEADER_LE)
    _writer(reg, name)(msg, out)
    return bytes(out)


def frame_reader(reg: CdrCodec, name: str, offset: int = 0) -> Callable[[bytes], dict[str, Any]]:
    """``decode(data)`` of CDR that starts ``offset`` bytes into ``data`` (a protocol's frame header before
    it): the little-endian reader of ``name`` compiled once, the same checks as :func:`deserialize`
    (which a big-endian message falls back to).  The Foxglove link's hot path (``rcon_core/foxglove``)."""
    dec = reg.cache.get(("cdr_decoder", 1))
    if dec is None:
        dec = reg.cache[("cdr_decoder", 1)] = _Dec(reg, little=True)
    read = dec.message(name)
    start = offset + 4
    flat = _flat_layout(reg, name)

    def decode(data: bytes) -> dict[str, Any]:
        if len(data) < start or data[offset] != 0 or data[offset + 1] != 1:
            return deserialize(reg, name, data[offset:])
        body = memoryview(data)[start:]
        try:
            out, end = read(body, 0)
        except struct.error:
            raise CdrError(f"the data ({len(data) - offset} bytes) ends before a whole {reg.wire_name(name)}") from None
        left = len(body) - end
        if left and (left > 3 or any(body[end:])):
            raise CdrError(f"{left} bytes left over after a {reg.wire_name(name)} ({end} bytes): wrong type?")
        return out

    if flat is None or len(flat[0]) != 1:
        return decode
    (only,), st = flat
    need = start + st.size

    def decode_one(data: bytes) -> dict[str, Any]:
        """A message of one plain scalar (``std_msgs/Float64``...) of exactly its size, read in place (no
        view of the body); anything else (another size, a big-endian header) takes the general path."""
        if len(data) != need or data[offset] != 0 or data[offset + 1] != 1:
            return decode(data)
        return {only: st.unpack_from(data, start)[0]}

    return decode_one


def _flat_layout(reg: CdrCodec, name: str) -> tuple[tuple[str, ...], struct.Struct] | None:
    """A message made of plain fixed-size scalars only: its field names and the little-endian ``struct`` of
    its body (starting 8-aligned, as a top-level body does); None for any other message."""
    items = []
    for f in reg.msgdef(name).fields:
        p = primitive(f.base, True)
        if f.array_len is not None or f.base in TIME_TYPES or p is None or not p.code:
            return None
        items.append((f.name, p.code))
    if not items:
        return None
    fmt, pos = ["<"], 0
    for _fname, code in items:
        size = _SIZES[code]
        pad = -pos % size
        fmt.append("x" * pad + code)
        pos += pad + size
    return tuple(fname for fname, _code in items), struct.Struct("".join(fmt))
