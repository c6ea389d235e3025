"""The frame around one widget on a canvas: title, the widget's view, status badges, and editing.

In edit mode a transparent *shield* covers the view and takes every press: drag to move, drag a corner
handle or pinch with two fingers to resize, long-press or right-click for the context menu.  In operator
(locked) mode the shield is gone, the view gets the touches, and nothing can be moved or deleted.

Painting is kept cheap because every live value repaints its view up to 60 times a second: the body
around the view is opaque (a value change repaints the body and the view only, never the frame, the
canvas grid or the window behind them), the shield never paints (the corner marks are small pixmap
labels drawn by Qt), and the frame handles no per-event Python code (pinch gestures go to the shield).
"""

from __future__ import annotations

import math

from qtpy import QtCore, QtGui, QtWidgets

from rcon_core.app.elided_label import OneLineLabel
from rcon_core.app.frame_badge import Badge, ReasonLine, badge_form
from rcon_core.app.geometry import GRID, fit_rect, scaled_about_center, snap_rect, snap_up
from rcon_core.app.theme import colour as theme_colour
from rcon_core.app.theme import current_text_size, current_touch_px, font_px, repolish

LONG_PRESS_MS = 600
DRAG_SLOP = 12
#: a widget's frame holds at least this many lines of its text: a larger text size grows the text in a
#: widget as far as the widget's box allows (its title and its view), never past it
FRAME_LINES = 6


def frame_min_size() -> QtCore.QSize:
    """The smallest a widget frame may be: room for its corner handles and a little content."""
    t = current_touch_px()
    return QtCore.QSize(max(3 * t, 5 * GRID), max(2 * t + GRID, 5 * GRID))


