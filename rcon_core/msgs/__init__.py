"""RCON's message types: names, definitions, rosapi typedefs, defaults, typed objects, text input.

No Qt here. Messages travel as plain wire-shape dicts; see ``docs/architecture.md``.
"""

from .fielddefs import Constant, FieldDef, MsgDef
from .names import normalize, to_ros1, to_ros2
from .registry import TypeRegistry, UnknownTypeError
from .text import MessageTextError, Problem
from .walk import walk_fields

__all__ = [
    "TypeRegistry",
    "UnknownTypeError",
    "MessageTextError",
    "Problem",
    "FieldDef",
    "MsgDef",
    "Constant",
    "normalize",
    "to_ros1",
    "to_ros2",
    "walk_fields",
]
