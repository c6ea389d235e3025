"""The area one canvas's widgets live on: hosts frames, draws the grid in edit mode, accepts drops.

A :class:`CanvasSurface` is as large as its widgets need (plus a margin), never smaller than the view;
it sits in a :class:`CanvasScroll`, so a small window or an open side panel shows scrollbars instead of
squeezing the widgets. A widget's geometry is the layout's, never the window's. Dragging the background
scrolls it, with a finger (QScroller) and with the mouse alike.
"""

from __future__ import annotations

from collections.abc import Iterable

from qtpy import QtCore, QtGui, QtWidgets

from rcon_core.app.geometry import GRID, MARGIN, snap, snap_up
from rcon_core.app.theme import colour as theme_colour
from rcon_core.app.widget_frame import WidgetFrame

#: mime type of a widget draft dragged from the settings preview onto a canvas
DRAFT_MIME = "application/x-rcon-widget-draft"


#: the empty canvas's hint, by what is on screen: it never points at a panel that is hidden, it says
#: what to tap instead. "side": the side panel (topics, services, widgets) is shown; "hidden": it is not;
#: "adding": the add panel is open on the right (the side panel gave it its room)
EMPTY_HINTS = {
    "side": "This canvas is empty.\nPick a topic, a service or a widget on the left to add one.",
    "hidden": "This canvas is empty.\nTap ▶ at the top left to show the topics, services and widgets,\n"
              "then pick one to add it.",
    "adding": "This canvas is empty.\nChoose in the panel on the right, then drag the preview here\n"
              "or tap Place.",
}


class _Pan:
    """A mouse drag on the canvas background: where it began and the scroll position then."""

    __slots__ = ("start", "h", "v", "moving")

    def __init__(self, start: QtCore.QPoint, h: int, v: int) -> None:
        self.start, self.h, self.v, self.moving = start, h, v, False


