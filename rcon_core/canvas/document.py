"""Editing a workspace: operations as undoable commands, and change notifications (plain callbacks).

::

    doc = Document(workspace)
    doc.add_listener(lambda change: print(change.what, change.canvas_id, change.widget_id))
    c = doc.create_canvas("Deck")
    w = doc.add_widget(c.id, "std.slider", Binding("/speed", "std_msgs/Float64", "publish", "data"))
    doc.move_widget(w.id, 40, 80)
    doc.undo(); doc.redo()

Every edit is a :class:`Command` pushed on the undo stack (a new edit clears the redo stack).
Switching canvases is navigation, not an edit: it notifies but is not undone. Edits to the widgets of a
locked canvas raise :class:`CanvasLocked`. Listeners are called synchronously after each change, in the
caller's thread; a listener that raises is reported on stderr and does not stop the others.
"""

from __future__ import annotations

import copy
import enum
import sys
import traceback
from collections.abc import Callable
from typing import Any

import attrs

from rcon_core.plugins.model import Binding

from .retarget import rename_settings
from .robots import Robot, UnknownRobot, default_robot, resolve_robot
from .workspace import Canvas, Geometry, WidgetInstance, Workspace, new_id

__all__ = ["Document", "Change", "ChangeKind", "Command", "CanvasLocked", "EditError"]


class EditError(ValueError):
    """An edit that cannot be done (unknown id, empty name, last canvas...)."""


class CanvasLocked(EditError):
    """The canvas is locked; unlock it first."""


class ChangeKind(enum.StrEnum):
    """What kind of change a :class:`Change` is (a ``str``: ``change.what == "robots-changed"`` still holds)."""

    CANVAS_ADDED = "canvas-added"
    CANVAS_REMOVED = "canvas-removed"
    CANVAS_RENAMED = "canvas-renamed"
    CANVAS_LOCKED = "canvas-locked"
    CANVAS_VIEW_ONLY = "canvas-view-only"
    CANVAS_SWITCHED = "canvas-switched"
    WIDGET_ADDED = "widget-added"
    WIDGET_REMOVED = "widget-removed"
    WIDGET_CHANGED = "widget-changed"
    WORKSPACE_REPLACED = "workspace-replaced"
    PLUGIN_SETTINGS_CHANGED = "plugin-settings-changed"
    ROBOTS_CHANGED = "robots-changed"


@attrs.frozen
class Change:
    """What changed: ``what`` (a :class:`ChangeKind`; its value is taken too) and which canvas and widget."""

    what: ChangeKind = attrs.field(converter=ChangeKind)
    canvas_id: str | None = None
    widget_id: str | None = None


@attrs.define
class Command:
    """One undoable edit: ``do`` and ``undo`` return the changes they made."""

    label: str
    do: Callable[[], list[Change]]
    undo: Callable[[], list[Change]]


