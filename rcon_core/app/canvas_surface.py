"""The area one canvas's widgets live on: hosts frames, draws the grid in edit mode, accepts drops."""

from __future__ import annotations

from qtpy import QtCore, QtGui, QtWidgets

from rcon_core.app.geometry import GRID, snap
from rcon_core.app.widget_frame import WidgetFrame

#: mime type of a widget draft dragged from the settings preview onto a canvas
DRAFT_MIME = "application/x-rcon-widget-draft"


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
        self.placeholder = QtWidgets.QLabel(
            "This canvas is empty.\nPick a topic, a service or a widget on the left to add one.", self
        )
        self.placeholder.setObjectName("emptyCanvas")
        self.placeholder.setProperty("role", "hint")
        self.placeholder.setAlignment(QtCore.Qt.AlignmentFlag.AlignCenter)
        self.placeholder.setAttribute(QtCore.Qt.WidgetAttribute.WA_TransparentForMouseEvents)

    # frames -----------------------------------------------------------------------------------------
    def add_frame(self, frame: WidgetFrame, rect: QtCore.QRect) -> WidgetFrame:
        frame.setParent(self)
        self.frames[frame.instance_id] = frame
        frame.set_editable(self.editable)
        frame.place(rect, remember=True)
        frame.show()
        self.placeholder.setVisible(False)
        return frame

    def remove_frame(self, instance_id: str) -> None:
        frame = self.frames.pop(instance_id, None)
        if frame is not None:
            frame.hide()
            frame.setParent(None)
            frame.deleteLater()
        self.placeholder.setVisible(not self.frames)

    def clear_frames(self) -> None:
        for iid in list(self.frames):
            self.remove_frame(iid)

    def set_editable(self, editable: bool) -> None:
        self.editable = editable
        for frame in self.frames.values():
            frame.set_editable(editable)
        self.update()

    def free_spot(self, size: QtCore.QSize) -> QtCore.QPoint:
        """A grid point where a widget of ``size`` overlaps nothing (top-left first), else the origin."""
        step = GRID * 2
        for y in range(GRID, max(GRID + 1, self.height() - size.height()), step):
            for x in range(GRID, max(GRID + 1, self.width() - size.width()), step):
                rect = QtCore.QRect(QtCore.QPoint(x, y), size)
                if not any(f.geometry().intersects(rect) for f in self.frames.values()):
                    return QtCore.QPoint(x, y)
        return QtCore.QPoint(GRID, GRID)

    # painting ---------------------------------------------------------------------------------------
    def paintEvent(self, event: QtGui.QPaintEvent) -> None:
        super().paintEvent(event)
        if not self.editable:
            return
        p = QtGui.QPainter(self)
        pen = QtGui.QPen(QtGui.QColor("#b8b8b8"))
        pen.setWidth(2)
        p.setPen(pen)
        r = event.rect()
        for x in range(snap(r.left()) - GRID, r.right() + GRID, GRID):
            for y in range(snap(r.top()) - GRID, r.bottom() + GRID, GRID):
                p.drawPoint(x, y)

    def resizeEvent(self, event: QtGui.QResizeEvent) -> None:
        super().resizeEvent(event)
        self.placeholder.setGeometry(self.rect())
        for frame in self.frames.values():  # a smaller window never leaves widgets off-screen
            frame.place(frame.desired if not frame.desired.isNull() else frame.geometry())

    def mousePressEvent(self, event: QtGui.QMouseEvent) -> None:
        self.background_pressed.emit()
        super().mousePressEvent(event)

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
        pos = event.position().toPoint()
        self.dropped.emit(QtCore.QPoint(snap(pos.x()), snap(pos.y())))
