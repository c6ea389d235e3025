"""All-zero messages built from rosapi typedefs, for answers the client must give without a handler's help.

Used when an advertised service's handler fails: rosbridge 0.11 rejects a ``service_response`` whose
``values`` is not an object and the ROS caller then waits forever (README point 21), so the client answers
with the response type's default message instead.  The typedefs come from ``/rosapi/service_response_details``
(ROS 1 ``pkg/Type`` base names, or ROS 2 IDL names such as ``boolean``/``double``/``octet``).
"""

from __future__ import annotations

import base64
from typing import Any

from .rawdecode import _short, typedef_index

_BOOL = {"bool", "boolean"}
_INT = {"int8", "uint8", "byte", "char", "octet", "int16", "uint16", "int32", "uint32", "int64", "uint64"}
_FLOAT = {"float32", "float64", "float", "double"}
_STRING = {"string", "wstring"}
_BYTES = {"uint8", "char", "octet", "byte"}  # arrays of these are base64 text on the JSON wire
_TIME = {"time", "duration"}  # ROS 1 primitives; ROS 2 spells them as nested builtin_interfaces types


def _scalar(base: str, index: dict[str, dict[str, Any]], depth: int) -> Any:
    if base in _BOOL:
        return False
    if base in _INT:
        return 0
    if base in _FLOAT:
        return 0.0
    if base in _STRING:
        return ""
    if base in _TIME:
        return {"secs": 0, "nsecs": 0}
    td = index.get(base) or index.get(_short(base))
    if td is None or depth > 32:
        return {}
    return _message(td, index, depth + 1)


def _message(td: dict[str, Any], index: dict[str, dict[str, Any]], depth: int) -> dict[str, Any]:
    names = td.get("fieldnames") or []
    types = td.get("fieldtypes") or []
    lens = td.get("fieldarraylen") or [-1] * len(names)
    out: dict[str, Any] = {}
    for name, base, n in zip(names, types, lens, strict=False):
        if not isinstance(name, str) or not isinstance(base, str):
            continue
        n = n if isinstance(n, int) else -1
        if n < 0:
            out[name] = _scalar(base, index, depth)
        elif base in _BYTES:
            out[name] = base64.b64encode(bytes(n)).decode("ascii")
        elif n == 0:
            out[name] = []
        else:
            out[name] = [_scalar(base, index, depth) for _ in range(n)]
    return out


def default_from_typedefs(typedefs: list[dict[str, Any]]) -> tuple[dict[str, Any], set[str]]:
    """The all-zero message of the first (root) typedef, and the names of its scalar string fields."""
    if not typedefs or not isinstance(typedefs[0], dict):
        return {}, set()
    root = typedefs[0]
    index = typedef_index([td for td in typedefs if isinstance(td, dict)])
    strings = {name for name, base, n in zip(root.get("fieldnames") or [], root.get("fieldtypes") or [],
                                             root.get("fieldarraylen") or [], strict=False)
               if base in _STRING and n == -1}
    return _message(root, index, 0), strings
