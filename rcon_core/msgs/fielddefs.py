"""The type model: field and message definitions, and what each primitive type is on the wire."""

from __future__ import annotations

from typing import Any

import attrs

__all__ = ["FieldDef", "Constant", "MsgDef", "Primitive", "PRIMITIVES", "TIME_TYPES", "primitive", "is_binary"]


@attrs.frozen
class Primitive:
    """One built-in type: its ROS 1 binary struct code, its kind and its range."""

    name: str
    code: str  # struct / numpy code, little endian; "" for string
    kind: str  # "bool" | "int" | "float" | "string"
    lo: float | int | None = None
    hi: float | int | None = None

    @property
    def size(self) -> int:
        return {"?": 1, "b": 1, "B": 1, "h": 2, "H": 2, "i": 4, "I": 4, "q": 8, "Q": 8, "f": 4, "d": 8}.get(
            self.code, 0
        )


def _int(name: str, code: str, bits: int, signed: bool) -> Primitive:
    if signed:
        return Primitive(name, code, "int", -(1 << (bits - 1)), (1 << (bits - 1)) - 1)
    return Primitive(name, code, "int", 0, (1 << bits) - 1)


PRIMITIVES: dict[str, Primitive] = {
    "bool": Primitive("bool", "?", "bool"),
    "int8": _int("int8", "b", 8, True),
    "uint8": _int("uint8", "B", 8, False),
    "int16": _int("int16", "h", 16, True),
    "uint16": _int("uint16", "H", 16, False),
    "int32": _int("int32", "i", 32, True),
    "uint32": _int("uint32", "I", 32, False),
    "int64": _int("int64", "q", 64, True),
    "uint64": _int("uint64", "Q", 64, False),
    "float32": Primitive("float32", "f", "float", -3.4028234663852886e38, 3.4028234663852886e38),
    "float64": Primitive("float64", "d", "float"),
    "string": Primitive("string", "", "string"),
    "wstring": Primitive("wstring", "", "string"),
    # ROS 1 aliases: byte is int8, char is uint8 (ROS 2 makes byte an unsigned octet)
    "byte": _int("byte", "b", 8, True),
    "char": _int("char", "B", 8, False),
}
_ROS2_OVERRIDES = {"byte": _int("byte", "B", 8, False)}

#: ``time`` and ``duration`` are built-ins: ``{secs, nsecs}`` on ROS 1, ``{sec, nanosec}`` on ROS 2.
TIME_TYPES = ("time", "duration")

# IDL spellings a ROS 2 server uses, mapped to .msg spellings
IDL_ALIASES = {
    "boolean": "bool",
    "octet": "byte",
    "double": "float64",
    "float": "float32",
    "long double": "float64",
    "short": "int16",
    "unsigned short": "uint16",
    "long": "int32",
    "unsigned long": "uint32",
    "long long": "int64",
    "unsigned long long": "uint64",
}


def primitive(base: str, ros2: bool = False) -> Primitive | None:
    """The :class:`Primitive` for ``base``, or ``None`` when it is not a primitive (a message or time)."""
    if ros2 and base in _ROS2_OVERRIDES:
        return _ROS2_OVERRIDES[base]
    return PRIMITIVES.get(base)


def is_binary(base: str, array_len: int | None) -> bool:
    """``uint8``/``char`` arrays travel as bytes (base64 in JSON)."""
    return array_len is not None and base in ("uint8", "char")


@attrs.frozen
class FieldDef:
    """One field of a message.

    ``type`` is the full declared type in canonical spelling (``float64[9]``, ``std_msgs/msg/Header``,
    ``string[]``, ``time``); ``base`` the element type: a primitive name, ``time``/``duration``, or a
    canonical message name. ``array_len`` is ``None`` for a scalar, ``0`` for a variable-length array, N
    for a fixed array. ``is_builtin`` is true for primitives and time/duration.
    """

    name: str
    type: str
    base: str
    array_len: int | None
    is_builtin: bool
    bound: int = 0  # upper bound of a bounded string or sequence (ROS 2), 0 when unbounded

    @classmethod
    def make(cls, name: str, base: str, array_len: int | None, bound: int = 0) -> FieldDef:
        builtin = base in PRIMITIVES or base in TIME_TYPES
        suffix = "" if array_len is None else ("[]" if array_len == 0 else f"[{array_len}]")
        return cls(name, base + suffix, base, array_len, builtin, bound)

    @property
    def is_array(self) -> bool:
        return self.array_len is not None


@attrs.frozen
class Constant:
    """A constant of a message: ``uint8 FOO=1``."""

    name: str
    type: str
    value: Any


@attrs.frozen
class MsgDef:
    """A message definition: its canonical name, fields and constants."""

    name: str
    fields: tuple[FieldDef, ...]
    constants: tuple[Constant, ...] = ()
