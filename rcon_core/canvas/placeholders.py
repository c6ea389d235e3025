"""What the canvas runtime puts where a widget cannot run: a small model of its own (no Qt).

A placeholder is not a ``WidgetModel``: it talks to nobody and needs none of a model's machinery, only to
be what the runtime and the front end use of a model (``rcon_core.plugins.api.HostedModel``), with its own
small state. The frame shows why (:attr:`MissingWidgetModel.reason`); the instance's data is never
touched, so the layout saves back unchanged.

- :class:`MissingWidgetModel`: the widget's plugin is not installed (or disabled);
- :class:`BrokenWidgetModel`: the model could not be built (an import error, a robot the workspace lacks);
- :class:`UnconfiguredWidgetModel`: the stored settings hold a value of the wrong type: not an error but
  the "not configured" warning, one sentence per bad value (``problems()``).
"""

from __future__ import annotations

import threading
from typing import Any

import attrs

from rcon_core.plugins.api import Binding, RobotPort, WidgetState

from .workspace import WidgetInstance

__all__ = ["MissingWidgetModel", "BrokenWidgetModel", "UnconfiguredWidgetModel"]


class MissingWidgetModel:
    """Stands in for a widget whose plugin is not installed (or disabled). Never subscribes; its state says
    ``reason`` as the error."""

    #: a placeholder sends nothing, shows no robot and is never a preview
    view_only: str | None = None
    shows_every_robot = False
    dry_run = False
    fleet_wide = False

    def __init__(self, instance: WidgetInstance, reason: str) -> None:
        self.kind = instance.kind
        self.binding: Binding = instance.binding
        self.reason = reason
        self._lock = threading.Lock()
        self._state = WidgetState(error=reason or None)

    @property
    def state(self) -> WidgetState:
        with self._lock:
            return self._state

    def _change(self, **fields: Any) -> None:
        with self._lock:
            self._state = attrs.evolve(self._state, **fields, seq=self._state.seq + 1)

    def start(self) -> None:
        self._change(running=True)

    def stop(self) -> None:
        self._change(running=False)

    def set_link(self, up: bool) -> None:
        """A placeholder shows why it stands there, not the link."""

    def set_error(self, error: str | None) -> None:
        if error != self.state.error:
            self._change(error=error)

    def problems(self) -> list[str]:
        return [self.reason]

    def child_models(self) -> list[Any]:
        return []

    def on_focus_lost(self) -> None:
        """Nothing to stop."""

    def on_fleet(self, robots: list[RobotPort]) -> None:
        """Never fleet-wide."""

    def on_robot_link(self, robot_id: str, up: bool) -> None:
        """Never fleet-wide."""

    def shown_message(self) -> dict[str, Any] | None:
        return None


class BrokenWidgetModel(MissingWidgetModel):
    """Stands in for a widget whose model could not be built; ``reason`` says why."""


class UnconfiguredWidgetModel(MissingWidgetModel):
    """Stands in for a widget whose stored settings cannot be read (a value of the wrong type): not an
    error but the "not configured" warning, one sentence per bad value (``problems()``)."""

    def __init__(self, instance: WidgetInstance, problems: list[str]) -> None:
        super().__init__(instance, "; ".join(problems))
        self._state = WidgetState()
        self._problems = list(problems)

    def problems(self) -> list[str]:
        return list(self._problems)
