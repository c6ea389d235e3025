"""Keeps the canvas document, the canvas surfaces and the running widgets in step.

The workspace is a :class:`rcon_core.canvas.Document`: every edit goes through it (so it can be undone)
and is saved by an :class:`rcon_core.canvas.AutoSaver` through the :class:`WorkspaceStore`. The
controller listens to the document's changes and updates the surfaces (one per canvas) and the
:class:`LiveCanvas` that runs the current canvas's widget models on the bridge thread. Undo, redo and
edits made elsewhere therefore reach the screen and the robot the same way.
"""

from __future__ import annotations

import logging
import os
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

from qtpy import QtCore, QtWidgets

from rcon_core.app.canvas_surface import CanvasScroll, CanvasSurface
from rcon_core.app.draft import Draft
from rcon_core.app.geometry import GRID, on_grid
from rcon_core.app.link import OFFLINE
from rcon_core.app.live import LiveCanvas
from rcon_core.app.widget_frame import frame_min_size
from rcon_core.app.widget_host import WidgetHost
from rcon_core.canvas import (
    AutoSaver,
    Canvas,
    CanvasLocked,
    Change,
    ChangeKind,
    Document,
    EditError,
    Geometry,
    WidgetInstance,
    Workspace,
    WorkspaceStore,
    export_canvas,
    import_canvas,
)

log = logging.getLogger(__name__)

#: what an exported canvas file is called: ``Docking.rcon-canvas.json``
CANVAS_SUFFIX = ".rcon-canvas.json"


def _runs_differently(a: WidgetInstance, b: WidgetInstance) -> bool:
    """Whether the model must be rebuilt (title and geometry are the frame's business)."""
    return (a.kind, a.binding, a.settings) != (b.kind, b.binding, b.settings)


