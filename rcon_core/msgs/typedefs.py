"""rosapi ``message_details`` typedefs: produce them exactly like rosbridge's rosapi, and learn from them.

ROS 1 (rosbridge 0.11.x): type names ``pkg/Type``; ``time``/``duration`` are pseudo-types with int32
``secs``/``nsecs``; primitives keep their .msg spelling (``byte`` stays ``byte``).

ROS 2 (rosbridge 1.x/2.x rosapi): type names are built from the Python class (``pkg/Type``, service
halves ``pkg/Type_Request``), primitives use the IDL names the generated classes report
(``double``, ``float``, ``boolean``, ``octet``), and time is the message ``builtin_interfaces/Time``
with ``sec``/``nanosec``.

Both: the requested type first, then every nested type once, depth first; ``fieldarraylen`` -1 for a
scalar, 0 for a variable array, N for a fixed one; ``examples`` are ``str()`` of a default instance's
value, ``"[]"`` for arrays and ``"{}"`` for nested messages; constants sorted by name with ``str()``
values.
"""

from __future__ import annotations

import re
from typing import TYPE_CHECKING, Any

from . import names
from .fielddefs import IDL_ALIASES, PRIMITIVES, TIME_TYPES, Constant, FieldDef, MsgDef

if TYPE_CHECKING:
    from .lookup import TypeLookup

__all__ = ["build_typedefs", "parse_typedefs", "TypedefError"]


class TypedefError(ValueError):
    """A typedef list from a server that cannot be understood."""


_ROS2_PRIM = {"bool": "boolean", "byte": "octet", "char": "uint8", "float32": "float", "float64": "double"}
_ROS2_TIME = {"time": "builtin_interfaces/Time", "duration": "builtin_interfaces/Duration"}
_KEYS = ("type", "fieldnames", "fieldtypes", "fieldarraylen", "examples", "constnames", "constvalues")


def _type_name(base: str, ros2: bool) -> str:
    if base in TIME_TYPES:
        return _ROS2_TIME[base] if ros2 else base
    if base in PRIMITIVES:
        return _ROS2_PRIM.get(base, base) if ros2 else base
    return _msg_name(base, ros2)


def _msg_name(name: str, ros2: bool) -> str:
    if ros2:
        pkg, _kind, typ = names.split(name)
        return f"{pkg}/{typ}"
    return names.to_ros1(name)


def _example(f: FieldDef, ros2: bool) -> str:
    if f.array_len is not None:
        return "[]"
    if f.base in TIME_TYPES or f.base not in PRIMITIVES:
        return "{}"
    kind = PRIMITIVES[f.base].kind
    if kind == "bool":
        return "False"
    if kind == "float":
        return "0.0"
    if kind == "string":
        return ""
    if ros2 and f.base == "byte":
        return "b'\\x00'"
    return "0"


def _time_typedef(base: str, ros2: bool) -> dict[str, Any]:
    if ros2:
        return {
            "type": _ROS2_TIME[base],
            "fieldnames": ["sec", "nanosec"],
            "fieldtypes": ["int32", "uint32"],
            "fieldarraylen": [-1, -1],
            "examples": ["0", "0"],
            "constnames": [],
            "constvalues": [],
        }
    return {
        "type": base,
        "fieldnames": ["secs", "nsecs"],
        "fieldtypes": ["int32", "int32"],
        "fieldarraylen": [-1, -1],
        "examples": ["0", "0"],
        "constnames": [],
        "constvalues": [],
    }


def _entry(md: MsgDef, ros2: bool) -> dict[str, Any]:
    consts = sorted(md.constants, key=lambda c: c.name)
    return {
        "type": _msg_name(md.name, ros2),
        "fieldnames": [f.name for f in md.fields],
        "fieldtypes": [_type_name(f.base, ros2) for f in md.fields],
        "fieldarraylen": [-1 if f.array_len is None else f.array_len for f in md.fields],
        "examples": [_example(f, ros2) for f in md.fields],
        "constnames": [c.name for c in consts],
        "constvalues": [str(c.value) for c in consts],
    }


def build_typedefs(reg: TypeLookup, name: str) -> list[dict[str, Any]]:
    """The typedef list for the message ``name`` (canonical), in rosapi's order."""
    ros2 = reg.ros2
    out: list[dict[str, Any]] = []
    seen: set[str] = set()

    def visit(md: MsgDef) -> None:
        out.append(_entry(md, ros2))
        for f in md.fields:
            if f.base in seen or f.base in PRIMITIVES:
                continue
            seen.add(f.base)
            if f.base in TIME_TYPES:
                out.append(_time_typedef(f.base, ros2))
            else:
                visit(reg.msgdef(f.base))

    seen.add(name)
    visit(reg.msgdef(name))
    return out


# ---------------------------------------------------------------- learning from a server's answer

_SEQ = re.compile(r"sequence<\s*([^,>]+)")
_BOUNDED_STR = re.compile(r"w?string<=?\d+>?\Z")


