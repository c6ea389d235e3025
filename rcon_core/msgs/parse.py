""".msg / .srv / .action text -> :class:`MsgDef` (our own small parser, so that every spelling survives)."""

from __future__ import annotations

import re
from typing import Any

from . import names
from .fielddefs import IDL_ALIASES, PRIMITIVES, TIME_TYPES, Constant, FieldDef, MsgDef

__all__ = ["parse_msg", "parse_interface", "resolve_base", "split_full_text", "MsgParseError"]


class MsgParseError(ValueError):
    """A definition text that cannot be read; the message names the line."""


_TYPE_RE = re.compile(
    r"(?P<base>[A-Za-z][A-Za-z0-9_/]*)(?:<=(?P<sbound>\d+))?(?P<arr>\[(?:<=)?(?P<n>\d*)\])?\Z"
)
_NAME_RE = re.compile(r"[A-Za-z][A-Za-z0-9_]*\Z")
_TIME_NAMES = {
    "time": "time",
    "duration": "duration",
    "builtin_interfaces/Time": "time",
    "builtin_interfaces/msg/Time": "time",
    "builtin_interfaces/Duration": "duration",
    "builtin_interfaces/msg/Duration": "duration",
}


def resolve_base(base: str, package: str) -> str:
    """Canonical element type for ``base`` written inside ``package``."""
    if base in _TIME_NAMES:
        return _TIME_NAMES[base]
    if base in PRIMITIVES:
        return base
    if base in IDL_ALIASES:
        return IDL_ALIASES[base]
    if base == "Header":
        return "std_msgs/msg/Header"
    if "/" not in base:
        return f"{package}/msg/{base}"
    return names.normalize(base)


def parse_type(text: str, package: str) -> tuple[str, int | None, int]:
    """``(base, array_len, bound)`` for a type written in a .msg file."""
    m = _TYPE_RE.match(text)
    if not m:
        raise ValueError(f"not a field type: {text!r}")
    base = resolve_base(m["base"], package)
    array_len: int | None = None
    bound = int(m["sbound"] or 0)
    if m["arr"]:
        fixed = m["n"] and "<=" not in m["arr"]
        array_len = int(m["n"]) if fixed else 0
        if not fixed and m["n"]:
            bound = int(m["n"])
    return base, array_len, bound


def _const_value(typ: str, raw: str) -> Any:
    if typ in ("string", "wstring"):
        return raw
    raw = raw.strip()
    if typ == "bool":
        if raw.lower() in ("true", "1"):
            return True
        if raw.lower() in ("false", "0"):
            return False
        raise ValueError(f"not a bool constant: {raw!r}")
    if PRIMITIVES[typ].kind == "float":
        return float(raw)
    return int(raw, 0)


def parse_msg(name: str, text: str) -> MsgDef:
    """Parse the text of one .msg (or one part of a .srv/.action) as the message ``name``."""
    canonical = names.normalize(name)
    package = names.package(canonical)
    fields: list[FieldDef] = []
    constants: list[Constant] = []
    for lineno, line in enumerate(text.splitlines(), 1):
        stripped = line.strip()
        if not stripped or stripped.startswith("#"):
            continue
        parts = stripped.split(None, 1)
        if len(parts) < 2:
            raise MsgParseError(f"{canonical}: line {lineno}: expected 'type name', got {stripped!r}")
        typ, rest = parts
        try:
            base, array_len, bound = parse_type(typ, package)
        except ValueError as exc:
            raise MsgParseError(f"{canonical}: line {lineno}: {exc}") from None
        # constants: NAME=VALUE (string constants keep '#' and everything to the end of the line)
        m = re.match(r"([A-Za-z][A-Za-z0-9_]*)\s*=\s*(.*)\Z", rest)
        if m:
            if base not in PRIMITIVES or array_len is not None:
                raise MsgParseError(f"{canonical}: line {lineno}: constants must have a primitive type")
            raw = m[2] if base in ("string", "wstring") else m[2].split("#", 1)[0]
            try:
                constants.append(Constant(m[1], base, _const_value(base, raw.strip())))
            except ValueError as exc:
                raise MsgParseError(f"{canonical}: line {lineno}: {exc}") from None
            continue
        fname = rest.split("#", 1)[0].split()[0]
        if not _NAME_RE.match(fname):
            raise MsgParseError(f"{canonical}: line {lineno}: not a field name: {fname!r}")
        fields.append(FieldDef.make(fname, base, array_len, bound))
    return MsgDef(canonical, tuple(fields), tuple(constants))


def _split_parts(text: str) -> list[str]:
    parts: list[list[str]] = [[]]
    for line in text.splitlines():
        if line.strip() == "---":
            parts.append([])
        else:
            parts[-1].append(line)
    return ["\n".join(p) for p in parts]


def parse_interface(name: str, text: str) -> list[MsgDef]:
    """Parse a message, service or action by the kind in ``name`` (``pkg/srv/Type`` -> two parts)."""
    pkg, kind, typ = names.split(names.normalize(name))
    if kind == "msg":
        return [parse_msg(f"{pkg}/msg/{typ}", text)]
    parts = _split_parts(text)
    suffixes = names.SERVICE_PARTS if kind == "srv" else names.ACTION_PARTS
    if len(parts) != len(suffixes):
        raise MsgParseError(
            f"{name}: a {kind} needs {len(suffixes)} parts separated by '---', found {len(parts)}"
        )
    return [parse_msg(f"{pkg}/{kind}/{typ}_{suffix}", part) for suffix, part in zip(suffixes, parts, strict=True)]


def split_full_text(name: str, text: str) -> list[tuple[str, str]]:
    """``(type, .msg text)`` of each definition in a ``gendeps --cat``-style text: the type ``name`` first,
    then one block per type it uses after a line of ``=`` and ``MSG: pkg/Type`` (rosapi's
    ``typedefs_full_text``, both ROS 1 and ROS 2)."""
    blocks: list[tuple[str, list[str]]] = [(name, [])]
    lines = text.splitlines()
    i = 0
    while i < len(lines):
        line = lines[i]
        nxt = lines[i + 1] if i + 1 < len(lines) else ""
        if set(line.strip()) == {"="} and len(line.strip()) >= 10 and nxt.startswith("MSG: "):
            blocks.append((nxt[5:].strip(), []))
            i += 2
            continue
        blocks[-1][1].append(line)
        i += 1
    return [(n, "\n".join(body) + "\n") for n, body in blocks]


TIME_NAMES = _TIME_NAMES
__all__ += ["TIME_NAMES", "TIME_TYPES"]