class CanvasController(QtCore.QObject):
    """Owns the document's surfaces; edits by index (the tab bar) or by widget id."""

    canvases_changed = QtCore.Signal()  # names/order changed
    current_changed = QtCore.Signal(int)
    lock_changed = QtCore.Signal(bool)
    save_failed = QtCore.Signal(str)

    def __init__(self, doc: Document, store: WorkspaceStore, host: WidgetHost, live: LiveCanvas,
                 stack: QtWidgets.QStackedWidget) -> None:
        super().__init__(stack)
        self.doc = doc
        self.store = store
        self.host = host
        self.live = live
        self.stack = stack
        self.surfaces: dict[str, CanvasSurface] = {}
        self.hint = "side"  #: what the empty-canvas hint points at (canvas_surface.EMPTY_HINTS)
        self._known: dict[str, WidgetInstance] = {}  # what the runtime was last given, per widget
        self.on_drop: Callable[[CanvasSurface, QtCore.QPoint], Any] | None = None  # set by the window
        self.on_configure: Callable[[str], Any] | None = None
        #: the bridge client the widgets run on (the window sets it; offline until connected)
        self.client: Any = OFFLINE
        #: why the robot connection is view-only (the window sets it), None when it may be commanded
        self.view_only: str | None = None
        self.saver = AutoSaver(doc, store, on_error=lambda exc: self.save_failed.emit(str(exc)))
        self._remove_listener = doc.add_listener(self._changed)
        self._rebuild_surfaces()

    # ------------------------------------------------------------------------------------- reading
    @property
    def workspace(self) -> Workspace:
        return self.doc.workspace

    @property
    def canvas(self) -> Canvas:
        return self.doc.current

    @property
    def index(self) -> int:
        return self.workspace.canvases.index(self.canvas)

    @property
    def surface(self) -> CanvasSurface:
        return self.surfaces[self.canvas.id]

    def _canvas_at(self, index: int) -> Canvas:
        canvases = self.workspace.canvases
        if not 0 <= index < len(canvases):
            raise EditError(f"there is no canvas number {index + 1}")
        return canvases[index]

    # ------------------------------------------------------------------------------------ surfaces
    def _rebuild_surfaces(self) -> None:
        for canvas_id in list(self.surfaces):
            self._drop_surface(canvas_id)
        for canvas in self.workspace.canvases:
            self._make_surface(canvas)
        self._show_current()
        self.canvases_changed.emit()

    def _make_surface(self, canvas: Canvas) -> CanvasSurface:
        surface = CanvasSurface(canvas.name)
        surface.set_hint(self.hint)
        scroll = CanvasScroll(surface)
        self.stack.insertWidget(self.workspace.canvases.index(canvas), scroll)
        scroll.resize(self.stack.size())
        surface.refit()
        self.surfaces[canvas.id] = surface
        for widget in canvas.widgets:
            self._add_frame(surface, widget)
        surface.set_editable(not canvas.locked)
        surface.dropped.connect(lambda pt, s=surface: self.on_drop and self.on_drop(s, pt))
        surface.background_pressed.connect(lambda s=surface: self._deselect(s))
        return surface

    def set_hint(self, where: str) -> None:
        """The window's side or add panel was shown or hidden: every empty canvas's hint follows."""
        self.hint = where
        for surface in self.surfaces.values():
            surface.set_hint(where)

    def _drop_surface(self, canvas_id: str) -> None:
        surface = self.surfaces.pop(canvas_id)
        for widget_id in list(surface.frames):
            self.host.discard(widget_id)
            self._known.pop(widget_id, None)
        surface.clear_frames()
        scroll = surface.scroll_area or surface
        self.stack.removeWidget(scroll)
        scroll.deleteLater()

    def _add_frame(self, surface: CanvasSurface, widget: WidgetInstance) -> None:
        frame = self.host.build_frame(widget)
        frame.geometry_committed.connect(self._geometry_committed)
        frame.action_requested.connect(self._frame_action)
        g = widget.geometry
        surface.add_frame(frame, QtCore.QRect(round(g.x), round(g.y), round(g.w), round(g.h)))
        self._known[widget.id] = _copy(widget)

    def _show_current(self) -> None:
        canvas = self.canvas
        surface = self.surfaces[canvas.id]
        self.stack.setCurrentWidget(surface.scroll_area or surface)
        self._apply_lock()
        self.current_changed.emit(self.index)

    def _apply_lock(self) -> None:
        locked = self.canvas.locked
        self.surface.set_editable(not locked)
        self.lock_changed.emit(locked)

    # ------------------------------------------------------------------------- document listener
    def _changed(self, change: Change) -> None:
        what, cid, wid = change.what, change.canvas_id or "", change.widget_id or ""
        current = self.canvas.id
        if what is ChangeKind.WORKSPACE_REPLACED:
            self._rebuild_surfaces()
            self.run_current()
        elif what is ChangeKind.CANVAS_ADDED and cid not in self.surfaces:
            self._make_surface(self.workspace.canvas(cid))
            self.canvases_changed.emit()
        elif what is ChangeKind.CANVAS_REMOVED and cid in self.surfaces:
            self._drop_surface(cid)
            self.canvases_changed.emit()
        elif what is ChangeKind.CANVAS_RENAMED and cid in self.surfaces:
            self.surfaces[cid].name = self.workspace.canvas(cid).name
            self.canvases_changed.emit()
        elif what is ChangeKind.CANVAS_SWITCHED:
            self._show_current()
            self.live.switch(self.canvas)
        elif what is ChangeKind.CANVAS_VIEW_ONLY and cid == current:
            self.run_current()  # every widget gets a port that refuses (or no longer refuses)
            self.lock_changed.emit(self.canvas.locked)
        elif what is ChangeKind.CANVAS_LOCKED and cid in self.surfaces:
            self.surfaces[cid].set_editable(not self.workspace.canvas(cid).locked)
            if cid == current:
                self._apply_lock()
        elif what is ChangeKind.WIDGET_ADDED and cid in self.surfaces:
            widget = self.workspace.canvas(cid).widget(wid)
            self._add_frame(self.surfaces[cid], widget)
            self.surfaces[cid].set_order(w.id for w in self.workspace.canvas(cid).widgets)
            if cid == current:
                self.live.add(widget)
        elif what is ChangeKind.WIDGET_REMOVED and cid in self.surfaces:
            self.surfaces[cid].remove_frame(wid)
            self.host.discard(wid)
            self._known.pop(wid, None)
            if cid == current:
                self.live.remove(wid)
        elif what is ChangeKind.WIDGET_CHANGED and cid in self.surfaces:
            self._widget_changed(cid, self.workspace.canvas(cid).widget(wid))
        elif what is ChangeKind.PLUGIN_SETTINGS_CHANGED:
            self.run_current()

    def _widget_changed(self, canvas_id: str, widget: WidgetInstance) -> None:
        frame = self.surfaces[canvas_id].frames.get(widget.id)
        if frame is not None:
            g = widget.geometry
            frame.place(QtCore.QRect(round(g.x), round(g.y), round(g.w), round(g.h)))
            self.surfaces[canvas_id].refit()
        self.host.update_widget(widget)
        before = self._known.get(widget.id)
        self._known[widget.id] = _copy(widget)
        if canvas_id == self.canvas.id and (before is None or _runs_differently(before, widget)):
            self.live.restart(widget)

    def run_current(self) -> None:
        """(Re)start the current canvas's widgets on :attr:`client` (set by the window)."""
        self.live.start(self.client, self.canvas, self.workspace.plugin_settings, view_only=self.view_only)

    # -------------------------------------------------------------------------------- navigation
    def switch(self, index: int) -> None:
        """Show canvas ``index``: the old canvas's widgets stop, the new one's start."""
        if 0 <= index < len(self.workspace.canvases):
            self.doc.switch_canvas(self.workspace.canvases[index].id)

    # ------------------------------------------------------------------------------- canvas edits
    def add_canvas(self, name: str = "Canvas") -> int:
        canvas = self.doc.create_canvas(name.strip() or "Canvas")
        self.doc.switch_canvas(canvas.id)
        return self.index

    def rename_canvas(self, index: int, name: str) -> None:
        self.doc.rename_canvas(self._canvas_at(index).id, name)

    def duplicate_canvas(self, index: int) -> int:
        dup = self.doc.duplicate_canvas(self._canvas_at(index).id)
        self.doc.switch_canvas(dup.id)
        return self.index

    def delete_canvas(self, index: int) -> None:
        """Delete canvas ``index`` (not the last); when it is shown, the one before it is shown instead."""
        canvas = self._canvas_at(index)
        if len(self.workspace.canvases) > 1 and canvas is self.canvas:
            self.switch(max(0, index - 1) if index > 0 else 1)
        self.doc.delete_canvas(canvas.id)

    # ---------------------------------------------------------------------- sharing one canvas
    def export_canvas(self, index: int, path: str | os.PathLike[str]) -> Path:
        """Write canvas ``index`` to its own file, atomically (read-only: allowed in operator mode).
        Raises OSError when the file cannot be written; returns the path written."""
        export_canvas(self._canvas_at(index), path)
        return Path(path)

    def import_canvas(self, path: str | os.PathLike[str]) -> Canvas:
        """Add the canvas of a file written by :meth:`export_canvas` as one undo step, and show it.

        Its name is made unique ("Docking (2)"), widget ids already used here get fresh ones, geometry is
        put on the grid (never at negative coordinates), and it opens in Edit mode (↶ takes it back at once). Widgets whose plugin is not
        installed come in as placeholders with their settings kept. Raises
        :class:`~rcon_core.canvas.WorkspaceFileError` (corrupt, newer or not a canvas file) or
        :class:`EditError` (the current canvas is locked, a bad name); then nothing changed.
        """
        if self.canvas.locked:
            raise CanvasLocked("switch to Edit mode to import a canvas")
        canvas = import_canvas(path)
        canvas.name = canvas.name.strip() or name_from_file(path)
        canvas.locked = False
        for widget in canvas.widgets:
            g = widget.geometry
            # on the grid and never left of or above the canvas; the size is kept as the sender made it
            # (a minimum frame size depends on this screen's touch metrics, not on the layout)
            rect = on_grid(QtCore.QRect(round(g.x), round(g.y), round(g.w), round(g.h)), QtCore.QSize(GRID, GRID))
            widget.geometry = Geometry(rect.x(), rect.y(), rect.width(), rect.height())
        added = self.doc.add_canvas(canvas)
        self.doc.switch_canvas(added.id)
        return added

    def set_locked(self, locked: bool) -> None:
        """Operator mode on the current canvas (saved with it; a mode switch, not an undo step)."""
        self.doc.set_locked(self.canvas.id, locked, undoable=False)

    def undo(self) -> bool:
        """Undo the last layout edit; refused in operator mode (nothing moves on a locked canvas)."""
        return False if self.canvas.locked else self.doc.undo()

    def redo(self) -> bool:
        return False if self.canvas.locked else self.doc.redo()

    # ------------------------------------------------------------------------------- widget edits
    def add_draft(self, draft: Draft, at: QtCore.QPoint | None = None) -> WidgetInstance:
        """Put a valid draft on the current canvas at ``at`` (surface coordinates; default: a free spot in
        view, else below the other widgets), on the grid; the canvas scrolls to show it."""
        problems = draft.problems()
        if problems:
            raise ValueError("the widget is not configured: " + "; ".join(problems))
        w, h = draft.size()
        surface = self.surface
        size = on_grid(QtCore.QRect(0, 0, w, h), frame_min_size()).size()
        pos = at if at is not None else surface.free_spot(size)
        rect = on_grid(QtCore.QRect(pos, size), frame_min_size())
        widget = self.doc.add_widget(
            self.canvas.id, draft.spec.kind, draft.binding,
            Geometry(rect.x(), rect.y(), rect.width(), rect.height()), draft.settings_dict(),
            draft.title or draft.spec.title,
        )
        self._show_placed(widget.id)
        return widget

    def _show_placed(self, widget_id: str) -> None:
        """Scroll a new widget into view and give it the keyboard focus (not whatever field Qt picks)."""
        frame = self.surface.frames.get(widget_id)
        if frame is not None:
            self.surface.reveal(frame.geometry())
            frame.setFocus(QtCore.Qt.FocusReason.OtherFocusReason)

    def _geometry_committed(self, widget_id: str, rect: QtCore.QRect) -> None:
        rect = on_grid(rect, frame_min_size())  # what is saved is always on the grid
        geometry = Geometry(rect.x(), rect.y(), rect.width(), rect.height())
        try:
            self.doc.set_geometry(widget_id, geometry)
        except EditError as exc:  # e.g. locked meanwhile: the frame goes back where the document has it
            log.info("geometry not kept: %s", exc)
            canvas, widget = self.workspace.find_widget(widget_id)
            self._widget_changed(canvas.id, widget)

    def _frame_action(self, widget_id: str, action: str) -> None:
        if action == "delete":
            self.delete_instance(widget_id)
        elif action == "duplicate":
            self.duplicate_instance(widget_id)
        elif action == "configure" and self.on_configure is not None:
            self.on_configure(widget_id)

    def delete_instance(self, widget_id: str) -> bool:
        """Remove a widget; False (and nothing happens) on a locked canvas."""
        try:
            self.doc.remove_widget(widget_id)
        except CanvasLocked:
            return False
        return True

    def duplicate_instance(self, widget_id: str) -> WidgetInstance | None:
        try:
            _canvas, src = self.workspace.find_widget(widget_id)
        except KeyError:
            return None
        g = src.geometry
        size = on_grid(QtCore.QRect(0, 0, round(g.w), round(g.h)), frame_min_size()).size()
        rect = QtCore.QRect(self.surface.free_spot(size), size)  # a free spot, never over the original
        try:
            copy = self.doc.add_widget(self.canvas.id, src.kind, src.binding,
                                       Geometry(rect.x(), rect.y(), rect.width(), rect.height()),
                                       _copy(src).settings, src.title)
        except CanvasLocked:
            return None
        self._show_placed(copy.id)
        return copy

    def update_instance(self, widget_id: str, *, settings: dict | None = None, title: str | None = None) -> None:
        self.doc.reconfigure_widget(widget_id, settings=settings, title=title)

    def _deselect(self, surface: CanvasSurface) -> None:
        for frame in surface.frames.values():
            frame.set_selected(False)

    # ------------------------------------------------------------------------------------ closing
    def shutdown(self) -> None:
        """Stop the widgets and save (the store refuses to overwrite a file it could not read)."""
        self.live.stop()
        self.saver.flush()
        self.saver.close()
        self._remove_listener()


def file_name_for(canvas_name: str) -> str:
    """The default file name of an exported canvas: its name made safe for any file system, plus
    :data:`CANVAS_SUFFIX` (``"Dock/Undock"`` -> ``"Dock_Undock.rcon-canvas.json"``)."""
    safe = re.sub(r'[\x00-\x1f<>:"/\\|?*]+', "_", canvas_name).strip(" ._") or "canvas"
    return safe[:80] + CANVAS_SUFFIX


def name_from_file(path: str | os.PathLike[str]) -> str:
    """A canvas name from a file name (for a file whose canvas has none): ``Docking.rcon-canvas.json``
    -> ``Docking``."""
    name = Path(path).name
    for suffix in (CANVAS_SUFFIX, ".json"):
        if name.lower().endswith(suffix):
            name = name[: -len(suffix)]
            break
    return name.strip()[:100] or "Imported canvas"


def _copy(widget: WidgetInstance) -> WidgetInstance:
    import copy

    return copy.deepcopy(widget)
