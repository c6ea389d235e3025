"""``.msg``-style definition text of a type and everything it uses (like ``gendeps --cat``)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from . import names
from .fielddefs import MsgDef

if TYPE_CHECKING:
    from .lookup import TypeLookup

__all__ = ["definition_text", "msgdef_text"]

SEPARATOR = "=" * 80


def _type_text(reg: TypeLookup, base: str) -> str:
    if base in ("time", "duration"):
        if reg.ros2:
            return f"builtin_interfaces/{'Time' if base == 'time' else 'Duration'}"
        return base
    if "/" in base:
        return reg.wire_name(base)
    return base


def msgdef_text(reg: TypeLookup, md: MsgDef) -> str:
    """The text of one definition: constants first, then fields."""
    lines = []
    for c in md.constants:
        value = c.value
        if isinstance(value, bool):
            value = "true" if value else "false"
        lines.append(f"{c.type} {c.name}={value}")
    for f in md.fields:
        suffix = "" if f.array_len is None else ("[]" if f.array_len == 0 else f"[{f.array_len}]")
        lines.append(f"{_type_text(reg, f.base)}{suffix} {f.name}")
    return "\n".join(lines) + ("\n" if lines else "")


def definition_text(reg: TypeLookup, name: str, dependencies: bool = False) -> str:
    """Text of ``name`` (a message, or a whole service/action with ``---`` between parts) and its types."""
    try:
        roots = [reg.resolve(name)]
        parts_text = [msgdef_text(reg, reg.msgdef(roots[0]))]
    except KeyError:
        parent = reg.resolve_interface(name)
        kind = "srv" if "/srv/" in parent else "action"
        parts = ("request", "response") if kind == "srv" else ("goal", "result", "feedback")
        roots = [names.part_name(parent, p) for p in parts]
        parts_text = [msgdef_text(reg, reg.msgdef(r)) for r in roots]
    out = "---\n".join(parts_text)
    if not dependencies:
        return out
    seen: list[str] = []
    for r in roots:
        for dep in reg.dependencies(r):
            if dep not in seen:
                seen.append(dep)
    for dep in seen:
        out += f"\n{SEPARATOR}\nMSG: {reg.wire_name(dep)}\n{msgdef_text(reg, reg.msgdef(dep))}"
    return out