def _learn_base(raw: str) -> str:
    t = raw.strip()
    m = _SEQ.match(t)
    if m:
        t = m[1].strip()
    t = t.split("[", 1)[0]
    if _BOUNDED_STR.match(t):
        t = "wstring" if t.startswith("w") else "string"
    if t in ("time", "builtin_interfaces/Time", "builtin_interfaces/msg/Time"):
        return "time"
    if t in ("duration", "builtin_interfaces/Duration", "builtin_interfaces/msg/Duration"):
        return "duration"
    if t in PRIMITIVES:
        return t
    if t in IDL_ALIASES:
        return IDL_ALIASES[t]
    return names.normalize(t)


def _entry_name(raw: str) -> str:
    """Canonical name of a typedef's ``type``: ROS 2 ``pkg/Type_Request`` is a service half."""
    pkg, kind, typ = names.split(raw)
    if kind == "msg" and raw.count("/") == 1:
        for parent_kind, suffixes in (("srv", names.SERVICE_PARTS), ("action", names.ACTION_PARTS)):
            for suffix in suffixes:
                if typ.endswith("_" + suffix):
                    return f"{pkg}/{parent_kind}/{typ}"
    return names.normalize(raw)


#: what rosapi 2.x's ``constvalues`` hold for class attributes that are not constants: tuples of rosidl
#: objects with memory addresses, ``array('B')``, numpy's ``[0. 0. 0.]``, nested message reprs
_NOT_A_LITERAL = re.compile(r"\A(\(.*\)|array\(.*|\[[^,]*\]|[A-Za-z_][\w.]*\.msg\.\w+\(.*)\Z|object at 0x", re.S)


def is_real_constant(name: str, value: str, field_names: set[str]) -> bool:
    """False for what rosapi 2.1.0 lists among ``constnames`` but is no constant of the type
    (``rosbridge-ros2-2.1.0/rosapi.jsonl:5-10``): ``SLOT_TYPES``, every field name, rosidl's
    ``<FIELD>__DEFAULT`` attributes, and any value that is a Python repr rather than a literal."""
    if name == "SLOT_TYPES" or name in field_names:
        return False
    if name.endswith("__DEFAULT") and name[: -len("__DEFAULT")].lower() in field_names:
        return False
    return not _NOT_A_LITERAL.search(value)


def clean_typedefs(typedefs: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The typedefs with only their real constants (see :func:`is_real_constant`); other keys unchanged."""
    out = []
    for td in typedefs:
        if not isinstance(td, dict):
            out.append(td)
            continue
        fields = {str(f) for f in td.get("fieldnames") or []}
        pairs = [(str(n), str(v)) for n, v in zip(td.get("constnames") or [], td.get("constvalues") or [],
                                                  strict=False) if is_real_constant(str(n), str(v), fields)]
        out.append({**td, "constnames": [n for n, _ in pairs], "constvalues": [v for _, v in pairs]})
    return out


def _const(name: str, value: str) -> Constant:
    try:
        return Constant(name, "int64", int(value))
    except ValueError:
        pass
    try:
        return Constant(name, "float64", float(value))
    except ValueError:
        pass
    if value in ("True", "False"):
        return Constant(name, "bool", value == "True")
    return Constant(name, "string", value)


def parse_typedefs(typedefs: Any, root: str | None = None) -> list[MsgDef]:
    """Message definitions from a ``typedefs`` list. ``root`` renames the first entry (canonical name)."""
    if isinstance(typedefs, dict) and "typedefs" in typedefs:
        typedefs = typedefs["typedefs"]
    if not isinstance(typedefs, list):
        raise TypedefError(f"expected a list of typedefs, got {type(typedefs).__name__}")
    out: list[MsgDef] = []
    for i, td in enumerate(typedefs):
        if not isinstance(td, dict):
            raise TypedefError(f"typedef {i}: expected an object, got {type(td).__name__}")
        missing = [k for k in _KEYS[:4] if k not in td]
        if missing:
            raise TypedefError(f"typedef {i}: missing {', '.join(missing)}")
        raw = td["type"]
        if not isinstance(raw, str):
            raise TypedefError(f"typedef {i}: 'type' must be a string")
        if raw in ("time", "duration") or _learn_base(raw) in TIME_TYPES:
            continue
        fnames, ftypes, flens = td["fieldnames"], td["fieldtypes"], td["fieldarraylen"]
        if not (len(fnames) == len(ftypes) == len(flens)):
            raise TypedefError(f"typedef {raw}: fieldnames, fieldtypes and fieldarraylen differ in length")
        try:
            name = root if (i == 0 and root) else _entry_name(raw)
            fields = []
            for fname, ftype, flen in zip(fnames, ftypes, flens, strict=True):
                array_len = None if int(flen) < 0 else int(flen)
                if array_len is None and "sequence<" in str(ftype):
                    array_len = 0
                fields.append(FieldDef.make(str(fname), _learn_base(str(ftype)), array_len))
        except ValueError as exc:
            raise TypedefError(f"typedef {raw}: {exc}") from None
        field_names = {str(f) for f in fnames}
        consts = tuple(
            _const(str(cn), str(cv))
            for cn, cv in zip(td.get("constnames", []), td.get("constvalues", []), strict=False)
            if is_real_constant(str(cn), str(cv), field_names)
        )
        out.append(MsgDef(name, tuple(fields), consts))
    return out
