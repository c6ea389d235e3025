"""Turn JSON that a client sent into a message of a known type, as rosbridge's message_conversion does.

Works from rosapi typedefs (the layout ``TypeRegistry.typedefs`` returns): missing fields get defaults,
integers are accepted for floats, ``uint8[]``/``char[]`` become ``bytes``, numeric arrays numpy arrays.
In ROS 2 mode a ``builtin_interfaces/Time``/``Duration`` takes ``sec``/``nanosec`` or ``secs``/``nsecs`` (missing
ones are 0) and a Time the string ``"now"``, as rosbridge 2.x reads them.  Errors carry the real server's
wording, e.g. ``std_srvs/SetBoolRequest message requires a bool for
field data, but got a <class 'str'>``.
"""

from __future__ import annotations

import base64
import binascii
import math
from collections.abc import Callable
from typing import Any

import numpy as np

INT_TYPES = {"int8", "int16", "int32", "int64", "uint8", "uint16", "uint32", "uint64", "byte", "char", "octet"}
FLOAT_TYPES = {"float32", "float64", "float", "double"}
BOOL_TYPES = {"bool", "boolean"}
_DTYPES: dict[str, Any] = {
    "int8": np.int8, "byte": np.int8, "int16": np.int16, "int32": np.int32, "int64": np.int64,
    "uint16": np.uint16, "uint32": np.uint32, "uint64": np.uint64,
    "float32": np.float32, "float64": np.float64, "float": np.float32, "double": np.float64,
}
BYTES_TYPES = {"uint8", "char"}  # byte[] (ROS 2 octet) stays a list of numbers, as rosbridge 2.x sends it


#: ROS 2 spellings of the time types in typedefs (ROS 1's ``time``/``duration`` are primitives there)
_ROS2_TIMES = {"builtin_interfaces/Time", "builtin_interfaces/msg/Time", "builtin_interfaces/Duration",
               "builtin_interfaces/msg/Duration"}


class ConversionError(ValueError):
    """The client's value does not fit the type; the text matches rosbridge's."""


def _pytype(value: Any) -> str:
    return f"<class '{type(value).__name__}'>"


