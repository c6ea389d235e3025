"""Walking a message type's fields: one walk for the matcher and the children editor.

``walk_fields(types, "geometry_msgs/msg/Twist")`` yields ``linear`` (a message), ``linear.x``,
``linear.y``, ``linear.z``, ``angular``, ... in definition order (pre-order). Builtin fields (scalars and
arrays) are leaves; a nested message that is not an array is yielded and then descended, at most
:data:`MAX_DEPTH` levels deep. Arrays of messages are yielded nowhere: no single path fits them.
No Qt here.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import attrs

__all__ = ["FieldStep", "MAX_DEPTH", "PLACEHOLDER", "own_fields", "walk_fields"]

#: how deep the walk descends into nested messages (BatteryState's header.stamp is depth 2)
MAX_DEPTH = 6
#: the member rosbags/IDL put in empty ROS 2 messages; not a real field
PLACEHOLDER = "structure_needs_at_least_one_member"


@attrs.frozen
class FieldStep:
    """One field met on the walk."""

    path: str  #: dotted path from the walked type (with the caller's prefix)
    field: Any  #: the FieldDef
    depth: int  #: 0 for the walked type's own fields

    @property
    def is_message(self) -> bool:
        return not self.field.is_builtin


def own_fields(types: Any, type_name: str) -> tuple[Any, ...]:
    """The fields of ``type_name`` without the empty-message placeholder."""
    return tuple(f for f in types.fields(type_name) if f.name != PLACEHOLDER)


def _join(prefix: str, name: str) -> str:
    return f"{prefix}.{name}" if prefix else name


def walk_fields(types: Any, type_name: str, prefix: str = "", depth: int = 0) -> Iterator[FieldStep]:
    """Every leaf and every scalar nested message of ``type_name``, pre-order (see the module doc).

    ``types`` is anything with ``fields(type_name)`` (a TypeRegistry); its UnknownTypeError passes through.
    """
    for f in own_fields(types, type_name):
        path = _join(prefix, f.name)
        if f.is_builtin:
            yield FieldStep(path, f, depth)
        elif f.array_len is None and depth < MAX_DEPTH:
            yield FieldStep(path, f, depth)
            yield from walk_fields(types, f.base, path, depth + 1)
