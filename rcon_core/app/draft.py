"""A widget being added: its kind, what it is bound to, and its settings, before it is on a canvas."""

from __future__ import annotations

from typing import Any

import attrs

from rcon_core.app.settings_form import settings_problems
from rcon_core.plugins import Binding, Role, WidgetSpec


@attrs.define
class Candidate:
    """One ranked answer of the matcher: a widget that fits, and the field paths it would bind."""

    spec: WidgetSpec
    field_paths: tuple[str, ...] = ()
    score: float = 0.0
    reason: str = ""
    #: every field path the widget could bind on this type, best first (the operator may pick another)
    choices: tuple[str, ...] = ()


@attrs.define
class Target:
    """A topic or service a widget could be bound to."""

    name: str
    type: str
    field_paths: tuple[str, ...] = ()
    #: every field path the widget could bind on this target's type, best first
    choices: tuple[str, ...] = ()


@attrs.define
class Draft:
    """Everything needed to put a new widget on a canvas."""

    spec: WidgetSpec
    role: Role
    target: Target | None = None
    settings: Any = None
    title: str = ""

    @property
    def binding(self) -> Binding:
        if self.target is None:
            return Binding(role=self.role)
        return Binding(self.target.name, self.target.type, self.role, self.target.field_paths)

    def problems(self) -> list[str]:
        """What keeps the draft from being placed: binding first, then the settings' own checks."""
        return list(self.binding.problems()) + settings_problems(self.settings)

    def settings_dict(self) -> dict[str, Any]:
        return self.spec.settings_to_dict(self.settings) if self.settings is not None else {}