class FrameTitle(OneLineLabel):
    """The frame's title on one line: cut with "…" when the frame is too narrow (never mid-letter), the
    full title in its tooltip; :attr:`reserve` px at its right end are kept for the status badge.
    Its side padding is a contents margin (:attr:`PAD`, not the style sheet's), so the room to elide in is
    known: see :meth:`set_inset`."""

    PAD = 6

    def __init__(self, title: str, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.full_title = ""
        self.reserve = 0
        self.setIndent(0)  # the text starts at the contents rect (PAD), nothing more
        self.set_inset(0)
        self.set_title(title)

    def set_inset(self, px: int) -> None:
        """Keep ``px`` more than the padding clear at both ends (the corner handles in Edit mode)."""
        self.setContentsMargins(self.PAD + px, 0, self.PAD + px, 0)

    def set_title(self, title: str) -> None:
        self.full_title = title
        self.setToolTip(title)
        self.setAccessibleName(title)
        self._elide()

    def set_reserve(self, px: int) -> None:
        if px != self.reserve:
            self.reserve = px
            self._elide()

    def resizeEvent(self, event: QtGui.QResizeEvent) -> None:  # noqa: N802 - Qt's name
        super().resizeEvent(event)
        frame = self.parentWidget()
        if isinstance(frame, WidgetFrame) and event.oldSize().height() != event.size().height():
            frame.layout_overlays()  # a taller or lower bar (another text size): the badge fits it again

    def _elide(self) -> None:
        room = self.contentsRect().width() - self.reserve
        text = self.fontMetrics().elidedText(self.full_title, QtCore.Qt.TextElideMode.ElideRight, max(0, room))
        if text != self.text():
            self.setText(text)


class ProblemOverlay(QtWidgets.QLabel):
    """Covers the view while the widget's settings are not valid and lists what is missing."""

    def __init__(self, parent: QtWidgets.QWidget) -> None:
        super().__init__(parent)
        self.setObjectName("problemOverlay")
        self.setWordWrap(True)
        self.setAlignment(QtCore.Qt.AlignmentFlag.AlignCenter)
        self.setAttribute(QtCore.Qt.WidgetAttribute.WA_TransparentForMouseEvents)
        self.set_font_sheet("")
        self.hide()

    def set_font_sheet(self, font_sheet: str) -> None:
        """Its look, at its frame's text size (``font_sheet``: "" for the app's)."""
        sheet = ("background: rgba(255, 236, 179, 235); color: #000000; border: 3px dashed #b00000;"
                 f" font-weight: bold; padding: 6px;{font_sheet}")
        if sheet != self.styleSheet():
            self.setStyleSheet(sheet)

    def set_problems(self, problems: list[str]) -> None:
        if problems:
            self.setText("⚠ Not configured\n" + "\n".join(f"• {p}" for p in problems))
            self.show()
            self.raise_()
        else:
            self.hide()


class Shield(QtWidgets.QWidget):
    """Transparent layer over a frame in edit mode: turns presses into move/resize/menu."""

    def __init__(self, frame: WidgetFrame) -> None:
        super().__init__(frame)
        self.frame = frame
        self.setAttribute(QtCore.Qt.WidgetAttribute.WA_AcceptTouchEvents)
        self.setMouseTracking(False)
        # input only: it never paints (the corner marks are CornerMark labels above it), so a repaint of
        # the view underneath costs no Python call here
        self.setUpdatesEnabled(False)
        self.grabGesture(QtCore.Qt.GestureType.PinchGesture)
        self._long = QtCore.QTimer(self)
        self._long.setSingleShot(True)
        self._long.setInterval(LONG_PRESS_MS)
        self._long.timeout.connect(self._long_press)
        self._mode = ""  # "", "move", "resize", "pinch"
        self._press_global = QtCore.QPointF()
        self._start_rect = QtCore.QRect()
        self._corner = ""
        self._pinch_dist = 0.0

    # mouse -------------------------------------------------------------------------------------------
    def mousePressEvent(self, event: QtGui.QMouseEvent) -> None:
        if event.button() == QtCore.Qt.MouseButton.RightButton:
            self.frame.request_menu(event.globalPosition().toPoint())
            return
        if event.button() == QtCore.Qt.MouseButton.LeftButton:
            self._begin(event.position(), event.globalPosition())

    def mouseMoveEvent(self, event: QtGui.QMouseEvent) -> None:
        if self._mode:
            self._drag(event.globalPosition())

    def mouseReleaseEvent(self, _event: QtGui.QMouseEvent) -> None:
        self._end()

    # touch -------------------------------------------------------------------------------------------
    def event(self, event: QtCore.QEvent) -> bool:
        t = event.type()
        if t == QtCore.QEvent.Type.Gesture:  # native pinch (trackpads, platforms sending QPinchGesture)
            pinch = event.gesture(QtCore.Qt.GestureType.PinchGesture)  # type: ignore[attr-defined]
            if pinch is not None:
                self.frame.pinch_gesture(pinch)
                event.accept()
                return True
        if t in (QtCore.QEvent.Type.TouchBegin, QtCore.QEvent.Type.TouchUpdate, QtCore.QEvent.Type.TouchEnd):
            self._touch(event)  # type: ignore[arg-type]
            event.accept()
            return True
        if t == QtCore.QEvent.Type.TouchCancel:
            self._end(commit=False)
            return True
        if t == QtCore.QEvent.Type.ToolTip:  # over the badge: its reason, as in Operate mode
            badge = self.frame.badge
            pos = event.pos()  # type: ignore[attr-defined]
            if badge.isVisible() and badge.told() and badge.geometry().contains(pos):
                QtWidgets.QToolTip.showText(event.globalPos(), badge.told(), self)  # type: ignore[attr-defined]
                return True
        return super().event(event)

    def _touch(self, event: QtGui.QTouchEvent) -> None:
        points = [p for p in event.points() if p.state() != QtGui.QEventPoint.State.Released]
        if event.type() == QtCore.QEvent.Type.TouchEnd or not points:
            self._end()
            return
        if len(points) >= 2:
            a, b = points[0].globalPosition(), points[1].globalPosition()
            dist = math.hypot(a.x() - b.x(), a.y() - b.y())
            if self._mode != "pinch":
                self._long.stop()
                self._mode = "pinch"
                self._pinch_dist = max(dist, 1.0)
                self._start_rect = self.frame.geometry()
                self.frame.set_selected(True)
            else:
                self.frame.apply_pinch(dist / self._pinch_dist, self._start_rect, finished=False)
            return
        if self._mode == "pinch":
            return  # one finger lifted mid-pinch: wait for the end
        point = points[0]
        if event.type() == QtCore.QEvent.Type.TouchBegin or not self._mode:
            self._begin(point.position(), point.globalPosition())
        else:
            self._drag(point.globalPosition())

    # shared ------------------------------------------------------------------------------------------
    def _begin(self, local: QtCore.QPointF, global_pos: QtCore.QPointF) -> None:
        self.frame.set_selected(True)
        self._press_global = QtCore.QPointF(global_pos)
        self._start_rect = self.frame.geometry()
        self._corner = self.frame.corner_at(local.toPoint())
        self._mode = "resize" if self._corner else "pending"
        self._long.start()

    def _drag(self, global_pos: QtCore.QPointF) -> None:
        delta = global_pos - self._press_global
        if self._mode == "pending":
            if abs(delta.x()) + abs(delta.y()) < DRAG_SLOP:
                return
            self._mode = "move"
        self._long.stop()
        if self._mode == "move":
            self.frame.move_to(self._start_rect.topLeft() + delta.toPoint(), finished=False)
        elif self._mode == "resize":
            self.frame.resize_corner(self._corner, self._start_rect, delta.toPoint(), finished=False)

    def _end(self, commit: bool = True) -> None:
        self._long.stop()
        mode, self._mode = self._mode, ""
        if commit and mode in ("move", "resize", "pinch"):
            self.frame.commit_geometry()

    def _long_press(self) -> None:
        if self._mode == "pending":
            self._mode = ""
            self.frame.request_menu(self.mapToGlobal(self.rect().center()))


CORNERS = ("tl", "tr", "bl", "br")
MARK_INSET = 4
_MARK_CACHE: dict[tuple[str, bool, int, float, str], QtGui.QPixmap] = {}


def mark_geometry(selected: bool, handle: int) -> tuple[int, int]:
    """(pen width, arm length) of the L drawn at each corner of a frame in edit mode."""
    return (8, round(handle * 0.6)) if selected else (5, max(14, handle // 3))


def mark_pixmap(corner: str, selected: bool, handle: int, dpr: float = 1.0, colour: str = "#0040a0") -> QtGui.QPixmap:
    """The L at ``corner`` ("tl", "tr", "bl", "br") in a transparent square pixmap whose outer corner is
    the frame's corner: thick and blue on the selected frame, "drag here to resize"."""
    key = (corner, selected, handle, dpr, colour)
    pix = _MARK_CACHE.get(key)
    if pix is not None:
        return pix
    width, arm = mark_geometry(selected, handle)
    side = MARK_INSET + arm + width
    pix = QtGui.QPixmap(round(side * dpr), round(side * dpr))
    pix.setDevicePixelRatio(dpr)
    pix.fill(QtCore.Qt.GlobalColor.transparent)
    p = QtGui.QPainter(pix)
    p.setRenderHint(QtGui.QPainter.RenderHint.Antialiasing)
    pen = QtGui.QPen(QtGui.QColor(colour), width)
    pen.setCapStyle(QtCore.Qt.PenCapStyle.FlatCap)
    p.setPen(pen)
    x, dx = (MARK_INSET, 1) if corner[1] == "l" else (side - MARK_INSET, -1)
    y, dy = (MARK_INSET, 1) if corner[0] == "t" else (side - MARK_INSET, -1)
    p.drawLine(x, y, x + dx * arm, y)
    p.drawLine(x, y, x, y + dy * arm)
    p.end()
    _MARK_CACHE[key] = pix
    return pix


class CornerMark(QtWidgets.QLabel):
    """One corner's L in edit mode: a pixmap Qt draws itself; presses go through to the shield."""

    def __init__(self, corner: str, parent: QtWidgets.QWidget) -> None:
        super().__init__(parent)
        self.setObjectName("frameCorner")
        self.corner = corner
        self.setAttribute(QtCore.Qt.WidgetAttribute.WA_TransparentForMouseEvents)

    def show_mark(self, selected: bool, handle: int) -> None:
        screen = self.screen()
        pix = mark_pixmap(self.corner, selected, handle, screen.devicePixelRatio() if screen else 1.0,
                          theme_colour("FOCUS").name())
        self.setPixmap(pix)
        side = round(pix.width() / pix.devicePixelRatio())
        frame = self.parentWidget()
        w, h = (frame.width(), frame.height()) if frame is not None else (side, side)
        self.setGeometry(0 if self.corner[1] == "l" else w - side, 0 if self.corner[0] == "t" else h - side,
                         side, side)


class FrameBody(QtWidgets.QWidget):
    """The white area around the view, opaque to Qt's painting: a repaint of the view stops here.

    The theme's style sheet clears ``autoFillBackground`` whenever it polishes a widget it gives a
    background; the body sets it again after each style change (the brush is the theme's background).
    """

    def __init__(self) -> None:
        super().__init__()
        self.setObjectName("frameBody")
        self.setAutoFillBackground(True)

    def changeEvent(self, event: QtCore.QEvent) -> None:  # noqa: N802 - Qt's name
        super().changeEvent(event)
        if event.type() in (QtCore.QEvent.Type.StyleChange, QtCore.QEvent.Type.PaletteChange) \
                and not self.autoFillBackground():
            self.setAutoFillBackground(True)

    def ensure_opaque(self) -> None:
        """Polish now and make sure the background is filled (so Qt treats the body as opaque)."""
        self.ensurePolished()
        if not self.autoFillBackground():
            self.setAutoFillBackground(True)


class WidgetFrame(QtWidgets.QFrame):
    """One widget instance on a canvas surface."""

    geometry_committed = QtCore.Signal(str, QtCore.QRect)  # instance id, new rect (snapped, on the canvas)
    action_requested = QtCore.Signal(str, str)  # instance id, "configure" | "duplicate" | "delete"
    selected_changed = QtCore.Signal(str, bool)

    def __init__(self, instance_id: str, title: str, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.setObjectName("widgetFrame")
        self.instance_id = instance_id
        self.selected = False
        self.editable = True
        self.menu: QtWidgets.QMenu | None = None
        self.title = FrameTitle(title)
        self.title.setObjectName("frameTitle")
        self.body = FrameBody()
        self.body_layout = QtWidgets.QVBoxLayout(self.body)
        self.body_layout.setContentsMargins(4, 4, 4, 4)
        self.view: QtWidgets.QWidget | None = None
        col = QtWidgets.QVBoxLayout(self)
        col.setContentsMargins(3, 3, 3, 3)
        col.setSpacing(0)
        col.addWidget(self.title)
        col.addWidget(self.body, 1)
        self.problems = ProblemOverlay(self)
        self.badge = Badge(self)
        self.reason_line = ReasonLine(self)
        self.shield = Shield(self)
        self.marks = [CornerMark(corner, self) for corner in CORNERS]
        self.setProperty("accessibleRole", "Grouping")  # a widget on the canvas: its title names it
        self.shield.setProperty("accessibleRole", "Grip")  # Edit mode: drag to move, corners to resize
        self._name_parts(title)
        self._pinch_start = QtCore.QRect()

    # content ----------------------------------------------------------------------------------------
    def set_view(self, view: QtWidgets.QWidget) -> None:
        if self.view is not None:
            self.body_layout.removeWidget(self.view)
            self.view.deleteLater()
        self.view = view
        self.body_layout.addWidget(view)
        self.layout_overlays()

    def set_placeholder(self, text: str) -> QtWidgets.QLabel:
        label = QtWidgets.QLabel(text)
        label.setObjectName("placeholder")
        label.setWordWrap(True)
        label.setAlignment(QtCore.Qt.AlignmentFlag.AlignCenter)
        self.set_view(label)
        return label

    def set_title(self, title: str) -> None:
        self.title.set_title(title)
        self._name_parts(title)

    def _name_parts(self, title: str) -> None:
        self.setAccessibleName(title)
        self.shield.setAccessibleName(f"Move or resize {title}")

    # modes ------------------------------------------------------------------------------------------
    def set_editable(self, editable: bool) -> None:
        self.editable = editable
        self.shield.setVisible(editable)
        for mark in self.marks:
            mark.setVisible(editable)
        # in edit mode the title keeps clear of the corner handles
        margin = max(14, self.handle_size() // 3) + 4 if editable else 0
        self.title.set_inset(margin)
        if not editable:
            self.set_selected(False)
        self.layout_overlays()

    def set_selected(self, selected: bool) -> None:
        if selected == self.selected:
            return
        self.selected = selected
        self.setProperty("selected", selected)
        repolish(self)
        self.layout_overlays()
        if selected:
            self.raise_()
        self.selected_changed.emit(self.instance_id, selected)

    # geometry ---------------------------------------------------------------------------------------
    def handle_size(self) -> int:
        return current_touch_px()

    def min_size(self) -> QtCore.QSize:
        return frame_min_size()

    def handle_rects(self, size: int | None = None) -> dict[str, QtCore.QRect]:
        size = size or self.handle_size()
        w, h = self.width(), self.height()
        return {
            "tl": QtCore.QRect(0, 0, size, size),
            "tr": QtCore.QRect(w - size, 0, size, size),
            "bl": QtCore.QRect(0, h - size, size, size),
            "br": QtCore.QRect(w - size, h - size, size, size),
        }

    def corner_at(self, pos: QtCore.QPoint) -> str:
        for name, rect in self.handle_rects().items():
            if rect.contains(pos):
                return name
        return ""

    def bounds(self) -> QtCore.QRect:
        parent = self.parentWidget()
        return parent.rect() if parent is not None else QtCore.QRect(0, 0, 10_000, 10_000)

    def max_size(self) -> QtCore.QSize:
        """The largest a resize or pinch may make the frame: the canvas's visible area (its scroll view),
        on the grid, never below :meth:`min_size`. A widget loaded larger keeps its size (see
        :meth:`_capped`)."""
        parent = self.parentWidget()
        view_size = getattr(parent, "view_size", None)
        view = view_size() if callable(view_size) else parent.size() if parent is not None else None
        low = self.min_size()
        if view is None or view.isEmpty():
            return QtCore.QSize(max(low.width(), 10_000), max(low.height(), 10_000))
        return QtCore.QSize(max(snap_up(low.width()), view.width() // GRID * GRID),
                            max(snap_up(low.height()), view.height() // GRID * GRID))

    def _limit(self, start: QtCore.QRect) -> QtCore.QSize:
        """:meth:`max_size`, or ``start``'s size where it is already larger (growing stops, nothing jumps)."""
        cap = self.max_size()
        return QtCore.QSize(max(cap.width(), start.width()), max(cap.height(), start.height()))

    def place(self, rect: QtCore.QRect) -> None:
        """Set the frame's geometry, at least :meth:`min_size` and never left of or above the canvas (no
        snapping, no upper limit: used while dragging and on load; the canvas scrolls to cover it)."""
        self.setGeometry(fit_rect(rect, self.bounds(), self.min_size()))

    def move_to(self, top_left: QtCore.QPoint, finished: bool = True) -> None:
        self.place(QtCore.QRect(top_left, self.size()))
        if finished:
            self.commit_geometry()

    def resize_corner(self, corner: str, start: QtCore.QRect, delta: QtCore.QPoint, finished: bool = True) -> None:
        """Drag ``corner`` of ``start`` by ``delta``; the opposite corner stays, the size stays between
        :meth:`min_size` and :meth:`max_size`."""
        r = QtCore.QRect(start)
        low, high = self.min_size(), self._limit(start)
        if "l" in corner:
            r.setLeft(max(min(r.left() + delta.x(), r.right() - low.width()), r.right() + 1 - high.width()))
        else:
            r.setRight(min(r.right() + delta.x(), r.left() + high.width() - 1))
        if "t" in corner:
            r.setTop(max(min(r.top() + delta.y(), r.bottom() - low.height()), r.bottom() + 1 - high.height()))
        else:
            r.setBottom(min(r.bottom() + delta.y(), r.top() + high.height() - 1))
        self.place(r)
        if finished:
            self.commit_geometry()

    def apply_pinch(self, scale: float, start: QtCore.QRect | None = None, finished: bool = True) -> None:
        """Resize by ``scale`` (relative to ``start``, default the current geometry) about the centre,
        keeping the aspect; growing stops at :meth:`max_size` (the canvas's visible area)."""
        if not self.editable:
            return
        start = QtCore.QRect(start if start is not None else self.geometry())
        high = self._limit(start)
        fits = min(high.width() / max(1, start.width()), high.height() / max(1, start.height()))
        scale = max(0.1, min(float(scale), fits))
        self.place(scaled_about_center(start, scale))
        if finished:
            self.commit_geometry()

    def commit_geometry(self) -> None:
        """Snap to the grid (at least :meth:`min_size`, never at negative coordinates; the canvas
        scrolls to the rest) and report the final geometry."""
        rect = fit_rect(snap_rect(self.geometry()), self.bounds(), self.min_size())
        self.setGeometry(rect)
        self.geometry_committed.emit(self.instance_id, QtCore.QRect(rect))

    # gestures (native pinch, e.g. trackpads; the shield receives them) ----------------------------
    def pinch_gesture(self, pinch: QtWidgets.QPinchGesture) -> None:
        """Handle a QPinchGesture (or any object with ``state()`` and ``totalScaleFactor()``)."""
        if not self.editable:
            return
        state = pinch.state()
        if state == QtCore.Qt.GestureState.GestureStarted:
            self._pinch_start = self.geometry()
            self.set_selected(True)
        if self._pinch_start.isNull():
            self._pinch_start = self.geometry()
        finished = state in (QtCore.Qt.GestureState.GestureFinished, QtCore.Qt.GestureState.GestureCanceled)
        self.apply_pinch(pinch.totalScaleFactor(), self._pinch_start, finished=finished)
        if finished:
            self._pinch_start = QtCore.QRect()

    # context menu -----------------------------------------------------------------------------------
    def request_menu(self, global_pos: QtCore.QPoint) -> QtWidgets.QMenu | None:
        """Open the context menu (configure, duplicate, delete); nothing in operator mode."""
        if not self.editable:
            return None
        menu = QtWidgets.QMenu(self)
        menu.setObjectName("frameMenu")
        for name, text in (("configure", "Configure…"), ("duplicate", "Duplicate"), ("delete", "Delete")):
            action = menu.addAction(text)
            action.setObjectName(name)
            action.triggered.connect(lambda _=False, n=name: self.action_requested.emit(self.instance_id, n))
        self.menu = menu
        menu.popup(global_pos)
        return menu

    # text size ----------------------------------------------------------------------------------------
    def text_px(self) -> int:
        """The font size of this widget's title and view: the app's (theme.py), but no more than
        :data:`FRAME_LINES` lines fill the frame's height (never below the standard size)."""
        base = font_px(current_touch_px(), current_text_size())
        room = max(1, self.height() - 6) // FRAME_LINES
        return max(min(base, room), min(base, font_px(current_touch_px(), 100)))

    def fit_text(self) -> None:
        """Give the title and the view :meth:`text_px` (through style sheets: the theme's would win over a
        font); nothing when it is the app's own size."""
        px = self.text_px()
        sheet = "" if px == font_px(current_touch_px(), current_text_size()) else f"font-size: {px}px;"
        for part in (self.title, self.body, self.reason_line):
            if part.styleSheet() != sheet:
                part.setStyleSheet(sheet)
        self.problems.set_font_sheet(f" {sheet}" if sheet else "")
        if self.badge.font_sheet != sheet:
            self.badge.font_sheet = sheet
            if self.badge.kind:
                self.badge.restyle()
                self.layout_overlays()

    # overlays ---------------------------------------------------------------------------------------
    def resizeEvent(self, event: QtGui.QResizeEvent) -> None:
        super().resizeEvent(event)
        self.fit_text()
        self.layout_overlays()

    def showEvent(self, event: QtGui.QShowEvent) -> None:
        super().showEvent(event)
        self.body.ensure_opaque()

    def changeEvent(self, event: QtCore.QEvent) -> None:  # noqa: N802 - Qt's name
        super().changeEvent(event)
        if event.type() == QtCore.QEvent.Type.PaletteChange and self.editable:
            self.layout_overlays()  # another theme: the corner marks in its colour
        if event.type() in (QtCore.QEvent.Type.StyleChange, QtCore.QEvent.Type.FontChange):
            self.fit_text()  # another text size

    def layout_overlays(self) -> None:
        self.shield.setGeometry(self.rect())
        body = self.body.geometry()
        self.problems.setGeometry(body.adjusted(4, 4, -4, -4))
        if self.badge.isVisible():  # in the title bar, so it never covers what the view shows
            title = self.title.geometry()
            self.badge.setMaximumHeight(title.height())
            self.badge.show_form(badge_form(self.badge, self.title))
            self.badge.move(title.right() - self.badge.width() - 2,
                            title.top() + max(0, (title.height() - self.badge.height()) // 2))
            self.title.set_reserve(max(0, self.badge.width() + 6 - self.title.contentsMargins().right()))
        else:
            self.title.set_reserve(0)
        title = self.title.geometry()
        line = self.reason_line.sizeHint().height()
        self.reason_line.setGeometry(title.left(), title.bottom() + 1, title.width(), line)
        self.problems.raise_()
        self.reason_line.raise_()
        self.badge.raise_()
        if self.editable:
            self.shield.raise_()
            handle = self.handle_size()
            for mark in self.marks:
                mark.show_mark(self.selected, handle)
                mark.raise_()