class Document:
    """A workspace plus its undo/redo history and listeners."""

    def __init__(self, workspace: Workspace | None = None, *, max_undo: int = 200) -> None:
        self.workspace = workspace if workspace is not None else Workspace.new()
        if not self.workspace.canvases:
            c = Canvas(new_id("c"), "Main")
            self.workspace.canvases.append(c)
        if not self.workspace.robots:  # every binding needs a robot to talk to (the first, by default)
            self.workspace.robots.append(default_robot())
        if self.workspace.current_canvas is not None:
            self.workspace.current = self.workspace.current_canvas.id
        self._undo: list[Command] = []
        self._redo: list[Command] = []
        self._listeners: list[Callable[[Change], Any]] = []
        self.max_undo = max_undo

    # -- listeners -----------------------------------------------------------------------------------
    def add_listener(self, fn: Callable[[Change], Any]) -> Callable[[], None]:
        """Call ``fn(change)`` after every change; returns a function that removes the listener."""
        self._listeners.append(fn)
        return lambda: self._listeners.remove(fn) if fn in self._listeners else None

    def _notify(self, changes: list[Change]) -> None:
        for change in changes:
            for fn in list(self._listeners):
                try:
                    fn(change)
                except Exception:
                    print(f"rcon: a workspace listener failed on {change.what}:", file=sys.stderr)
                    traceback.print_exc()

    # -- undo/redo -----------------------------------------------------------------------------------
    def _run(self, cmd: Command) -> None:
        changes = cmd.do()
        self._undo.append(cmd)
        del self._undo[: -self.max_undo]
        self._redo.clear()
        self._notify(changes)

    @property
    def can_undo(self) -> bool:
        return bool(self._undo)

    @property
    def can_redo(self) -> bool:
        return bool(self._redo)

    @property
    def undo_label(self) -> str | None:
        return self._undo[-1].label if self._undo else None

    @property
    def redo_label(self) -> str | None:
        return self._redo[-1].label if self._redo else None

    def undo(self) -> bool:
        """Undo the last edit; False when there is none."""
        if not self._undo:
            return False
        cmd = self._undo.pop()
        changes = cmd.undo()
        self._redo.append(cmd)
        self._notify(changes)
        return True

    def redo(self) -> bool:
        if not self._redo:
            return False
        cmd = self._redo.pop()
        changes = cmd.do()
        self._undo.append(cmd)
        self._notify(changes)
        return True

    def replace_workspace(self, workspace: Workspace) -> None:
        """Load another workspace (clears the history)."""
        self.workspace = workspace
        self._undo.clear()
        self._redo.clear()
        self._notify([Change(ChangeKind.WORKSPACE_REPLACED)])

    # -- canvases ------------------------------------------------------------------------------------
    @property
    def current(self) -> Canvas:
        c = self.workspace.current_canvas
        assert c is not None  # a document always has a canvas
        return c

    def _canvas(self, canvas_id: str) -> Canvas:
        try:
            return self.workspace.canvas(canvas_id)
        except KeyError as exc:
            raise EditError(str(exc.args[0])) from None

    def _unique_name(self, name: str) -> str:
        taken = {c.name for c in self.workspace.canvases}
        if name not in taken:
            return name
        n = 2
        while f"{name} ({n})" in taken:
            n += 1
        return f"{name} ({n})"

    def _insert_canvas(self, canvas: Canvas, index: int | None = None) -> Command:
        ws = self.workspace
        pos = len(ws.canvases) if index is None else index

        def do() -> list[Change]:
            ws.canvases.insert(pos, canvas)
            return [Change(ChangeKind.CANVAS_ADDED, canvas.id)]

        def undo() -> list[Change]:
            ws.canvases.remove(canvas)
            changes = [Change(ChangeKind.CANVAS_REMOVED, canvas.id)]
            if ws.current == canvas.id:
                ws.current = ws.canvases[min(pos, len(ws.canvases) - 1)].id
                changes.append(Change(ChangeKind.CANVAS_SWITCHED, ws.current))
            return changes

        return Command(f"add canvas {canvas.name}", do, undo)

    def create_canvas(self, name: str) -> Canvas:
        """A new empty canvas at the end (its name made unique). Does not switch to it."""
        name = _clean_name(name)
        canvas = Canvas(new_id("c"), self._unique_name(name))
        self._run(self._insert_canvas(canvas))
        return canvas

    def add_canvas(self, canvas: Canvas) -> Canvas:
        """Add an existing canvas object (import): a copy, with fresh ids where they collide (or are empty)
        and its name made unique ("Docking (2)"). Does not switch to it. Raises :class:`EditError` for a
        blank or over-long name."""
        name = _clean_name(canvas.name)
        taken_c = {c.id for c in self.workspace.canvases}
        taken_w = {w.id for c in self.workspace.canvases for w in c.widgets}
        canvas = copy.deepcopy(canvas)
        if not canvas.id or canvas.id in taken_c:
            canvas.id = new_id("c")
        for w in canvas.widgets:
            if not w.id or w.id in taken_w:
                w.id = new_id("w")
            taken_w.add(w.id)
        canvas.name = self._unique_name(name)
        self._run(self._insert_canvas(canvas))
        return canvas

    def rename_canvas(self, canvas_id: str, name: str) -> None:
        canvas = self._canvas(canvas_id)
        name = _clean_name(name)
        if name != canvas.name and any(c.name == name for c in self.workspace.canvases):
            raise EditError(f"a canvas named {name!r} already exists")
        old = canvas.name

        def set_to(value: str) -> Callable[[], list[Change]]:
            def fn() -> list[Change]:
                canvas.name = value
                return [Change(ChangeKind.CANVAS_RENAMED, canvas.id)]

            return fn

        self._run(Command(f"rename canvas {old} to {name}", set_to(name), set_to(old)))

    def delete_canvas(self, canvas_id: str) -> None:
        """Delete a canvas (not the last one). If it was current, the neighbour becomes current."""
        canvas = self._canvas(canvas_id)
        ws = self.workspace
        if len(ws.canvases) == 1:
            raise EditError("cannot delete the last canvas")
        pos = ws.canvases.index(canvas)
        was_current = ws.current == canvas.id

        def do() -> list[Change]:
            ws.canvases.remove(canvas)
            changes = [Change(ChangeKind.CANVAS_REMOVED, canvas.id)]
            if ws.current == canvas.id:
                ws.current = ws.canvases[min(pos, len(ws.canvases) - 1)].id
                changes.append(Change(ChangeKind.CANVAS_SWITCHED, ws.current))
            return changes

        def undo() -> list[Change]:
            ws.canvases.insert(pos, canvas)
            changes = [Change(ChangeKind.CANVAS_ADDED, canvas.id)]
            if was_current:
                ws.current = canvas.id
                changes.append(Change(ChangeKind.CANVAS_SWITCHED, canvas.id))
            return changes

        self._run(Command(f"delete canvas {canvas.name}", do, undo))

    def duplicate_canvas(self, canvas_id: str, name: str | None = None) -> Canvas:
        """A deep copy with fresh canvas and widget ids, placed right after the original."""
        src = self._canvas(canvas_id)
        dup = copy.deepcopy(src)
        dup.id = new_id("c")
        dup.name = self._unique_name(_clean_name(name) if name else f"{src.name} copy")
        for w in dup.widgets:
            w.id = new_id("w")
        self._run(self._insert_canvas(dup, self.workspace.canvases.index(src) + 1))
        return dup

    def switch_canvas(self, canvas_id: str) -> Canvas:
        """Make a canvas current (navigation: notifies, not undoable)."""
        canvas = self._canvas(canvas_id)
        if self.workspace.current != canvas.id:
            self.workspace.current = canvas.id
            self._notify([Change(ChangeKind.CANVAS_SWITCHED, canvas.id)])
        return canvas

    def set_locked(self, canvas_id: str, locked: bool, *, undoable: bool = True) -> None:
        """Lock or unlock a canvas. ``undoable=False`` treats it as a mode switch (an operator toggling
        operator mode): it notifies and is saved like any change, but is not put on the undo stack, so
        undo keeps meaning "undo my last layout edit"."""
        canvas = self._canvas(canvas_id)
        if canvas.locked == locked:
            return
        old = canvas.locked
        if not undoable:
            canvas.locked = locked
            self._notify([Change(ChangeKind.CANVAS_LOCKED, canvas.id)])
            return

        def set_to(value: bool) -> Callable[[], list[Change]]:
            def fn() -> list[Change]:
                canvas.locked = value
                return [Change(ChangeKind.CANVAS_LOCKED, canvas.id)]

            return fn

        self._run(Command("lock canvas" if locked else "unlock canvas", set_to(locked), set_to(old)))

    def set_view_only(self, canvas_id: str, view_only: bool) -> None:
        """Mark a canvas view-only (its widgets never send anything) or not. A setting of the canvas,
        saved with it, not an undo step (like the operator-mode switch); allowed on a locked canvas
        (making it view-only is always safe; the app asks for the operator PIN to undo it)."""
        canvas = self._canvas(canvas_id)
        if canvas.view_only != view_only:
            canvas.view_only = view_only
            self._notify([Change(ChangeKind.CANVAS_VIEW_ONLY, canvas.id)])

    def set_plugin_settings(self, kind: str, settings: dict[str, Any]) -> None:
        """Replace the shared settings of one widget kind."""
        ps = self.workspace.plugin_settings
        had, old = kind in ps, copy.deepcopy(ps.get(kind))
        new = copy.deepcopy(dict(settings))

        def do() -> list[Change]:
            ps[kind] = copy.deepcopy(new)
            return [Change(ChangeKind.PLUGIN_SETTINGS_CHANGED)]

        def undo() -> list[Change]:
            if had:
                ps[kind] = copy.deepcopy(old)  # type: ignore[arg-type]
            else:
                ps.pop(kind, None)
            return [Change(ChangeKind.PLUGIN_SETTINGS_CHANGED)]

        self._run(Command(f"settings of {kind}", do, undo))

    # -- robots --------------------------------------------------------------------------------------
    def set_robots(self, robots: list[Robot]) -> None:
        """Replace the workspace's robots (add, rename, another URL or settings, remove): one undo step.
        Raises :class:`EditError` for no robot, a robot without id, or two with the same id."""
        robots = copy.deepcopy(list(robots))
        if not robots:
            raise EditError("a workspace needs at least one robot")
        ids = [r.id for r in robots]
        if not all(ids) or len(set(ids)) != len(ids):
            raise EditError("every robot needs its own id")
        ws = self.workspace
        old = copy.deepcopy(ws.robots)

        def set_to(value: list[Robot]) -> Callable[[], list[Change]]:
            def fn() -> list[Change]:
                ws.robots = copy.deepcopy(value)
                return [Change(ChangeKind.ROBOTS_CHANGED)]

            return fn

        self._run(Command("edit robots", set_to(robots), set_to(old)))

    def duplicate_for_robot(self, canvas_id: str, robot_id: str, from_robot: str | None = None,
                            name: str | None = None, renames: dict[str, str] | None = None) -> Canvas:
        """Re-target a canvas: a copy (fresh ids, right after the original, named after the robot) whose
        widgets of ``from_robot`` -- every widget when None -- talk to ``robot_id``; ``renames`` maps the
        names they use to the target robot's (its namespace: ``rcon_core.canvas.retarget``), in their
        bindings and in the topic names of their settings. One undo step. Raises :class:`EditError` for a
        robot the workspace does not have."""
        try:
            target = resolve_robot(self.workspace.robots, robot_id)
            source = resolve_robot(self.workspace.robots, from_robot).id if from_robot is not None else None
        except UnknownRobot as exc:
            raise EditError(str(exc)) from None
        src = self._canvas(canvas_id)
        dup = copy.deepcopy(src)
        dup.id = new_id("c")
        dup.name = self._unique_name(_clean_name(name) if name else f"{src.name} · {target.label}")
        first = self.workspace.robots[0].id
        for w in dup.widgets:
            w.id = new_id("w")
            if source is None or (w.binding.robot or first) == source:
                # the first robot is written "" (the default), as a one-robot layout has it
                w.binding = attrs.evolve(w.binding, robot="" if target.id == first else target.id,
                                         name=(renames or {}).get(w.binding.name, w.binding.name))
                if renames:
                    w.settings = rename_settings(w.settings, renames)
        self._run(self._insert_canvas(dup, self.workspace.canvases.index(src) + 1))
        return dup

    # -- widgets -------------------------------------------------------------------------------------
    def _editable(self, canvas: Canvas) -> Canvas:
        if canvas.locked:
            raise CanvasLocked(f"canvas {canvas.name!r} is locked; unlock it to edit")
        return canvas

    def _widget(self, widget_id: str) -> tuple[Canvas, WidgetInstance]:
        try:
            canvas, w = self.workspace.find_widget(widget_id)
        except KeyError as exc:
            raise EditError(str(exc.args[0])) from None
        return self._editable(canvas), w

    def add_widget(
        self,
        canvas_id: str,
        kind: str,
        binding: Binding | None = None,
        geometry: Geometry | None = None,
        settings: dict[str, Any] | None = None,
        title: str = "",
    ) -> WidgetInstance:
        """Place a new widget on a canvas; returns it (with its fresh id)."""
        canvas = self._editable(self._canvas(canvas_id))
        if not kind:
            raise EditError("a widget needs a kind")
        w = WidgetInstance(
            new_id("w"), kind, binding or Binding(), geometry or Geometry(), dict(settings or {}), title
        )

        def do() -> list[Change]:
            canvas.widgets.append(w)
            return [Change(ChangeKind.WIDGET_ADDED, canvas.id, w.id)]

        def undo() -> list[Change]:
            canvas.widgets.remove(w)
            return [Change(ChangeKind.WIDGET_REMOVED, canvas.id, w.id)]

        self._run(Command(f"add {kind}", do, undo))
        return w

    def remove_widget(self, widget_id: str) -> None:
        canvas, w = self._widget(widget_id)
        pos = canvas.widgets.index(w)

        def do() -> list[Change]:
            canvas.widgets.remove(w)
            return [Change(ChangeKind.WIDGET_REMOVED, canvas.id, w.id)]

        def undo() -> list[Change]:
            canvas.widgets.insert(pos, w)
            return [Change(ChangeKind.WIDGET_ADDED, canvas.id, w.id)]

        self._run(Command(f"remove {w.kind}", do, undo))

    def _change_widget(self, widget_id: str, label: str, **new: Any) -> None:
        canvas, w = self._widget(widget_id)
        old = {k: copy.deepcopy(getattr(w, k)) for k in new}
        new = {k: copy.deepcopy(v) for k, v in new.items()}
        if old == new:
            return

        def set_to(values: dict[str, Any]) -> Callable[[], list[Change]]:
            def fn() -> list[Change]:
                for k, v in values.items():
                    setattr(w, k, copy.deepcopy(v))
                return [Change(ChangeKind.WIDGET_CHANGED, canvas.id, w.id)]

            return fn

        self._run(Command(label, set_to(new), set_to(old)))

    def move_widget(self, widget_id: str, x: float, y: float) -> None:
        _c, w = self._widget(widget_id)
        self._change_widget(widget_id, "move", geometry=attrs.evolve(w.geometry, x=float(x), y=float(y)))

    def resize_widget(self, widget_id: str, w: float, h: float) -> None:
        if w <= 0 or h <= 0:
            raise EditError(f"a widget's size must be positive, got {w} x {h}")
        _c, inst = self._widget(widget_id)
        self._change_widget(widget_id, "resize", geometry=attrs.evolve(inst.geometry, w=float(w), h=float(h)))

    def set_geometry(self, widget_id: str, geometry: Geometry) -> None:
        if geometry.w <= 0 or geometry.h <= 0:
            raise EditError(f"a widget's size must be positive, got {geometry.w} x {geometry.h}")
        self._change_widget(widget_id, "move/resize", geometry=geometry)

    def reconfigure_widget(
        self,
        widget_id: str,
        *,
        settings: dict[str, Any] | None = None,
        binding: Binding | None = None,
        title: str | None = None,
    ) -> None:
        """Replace a widget's settings dict, binding and/or title (one undo step)."""
        new: dict[str, Any] = {}
        if settings is not None:
            new["settings"] = dict(settings)
        if binding is not None:
            new["binding"] = binding
        if title is not None:
            new["title"] = title
        if new:
            self._change_widget(widget_id, "configure", **new)


def _clean_name(name: str) -> str:
    name = (name or "").strip()
    if not name:
        raise EditError("a canvas needs a name")
    if len(name) > 100:
        raise EditError("a canvas name is at most 100 characters")
    return name
