"""The data of a workspace: canvases of widget instances. Plain attrs classes, no behaviour beyond lookup.

Edit a workspace through :class:`rcon_core.canvas.document.Document` (undo/redo, notifications,
locking); read it directly. Geometry is in canvas units (device-independent pixels).
"""

from __future__ import annotations

import uuid
from typing import Any

import attrs

from rcon_core.plugins.model import Binding

from .robots import Robot, UnknownRobot, default_robot, resolve_robot

__all__ = ["Geometry", "WidgetInstance", "Canvas", "Workspace", "new_id", "Binding", "Robot", "UnknownRobot"]


def new_id(prefix: str) -> str:
    """A fresh short id such as ``w-3f9a1c2e``; also used as the bridge node id of a widget."""
    return f"{prefix}-{uuid.uuid4().hex[:8]}"


@attrs.define
class Geometry:
    x: float = attrs.field(default=0.0, converter=float)
    y: float = attrs.field(default=0.0, converter=float)
    w: float = attrs.field(default=160.0, converter=float)
    h: float = attrs.field(default=80.0, converter=float)


@attrs.define
class WidgetInstance:
    """One widget on a canvas.

    ``settings`` is the stored dict of the widget's per-instance settings, kept as-is (the runtime
    turns it into the settings object), so a widget whose plugin is missing keeps it unchanged.
    ``extra`` holds keys of the saved file this version does not know; they are written back.
    """

    id: str
    kind: str
    binding: Binding = attrs.field(factory=Binding)
    geometry: Geometry = attrs.field(factory=Geometry)
    settings: dict[str, Any] = attrs.field(factory=dict)
    title: str = ""
    extra: dict[str, Any] = attrs.field(factory=dict)


@attrs.define
class Canvas:
    id: str
    name: str
    widgets: list[WidgetInstance] = attrs.field(factory=list)
    locked: bool = False  #: a locked canvas refuses edits (operator mode)
    #: a view-only canvas never publishes, calls or serves: its widgets' ports refuse (canvas.port)
    view_only: bool = False
    extra: dict[str, Any] = attrs.field(factory=dict)

    def widget(self, widget_id: str) -> WidgetInstance:
        for w in self.widgets:
            if w.id == widget_id:
                return w
        raise KeyError(f"canvas {self.name!r} has no widget {widget_id!r}")


@attrs.define
class Workspace:
    """Every canvas, the current one, the per-kind shared ("plugin") settings and the robots (at least
    one; the first is the one a binding without ``robot`` talks to)."""

    canvases: list[Canvas] = attrs.field(factory=list)
    current: str = ""
    plugin_settings: dict[str, dict[str, Any]] = attrs.field(factory=dict)
    extra: dict[str, Any] = attrs.field(factory=dict)
    robots: list[Robot] = attrs.field(factory=lambda: [default_robot()])

    def robot(self, robot_id: str) -> Robot:
        """The robot a binding names (``""``: the first). Raises :class:`UnknownRobot` (a KeyError)."""
        return resolve_robot(self.robots, robot_id)

    def robot_of(self, widget: WidgetInstance) -> Robot:
        return resolve_robot(self.robots, widget.binding.robot)

    @classmethod
    def new(cls, name: str = "Main") -> Workspace:
        """A workspace with one empty canvas, current."""
        c = Canvas(new_id("c"), name)
        return cls([c], c.id)

    def canvas(self, canvas_id: str) -> Canvas:
        for c in self.canvases:
            if c.id == canvas_id:
                return c
        raise KeyError(f"no canvas {canvas_id!r}")

    def canvas_named(self, name: str) -> Canvas:
        for c in self.canvases:
            if c.name == name:
                return c
        raise KeyError(f"no canvas named {name!r}")

    @property
    def current_canvas(self) -> Canvas | None:
        for c in self.canvases:
            if c.id == self.current:
                return c
        return self.canvases[0] if self.canvases else None

    def find_widget(self, widget_id: str) -> tuple[Canvas, WidgetInstance]:
        for c in self.canvases:
            for w in c.widgets:
                if w.id == widget_id:
                    return c, w
        raise KeyError(f"no widget {widget_id!r}")
