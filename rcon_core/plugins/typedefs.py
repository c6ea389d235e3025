"""Turn contributed ``.msg``/``.srv`` text into rosapi ``message_details`` typedefs.

Plugins contribute definitions as text (``rcon_register_types``); the type registry learns types
from typedefs (the layout a real rosapi server answers). Field types are written in the ROS 1
spelling (``pkg/Type``), as rosapi does; a bare name (``Vector3``) means the same package, except
``Header`` which is ``std_msgs/Header``.
"""

from __future__ import annotations

import re
from typing import Any

from .registry import TypeDefinition
from .spec import SpecError

__all__ = ["msg_text_to_typedef", "srv_text_to_typedefs", "definition_to_typedefs", "ros1_name"]

_BUILTINS = {
    "bool", "byte", "char", "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64",
    "float32", "float64", "string", "wstring", "time", "duration",
}  # fmt: skip
_FIELD = re.compile(
    r"^(?P<type>[A-Za-z][A-Za-z0-9_/]*)(?:<=\d+)?(?P<array>\[(?:<=)?(?P<len>\d*)\])?\s+"
    r"(?P<name>[A-Za-z][A-Za-z0-9_]*)\s*(?P<const>=.*)?(?:\s+.*)?$"
)
_EXAMPLES = {"bool": "False", "string": "", "wstring": "", "time": "{}", "duration": "{}"}


def ros1_name(name: str) -> str:
    """``pkg/msg/Type`` -> ``pkg/Type``; ``pkg/Type`` unchanged."""
    parts = name.split("/")
    return f"{parts[0]}/{parts[-1]}" if len(parts) == 3 else name


def _field_type(token: str, package: str) -> str:
    if token in _BUILTINS:
        return token
    if token == "Header":
        return "std_msgs/Header"
    if "/" not in token:
        return f"{package}/{token}"
    return ros1_name(token)


def msg_text_to_typedef(name: str, text: str) -> dict[str, Any]:
    """One typedef dict (``type``, ``fieldnames``, ``fieldtypes``, ``fieldarraylen``, ``examples``,
    ``constnames``, ``constvalues``) for ``.msg`` text. Raises SpecError naming the bad line."""
    type_name = ros1_name(name)
    package = type_name.split("/")[0]
    td: dict[str, Any] = {
        "type": type_name, "fieldnames": [], "fieldtypes": [], "fieldarraylen": [],
        "examples": [], "constnames": [], "constvalues": [],
    }  # fmt: skip
    for lineno, raw in enumerate(text.splitlines(), 1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        m = _FIELD.match(line)
        if not m:
            raise SpecError(f"{name}: line {lineno}: cannot read {raw.strip()!r} as 'type name'")
        ftype = _field_type(m.group("type"), package)
        if m.group("const"):
            td["constnames"].append(m.group("name"))
            td["constvalues"].append(m.group("const")[1:].strip())
            continue
        array = m.group("array")
        alen = -1 if not array else (int(m.group("len")) if m.group("len") and "<=" not in array else 0)
        td["fieldnames"].append(m.group("name"))
        td["fieldtypes"].append(ftype)
        td["fieldarraylen"].append(alen)
        if array:
            td["examples"].append("[]")
        elif ftype in _BUILTINS:
            td["examples"].append(_EXAMPLES.get(ftype, "0"))
        else:
            td["examples"].append("{}")
    return td


def srv_text_to_typedefs(name: str, text: str) -> tuple[dict[str, Any], dict[str, Any]]:
    """(request typedef, response typedef) named ``pkg/TypeRequest`` / ``pkg/TypeResponse`` as rosapi does."""
    lines = text.splitlines()
    try:
        cut = next(i for i, line in enumerate(lines) if line.strip() == "---")
    except StopIteration:
        raise SpecError(f"{name}: service definition has no '---' line") from None
    base = ros1_name(name)
    return (
        msg_text_to_typedef(base + "Request", "\n".join(lines[:cut])),
        msg_text_to_typedef(base + "Response", "\n".join(lines[cut + 1 :])),
    )


def definition_to_typedefs(d: TypeDefinition) -> list[dict[str, Any]]:
    """The typedefs for one contributed definition (messages only; see ``PluginManager.apply_types``)."""
    if d.kind == "msg":
        return [msg_text_to_typedef(d.name, d.text)]
    if d.kind == "typedefs":
        return [dict(t) for t in d.typedefs]
    if d.kind == "srv":
        return list(srv_text_to_typedefs(d.name, d.text))
    raise SpecError(f"unknown definition kind {d.kind!r}")
