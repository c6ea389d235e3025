"""``ModelTypes``: what a widget model (and the children editor) may ask of the app's type registry.

A model is handed the registry as ``types`` (:class:`rcon_core.plugins.WidgetModel`); it reads message
definitions and builds messages, nothing else.  This protocol names exactly that, so the plugin contract
says what a model can rely on without importing :class:`rcon_core.msgs.TypeRegistry` (which is one) or
being typed ``Any``.  It extends :class:`rcon_core.msgs.lookup.TypeLookup` (definitions by name, the
flavour's wire conventions) with the interface names, the message builders and learning typedefs from
a robot.
"""

from __future__ import annotations

from typing import Any, Protocol

from rcon_core.msgs.fielddefs import FieldDef
from rcon_core.msgs.lookup import TypeLookup


class ModelTypes(TypeLookup, Protocol):
    """A type registry as a widget model sees it (``rcon_core.msgs.TypeRegistry`` is one)."""

    def has(self, name: str) -> bool: ...

    def has_service(self, name: str) -> bool: ...

    def fields(self, name: str) -> list[FieldDef]: ...

    def service_part_name(self, name: str, part: str) -> str: ...

    def action_part_name(self, name: str, part: str) -> str: ...

    def from_text(self, name: str, text: str, *, finite: bool = True) -> dict[str, Any]: ...

    def complete(self, name: str, msg: Any, *, finite: bool = False) -> dict[str, Any]: ...

    def add_typedefs(self, typedefs: Any, root: str | None = None) -> list[str]: ...

    def validate(self, name: str, msg: Any, *, finite: bool = False) -> list[Any]: ...