class Converter:
    """Converts and fills messages of the types described by a typedefs list."""

    def __init__(self, typedefs: list[dict[str, Any]], now: Callable[[], dict[str, int]] | None = None) -> None:
        self.defs = {d["type"]: d for d in typedefs}
        self.root = typedefs[0]["type"] if typedefs else ""
        self._now = now

    # -- defaults --------------------------------------------------------------------------------------

    def default(self, type_name: str | None = None) -> dict[str, Any]:
        td = self.defs[type_name or self.root]
        return {
            name: self._default_field(ftype, alen)
            for name, ftype, alen in zip(td["fieldnames"], td["fieldtypes"], td["fieldarraylen"], strict=False)
        }

    def _default_scalar(self, ftype: str) -> Any:
        if ftype in BOOL_TYPES:
            return False
        if ftype in INT_TYPES:
            return 0
        if ftype in FLOAT_TYPES:
            return 0.0
        if ftype in ("string", "wstring"):
            return ""
        if ftype in self.defs:
            return self.default(ftype)
        return None

    def _default_field(self, ftype: str, alen: int) -> Any:
        if alen < 0:
            return self._default_scalar(ftype)
        if ftype in BYTES_TYPES:
            return bytes(alen)
        if ftype in _DTYPES:
            return np.zeros(alen, dtype=_DTYPES[ftype])
        return [self._default_scalar(ftype) for _ in range(alen)]

    # -- conversion ------------------------------------------------------------------------------------

    def convert(self, value: Any, type_name: str | None = None) -> dict[str, Any]:
        type_name = type_name or self.root
        if not isinstance(value, dict):
            raise ConversionError(f"Expected a JSON object for type {type_name} but received a {_pytype(value)}")
        return self._message(value, type_name)

    def _message(self, value: dict[str, Any], type_name: str) -> dict[str, Any]:
        td = self.defs[type_name]
        names = td["fieldnames"]
        for key in value:
            if key not in names:
                raise ConversionError(f"Message type {type_name} does not have a field {key}")
        out: dict[str, Any] = {}
        for name, ftype, alen in zip(names, td["fieldtypes"], td["fieldarraylen"], strict=False):
            if name not in value:
                if ftype in ("time", "builtin_interfaces/Time", "builtin_interfaces/msg/Time") and self._now \
                        and type_name.endswith("Header"):
                    out[name] = self._now()
                else:
                    out[name] = self._default_field(ftype, alen)
                continue
            out[name] = self._field(value[name], ftype, alen, type_name, name)
        return out

    def _field(self, value: Any, ftype: str, alen: int, owner: str, name: str) -> Any:
        if alen < 0:
            return self._scalar(value, ftype, owner, name)
        if ftype in BYTES_TYPES:
            return self._bytes(value, owner, name)
        if not isinstance(value, list | tuple):
            raise ConversionError(f"{owner} message requires a list for field {name}, but got a {_pytype(value)}")
        if ftype in _DTYPES:
            items = [self._scalar(v, ftype, owner, name) for v in value]
            return np.array(items, dtype=_DTYPES[ftype])
        return [self._scalar(v, ftype, owner, name) for v in value]

    def _bytes(self, value: Any, owner: str, name: str) -> bytes:
        if isinstance(value, bytes | bytearray):
            return bytes(value)
        if isinstance(value, str):
            try:
                return base64.b64decode(value, validate=True)
            except (binascii.Error, ValueError) as exc:
                raise ConversionError(f"{owner} message field {name} is not valid base64: {exc}") from exc
        if isinstance(value, list) and all(isinstance(v, int) and 0 <= v <= 255 for v in value):
            return bytes(value)
        raise ConversionError(f"{owner} message requires a str for field {name}, but got a {_pytype(value)}")

    def _scalar(self, value: Any, ftype: str, owner: str, name: str) -> Any:
        if ftype in BOOL_TYPES:
            if isinstance(value, bool):
                return value
            raise ConversionError(f"{owner} message requires a {ftype} for field {name}, but got a {_pytype(value)}")
        if ftype in INT_TYPES:
            if isinstance(value, int) and not isinstance(value, bool):
                return value
            raise ConversionError(f"{owner} message requires a {ftype} for field {name}, but got a {_pytype(value)}")
        if ftype in FLOAT_TYPES:
            if value is None:
                return math.nan
            if isinstance(value, int | float) and not isinstance(value, bool):
                return float(value)
            raise ConversionError(
                f"{owner} message requires a {ftype} for field {name}, but got a {_pytype(value)}"
            )
        if ftype in ("string", "wstring"):
            if isinstance(value, str):
                return value
            raise ConversionError(f"{owner} message requires a {ftype} for field {name}, but got a {_pytype(value)}")
        if ftype in _ROS2_TIMES:
            return self._ros2_time(value, ftype, owner, name)
        if ftype in self.defs:
            if not isinstance(value, dict):
                raise ConversionError(
                    f"{owner} message requires a {ftype} for field {name}, but got a {_pytype(value)}"
                )
            return self._message(value, ftype)
        raise ConversionError(f"{owner} message field {name} has unknown type {ftype}")

    def _ros2_time(self, value: Any, ftype: str, owner: str, name: str) -> dict[str, Any]:
        """rosbridge 2.x's time fields: ``sec``/``nanosec`` or the ROS 1 ``secs``/``nsecs``, missing ones 0,
        and the string ``"now"`` for a Time."""
        if value == "now" and "Time" in ftype and self._now is not None:
            return self._now()
        if not isinstance(value, dict):
            raise ConversionError(f"{owner} message requires a {ftype} for field {name}, but got a {_pytype(value)}")
        sec = value.get("sec", value.get("secs", 0))
        nanosec = value.get("nanosec", value.get("nsecs", 0))
        for part in (sec, nanosec):
            if not isinstance(part, int) or isinstance(part, bool):
                raise ConversionError(f"{owner} message requires an int32/uint32 time for field {name}, "
                                      f"but got {_pytype(part)}")
        return {"sec": sec, "nanosec": nanosec}

    def from_args(self, args: Any) -> dict[str, Any]:
        """Service call arguments: an object, an array mapped in field order, or missing/null."""
        if args is None:
            return self.default()
        if isinstance(args, list):
            names = self.defs[self.root]["fieldnames"]
            args = dict(zip(names, args, strict=False))  # extra items are dropped, as in rosbridge
        return self.convert(args)
