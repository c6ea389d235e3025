"""``TypeLookup``: what the helpers of ``msgs`` need from a registry -- and nothing else.

The serializers (``ros1_wire``, ``cdr``), the typed classes (``typed``), message text (``text``,
``deftext``) and rosapi typedefs (``typedefs``) are written against this small protocol, not against
:class:`~rcon_core.msgs.registry.TypeRegistry`: the registry uses them, they never import it back, and each
keeps its own caches (a :class:`~rcon_core.msgs.ros1_wire.Ros1Codec` compiles and caches per type; the
registry drops its codecs when it learns new types, so nothing stale is kept).
"""

from __future__ import annotations

from typing import Any, Protocol

from .fielddefs import FieldDef, MsgDef


class TypeLookup(Protocol):
    """Message definitions by name, and the flavour's wire conventions."""

    ros2: bool

    @property
    def time_fields(self) -> tuple[str, str]: ...

    def resolve(self, name: str) -> str: ...

    def resolve_interface(self, name: str) -> str: ...

    def msgdef(self, name: str) -> MsgDef: ...

    def dependencies(self, name: str) -> list[str]: ...

    def wire_name(self, name: str) -> str: ...

    def default_value(self, f: FieldDef) -> Any: ...

    def default(self, name: str) -> dict[str, Any]: ...
