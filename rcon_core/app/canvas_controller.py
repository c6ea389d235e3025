"""Keeps the workspace document, the canvas surfaces and the running widgets in step.

Every edit goes through here: it changes the document, records an undo snapshot, saves the workspace,
and updates the surfaces.  Switching canvas stops the old canvas's widgets and starts the new one's.
"""

from __future__ import annotations

import copy
import logging
from pathlib import Path

from qtpy import QtCore, QtWidgets

from rcon_core.app.canvas_surface import CanvasSurface
from rcon_core.app.draft import Draft
from rcon_core.app.layout import CanvasDoc, Instance, WorkspaceDoc
from rcon_core.app.widget_host import WidgetHost

log = logging.getLogger(__name__)

UNDO_LIMIT = 100


class CanvasController(QtCore.QObject):
    """Owns the :class:`WorkspaceDoc` and one :class:`CanvasSurface` per canvas."""

    canvases_changed = QtCore.Signal()  # names/order changed
    current_changed = QtCore.Signal(int)
    lock_changed = QtCore.Signal(bool)

    def __init__(self, doc: WorkspaceDoc, host: WidgetHost, stack: QtWidgets.QStackedWidget,
                 save_path: Path | None) -> None:
        super().__init__(stack)
        self.doc = doc
        self.host = host
        self.stack = stack
        self.save_path = save_path
        self.surfaces: list[CanvasSurface] = []
        self._undo: list[dict] = []
        self._redo: list[dict] = []
        self.on_drop = None  # set by the window: fn(surface, point)
        self._rebuild_surfaces()

    # ------------------------------------------------------------------------------------ surfaces
    def _rebuild_surfaces(self) -> None:
        for surface in self.surfaces:
            for iid in list(surface.frames):
                self.host.discard(iid)
            surface.clear_frames()
            self.stack.removeWidget(surface)
            surface.deleteLater()
        self.surfaces = []
        for canvas in self.doc.canvases:
            self.surfaces.append(self._make_surface(canvas))
        self.stack.setCurrentWidget(self.surfaces[self.doc.current])
        self._apply_lock()
        self.host.start(self._ids(self.doc.canvas))
        self.canvases_changed.emit()
        self.current_changed.emit(self.doc.current)

    def _make_surface(self, canvas: CanvasDoc) -> CanvasSurface:
        surface = CanvasSurface(canvas.name)
        self.stack.addWidget(surface)
        surface.resize(self.stack.size())
        for inst in canvas.instances:
            self._add_frame(surface, inst)
        surface.dropped.connect(lambda pt, s=surface: self.on_drop and self.on_drop(s, pt))
        surface.background_pressed.connect(lambda s=surface: self._deselect(s))
        return surface

    def _add_frame(self, surface: CanvasSurface, inst: Instance) -> None:
        frame = self.host.build(inst)
        frame.geometry_committed.connect(self._geometry_committed)
        frame.action_requested.connect(self._frame_action)
        surface.add_frame(frame, QtCore.QRect(*inst.rect))

    @staticmethod
    def _ids(canvas: CanvasDoc) -> list[str]:
        return [i.id for i in canvas.instances]

    @property
    def surface(self) -> CanvasSurface:
        return self.surfaces[self.doc.current]

    @property
    def canvas(self) -> CanvasDoc:
        return self.doc.canvas

    # -------------------------------------------------------------------------------------- history
    def _snapshot(self) -> None:
        self._undo.append(copy.deepcopy(self.doc.to_dict()))
        del self._undo[:-UNDO_LIMIT]
        self._redo.clear()

    def _restore(self, data: dict) -> None:
        self.doc = WorkspaceDoc.from_dict(data)
        self._rebuild_surfaces()
        self.save()

    def undo(self) -> bool:
        if not self._undo:
            return False
        self._redo.append(self.doc.to_dict())
        self._restore(self._undo.pop())
        return True

    def redo(self) -> bool:
        if not self._redo:
            return False
        self._undo.append(self.doc.to_dict())
        self._restore(self._redo.pop())
        return True

    def save(self) -> None:
        if self.save_path is not None:
            try:
                self.doc.save(self.save_path)
            except OSError as exc:
                log.error("could not save the workspace to %s: %s", self.save_path, exc)

    # -------------------------------------------------------------------------------------- canvases
    def switch(self, index: int) -> None:
        """Show canvas ``index``: stop the old canvas's widgets, start the new one's."""
        if not 0 <= index < len(self.doc.canvases) or index == self.doc.current:
            return
        self.host.stop(self._ids(self.doc.canvas))
        self.doc.current = index
        self.stack.setCurrentWidget(self.surfaces[index])
        self.host.start(self._ids(self.doc.canvas))
        self._apply_lock()
        self.save()
        self.current_changed.emit(index)

    def add_canvas(self, name: str = "Canvas") -> int:
        self._snapshot()
        canvas = CanvasDoc(self.doc.unique_name(name.strip() or "Canvas"))
        self.doc.canvases.append(canvas)
        self.surfaces.append(self._make_surface(canvas))
        self.canvases_changed.emit()
        self.switch(len(self.doc.canvases) - 1)
        self.save()
        return self.doc.current

    def rename_canvas(self, index: int, name: str) -> None:
        name = name.strip()
        if not name:
            raise ValueError("a canvas needs a name")
        if any(c.name == name for i, c in enumerate(self.doc.canvases) if i != index):
            raise ValueError(f"there is already a canvas named {name!r}")
        self._snapshot()
        self.doc.canvases[index].name = name
        self.surfaces[index].name = name
        self.save()
        self.canvases_changed.emit()

    def duplicate_canvas(self, index: int) -> int:
        self._snapshot()
        src = self.doc.canvases[index]
        data = src.to_dict()
        for w in data["widgets"]:
            w["id"] = ""
        copy_doc = CanvasDoc.from_dict(data)
        copy_doc.name = self.doc.unique_name(f"{src.name} copy")
        self.doc.canvases.insert(index + 1, copy_doc)
        surface = self._make_surface(copy_doc)
        self.surfaces.insert(index + 1, surface)
        if self.doc.current > index:
            self.doc.current += 1
        self.canvases_changed.emit()
        self.switch(index + 1)
        self.save()
        return index + 1

    def delete_canvas(self, index: int) -> None:
        if len(self.doc.canvases) <= 1:
            raise ValueError("the last canvas cannot be deleted")
        self._snapshot()
        was_current = index == self.doc.current
        canvas = self.doc.canvases.pop(index)
        surface = self.surfaces.pop(index)
        for iid in self._ids(canvas):
            self.host.discard(iid)
        self.stack.removeWidget(surface)
        surface.deleteLater()
        if self.doc.current > index or was_current:  # a deleted current canvas: show the one before it
            self.doc.current = max(0, self.doc.current - 1)
        self.stack.setCurrentWidget(self.surfaces[self.doc.current])
        if was_current:
            self.host.start(self._ids(self.doc.canvas))
        self._apply_lock()
        self.save()
        self.canvases_changed.emit()
        self.current_changed.emit(self.doc.current)

    # -------------------------------------------------------------------------------------- lock
    def set_locked(self, locked: bool) -> None:
        if self.canvas.locked == locked:
            return
        self.canvas.locked = locked
        self._apply_lock()
        self.save()

    def _apply_lock(self) -> None:
        locked = self.canvas.locked
        self.surface.set_editable(not locked)
        self.lock_changed.emit(locked)

    # -------------------------------------------------------------------------------------- widgets
    def add_draft(self, draft: Draft, at: QtCore.QPoint | None = None) -> Instance:
        """Put a valid draft on the current canvas at ``at`` (default: a free spot)."""
        problems = draft.problems()
        if problems:
            raise ValueError("the widget is not configured: " + "; ".join(problems))
        if self.canvas.locked:
            raise ValueError(f"canvas {self.canvas.name!r} is locked (operator mode)")
        self._snapshot()
        w, h = (int(v) for v in draft.spec.default_size)
        surface = self.surface
        pos = at if at is not None else surface.free_spot(QtCore.QSize(w, h))
        inst = Instance(
            kind=draft.spec.kind, binding=draft.binding, settings=draft.settings_dict(),
            rect=(pos.x(), pos.y(), w, h), title=draft.title or draft.spec.title,
        )
        self.canvas.instances.append(inst)
        self._add_frame(surface, inst)
        frame = surface.frames[inst.id]
        frame.commit_geometry()  # snaps and keeps it on screen, records the final rect
        self.host.start([inst.id])
        self.save()
        return inst

    def _geometry_committed(self, instance_id: str, rect: QtCore.QRect) -> None:
        inst = self.canvas.find(instance_id)
        if inst is None:
            return
        new = (rect.x(), rect.y(), rect.width(), rect.height())
        if new != inst.rect:
            self._snapshot()
            inst.rect = new
            self.save()

    def _frame_action(self, instance_id: str, action: str) -> None:
        if action == "delete":
            self.delete_instance(instance_id)
        elif action == "duplicate":
            self.duplicate_instance(instance_id)
        elif action == "configure" and self.on_configure is not None:
            self.on_configure(instance_id)

    on_configure = None  # set by the window: fn(instance_id)

    def delete_instance(self, instance_id: str) -> None:
        if self.canvas.locked:
            return
        inst = self.canvas.find(instance_id)
        if inst is None:
            return
        self._snapshot()
        self.canvas.instances.remove(inst)
        self.host.discard(instance_id)
        self.surface.remove_frame(instance_id)
        self.save()

    def duplicate_instance(self, instance_id: str) -> Instance | None:
        if self.canvas.locked:
            return None
        src = self.canvas.find(instance_id)
        if src is None:
            return None
        self._snapshot()
        data = src.to_dict()
        data["id"] = ""
        x, y, w, h = src.rect
        data["rect"] = [x + 32, y + 32, w, h]
        inst = Instance.from_dict(data)
        self.canvas.instances.append(inst)
        self._add_frame(self.surface, inst)
        self.surface.frames[inst.id].commit_geometry()
        self.host.start([inst.id])
        self.save()
        return inst

    def update_instance(self, instance_id: str, *, settings: dict | None = None, title: str | None = None) -> None:
        inst = self.canvas.find(instance_id)
        if inst is None:
            return
        self._snapshot()
        if settings is not None:
            inst.settings = settings
        if title is not None:
            inst.title = title
            self.surface.frames[instance_id].set_title(title)
        self.host.rebuild(instance_id)
        self.save()

    def _deselect(self, surface: CanvasSurface) -> None:
        for frame in surface.frames.values():
            frame.set_selected(False)

    def shutdown(self) -> None:
        self.host.stop(list(self.host.hosted))
        self.save()