class CanvasSurface(QtWidgets.QWidget):
    """Frames are children positioned in canvas units (device-independent pixels)."""

    dropped = QtCore.Signal(QtCore.QPoint)  # a draft was dropped at this (snapped) point
    background_pressed = QtCore.Signal()

    def __init__(self, name: str, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.setObjectName("canvasSurface")
        self.setAttribute(QtCore.Qt.WidgetAttribute.WA_StyledBackground)
        self.setAcceptDrops(True)
        self.name = name
        self.editable = True
        self.frames: dict[str, WidgetFrame] = {}
        #: stacking order (bottom first): the canvas's widget order; the selected frame is raised on top
        self.order: list[str] = []
        #: the scroll area showing this surface (set by CanvasScroll)
        self.scroll_area: CanvasScroll | None = None
        self.placeholder = QtWidgets.QLabel(EMPTY_HINTS["side"], self)
        self.placeholder.setObjectName("emptyCanvas")
        self.placeholder.setProperty("role", "hint")
        self.placeholder.setAlignment(QtCore.Qt.AlignmentFlag.AlignCenter)
        self.placeholder.setAttribute(QtCore.Qt.WidgetAttribute.WA_TransparentForMouseEvents)
        self._pan: _Pan | None = None  #: a mouse drag on the background, scrolling the canvas

    def set_hint(self, where: str) -> None:
        """Word the empty-canvas hint for what is on screen (a key of :data:`EMPTY_HINTS`)."""
        self.placeholder.setText(EMPTY_HINTS[where])

    # frames -----------------------------------------------------------------------------------------
    def add_frame(self, frame: WidgetFrame, rect: QtCore.QRect) -> WidgetFrame:
        frame.setParent(self)
        self.frames[frame.instance_id] = frame
        if frame.instance_id not in self.order:
            self.order.append(frame.instance_id)
        frame.setFocusPolicy(QtCore.Qt.FocusPolicy.ClickFocus)  # focus lands on a placed widget
        frame.set_editable(self.editable)
        self._grow_to(rect)  # before placing: the frame is never clamped to a surface too small for it
        frame.place(rect)
        frame.installEventFilter(self)
        frame.selected_changed.connect(self._selection_changed)
        frame.show()
        self.placeholder.setVisible(False)
        self.restack()
        self.refit()
        return frame

    def remove_frame(self, instance_id: str) -> None:
        frame = self.frames.pop(instance_id, None)
        if instance_id in self.order:
            self.order.remove(instance_id)
        if frame is not None:
            frame.removeEventFilter(self)
            frame.hide()
            frame.setParent(None)
            frame.deleteLater()
        self.placeholder.setVisible(not self.frames)
        self.refit()

    def clear_frames(self) -> None:
        for iid in list(self.frames):
            self.remove_frame(iid)

    def set_order(self, ids: Iterable[str]) -> None:
        """Stack the frames in ``ids`` order (the canvas's widget order), the selected one on top."""
        self.order = [i for i in ids if i in self.frames] + [i for i in self.order if i not in set(ids)]
        self.restack()

    def restack(self) -> None:
        selected = None
        for iid in self.order:
            frame = self.frames.get(iid)
            if frame is not None:
                frame.raise_()
                if frame.selected:
                    selected = frame
        if selected is not None:
            selected.raise_()

    def _selection_changed(self, _iid: str, _selected: bool) -> None:
        self.restack()

    def set_editable(self, editable: bool) -> None:
        self.editable = editable
        for frame in self.frames.values():
            frame.set_editable(editable)
        self.update()

    # logical size -----------------------------------------------------------------------------------
    def content_rect(self) -> QtCore.QRect:
        """The union of every frame's geometry (empty when there are none)."""
        out = QtCore.QRect()
        for frame in self.frames.values():
            out = out.united(frame.geometry())
        return out

    def view_size(self) -> QtCore.QSize:
        return self.scroll_area.viewport().size() if self.scroll_area is not None else self.size()

    def visible_rect(self) -> QtCore.QRect:
        """The part of the surface the operator sees now (surface coordinates)."""
        if self.scroll_area is None:
            return self.rect()
        return QtCore.QRect(-self.pos(), self.scroll_area.viewport().size()).intersected(self.rect())

    def wanted_size(self) -> QtCore.QSize:
        content = self.content_rect()
        view = self.view_size()
        right = content.x() + content.width() + MARGIN if not content.isNull() else 0
        bottom = content.y() + content.height() + MARGIN if not content.isNull() else 0
        return QtCore.QSize(max(view.width(), right), max(view.height(), bottom))

    def refit(self) -> None:
        """Size the surface to cover every widget plus a margin, and at least the view."""
        wanted = self.wanted_size()
        if wanted != self.size():
            self.resize(wanted)

    def _grow_to(self, rect: QtCore.QRect) -> None:
        w = max(self.width(), rect.x() + rect.width() + MARGIN)
        h = max(self.height(), rect.y() + rect.height() + MARGIN)
        if (w, h) != (self.width(), self.height()):
            self.resize(w, h)

    def eventFilter(self, obj: QtCore.QObject, event: QtCore.QEvent) -> bool:
        # a frame dragged or resized past the edge grows the surface at once (it shrinks back on commit)
        if event.type() in (QtCore.QEvent.Type.Move, QtCore.QEvent.Type.Resize) and isinstance(obj, WidgetFrame):
            self._grow_to(obj.geometry())
        return super().eventFilter(obj, event)

    # placing ----------------------------------------------------------------------------------------
    def free_spot(self, size: QtCore.QSize, avoid_gap: int = GRID) -> QtCore.QPoint:
        """Where a new widget of ``size`` goes: the first grid point (top-left first) in the visible part of
        the canvas where it overlaps no widget (keeping ``avoid_gap`` clear around them), else on the
        grid below every widget (at the left of the visible part)."""
        taken = [f.geometry().adjusted(-avoid_gap + 1, -avoid_gap + 1, avoid_gap - 1, avoid_gap - 1)
                 for f in self.frames.values()]
        vis = self.visible_rect()
        left, top = max(GRID, snap_up(vis.left())), max(GRID, snap_up(vis.top()))
        right, bottom = vis.left() + vis.width(), vis.top() + vis.height()
        for y in range(top, bottom - size.height() + 1, GRID):
            for x in range(left, right - size.width() + 1, GRID):
                rect = QtCore.QRect(QtCore.QPoint(x, y), size)
                if not any(t.intersects(rect) for t in taken):
                    return QtCore.QPoint(x, y)
        content = self.content_rect()
        below = snap_up(content.y() + content.height()) + GRID if not content.isNull() else GRID
        return QtCore.QPoint(left, max(GRID, below))

    def reveal(self, rect: QtCore.QRect) -> None:
        """Scroll so ``rect`` (surface coordinates) is in view."""
        if self.scroll_area is not None:
            self._grow_to(rect)
            centre = rect.center()
            self.scroll_area.ensureVisible(centre.x(), centre.y(), rect.width() // 2 + GRID, rect.height() // 2 + GRID)

    # painting ---------------------------------------------------------------------------------------
    def paintEvent(self, event: QtGui.QPaintEvent) -> None:
        super().paintEvent(event)
        if not self.editable:
            return
        p = QtGui.QPainter(self)
        pen = QtGui.QPen(theme_colour("GRID"))
        pen.setWidth(2)
        p.setPen(pen)
        r = event.rect()
        for x in range(snap(r.left()) - GRID, r.right() + GRID, GRID):
            for y in range(snap(r.top()) - GRID, r.bottom() + GRID, GRID):
                p.drawPoint(x, y)

    def resizeEvent(self, event: QtGui.QResizeEvent) -> None:
        # the widgets stay where the layout has them: only the empty-canvas hint follows the view
        super().resizeEvent(event)
        self.placeholder.setGeometry(QtCore.QRect(QtCore.QPoint(0, 0), self.view_size()))

    # panning: dragging the background with the mouse scrolls the canvas, as a finger does (QScroller)
    def mousePressEvent(self, event: QtGui.QMouseEvent) -> None:
        self.background_pressed.emit()
        if event.button() == QtCore.Qt.MouseButton.LeftButton and self.scroll_area is not None:
            bars = self.scroll_area.horizontalScrollBar(), self.scroll_area.verticalScrollBar()
            self._pan = _Pan(event.globalPosition().toPoint(), bars[0].value(), bars[1].value())
        super().mousePressEvent(event)

    def mouseMoveEvent(self, event: QtGui.QMouseEvent) -> None:
        pan = self._pan
        if pan is None or self.scroll_area is None or not event.buttons() & QtCore.Qt.MouseButton.LeftButton:
            super().mouseMoveEvent(event)
            return
        moved = event.globalPosition().toPoint() - pan.start
        if not pan.moving and moved.manhattanLength() < QtWidgets.QApplication.startDragDistance():
            return  # a tap, not a pan (yet)
        if not pan.moving:
            pan.moving = True
            self.setCursor(QtCore.Qt.CursorShape.ClosedHandCursor)
        self.scroll_area.horizontalScrollBar().setValue(pan.h - moved.x())
        self.scroll_area.verticalScrollBar().setValue(pan.v - moved.y())

    def mouseReleaseEvent(self, event: QtGui.QMouseEvent) -> None:
        if self._pan is not None and self._pan.moving:
            self.unsetCursor()
        self._pan = None
        super().mouseReleaseEvent(event)

    # drops ------------------------------------------------------------------------------------------
    def dragEnterEvent(self, event: QtGui.QDragEnterEvent) -> None:
        if self.editable and event.mimeData().hasFormat(DRAFT_MIME):
            event.acceptProposedAction()

    def dragMoveEvent(self, event: QtGui.QDragMoveEvent) -> None:
        if self.editable and event.mimeData().hasFormat(DRAFT_MIME):
            event.acceptProposedAction()

    def dropEvent(self, event: QtGui.QDropEvent) -> None:
        if not (self.editable and event.mimeData().hasFormat(DRAFT_MIME)):
            return
        event.acceptProposedAction()
        pos = event.position().toPoint()  # surface coordinates: the scroll offset is already in them
        self.dropped.emit(QtCore.QPoint(max(0, snap(pos.x())), max(0, snap(pos.y()))))


class CanvasScroll(QtWidgets.QScrollArea):
    """Shows a :class:`CanvasSurface` with scrollbars when it is larger than the view.

    Touch: a finger on the canvas background scrolls it kinetically (QScroller); a finger on a widget
    never starts a scroll, so dragging a widget in edit mode moves it and a teleop pad or slider in
    operator mode keeps its touches.
    """

    def __init__(self, surface: CanvasSurface, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.setObjectName("canvasScroll")
        self.setFrameShape(QtWidgets.QFrame.Shape.NoFrame)
        self.setWidgetResizable(False)
        self.setAlignment(QtCore.Qt.AlignmentFlag.AlignLeft | QtCore.Qt.AlignmentFlag.AlignTop)
        self.surface = surface
        surface.scroll_area = self
        self.setWidget(surface)
        viewport = self.viewport()
        viewport.setAttribute(QtCore.Qt.WidgetAttribute.WA_AcceptTouchEvents)
        QtWidgets.QScroller.grabGesture(viewport, QtWidgets.QScroller.ScrollerGestureType.TouchGesture)

    def resizeEvent(self, event: QtGui.QResizeEvent) -> None:
        super().resizeEvent(event)
        self.surface.refit()

    def frame_at(self, viewport_pos: QtCore.QPoint) -> WidgetFrame | None:
        """The widget frame under a point of the viewport, if any."""
        child = self.surface.childAt(self.surface.mapFrom(self.viewport(), viewport_pos))
        while child is not None and not isinstance(child, WidgetFrame):
            child = child.parentWidget()
        return child

    def viewportEvent(self, event: QtCore.QEvent) -> bool:
        if event.type() == QtCore.QEvent.Type.ScrollPrepare:
            start = event.startPos().toPoint()  # type: ignore[attr-defined]
            if self.frame_at(start) is not None:
                event.ignore()  # a touch on a widget belongs to the widget, not to the scroller
                return True
        return super().viewportEvent(event)
