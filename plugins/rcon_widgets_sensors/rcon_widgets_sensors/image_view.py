"""The Image widget's Qt view: paints the newest decoded frame; pinch/pan/double-tap to zoom.

The model hands over a ready RGB array; the view wraps it in a QImage without copying and draws it
scaled (the one copy is the scaling itself). Touch: one finger pans, two fingers pinch-zoom around their
centre, a double tap fits the image again. Mouse: drag pans, the wheel zooms, a double click fits.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any

from qtpy import QtCore, QtGui, QtWidgets

from .image import Frame
from .viewport import Viewport

DOUBLE_TAP_S = 0.35
DOUBLE_TAP_PX = 40.0


class ImageView(QtWidgets.QWidget):
    """Shows ``state.value`` (a :class:`Frame`) letterboxed, with a frame-rate and age overlay."""

    def __init__(self, model: Any, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.model = model
        self.viewport = Viewport()
        self.frame: Frame | None = None
        self._qimage: QtGui.QImage | None = None
        self._state: Any = None
        self._painted_times: list[float] = []
        self.painted_fps = 0.0
        #: called after each paint that showed a new frame: fn(frame, painted_wall_time) (benchmarks)
        self.on_painted: Callable[[Frame, float], None] | None = None
        self._last_painted_index = -1
        self._touch_last: dict[int, QtCore.QPointF] = {}
        self._last_tap: tuple[float, QtCore.QPointF] | None = None
        self._touch_moved = False
        self._drag_from: QtCore.QPointF | None = None
        self.setAttribute(QtCore.Qt.WidgetAttribute.WA_AcceptTouchEvents, True)
        self.setAttribute(QtCore.Qt.WidgetAttribute.WA_OpaquePaintEvent, True)
        self.setMinimumSize(80, 60)
        self.setSizePolicy(QtWidgets.QSizePolicy.Policy.Expanding, QtWidgets.QSizePolicy.Policy.Expanding)

    # -- state ------------------------------------------------------------------------------------------
    def refresh(self, state: Any) -> None:
        self._state = state
        value = state.value
        if isinstance(value, Frame) and value is not self.frame:
            self.frame = value
            rgb = value.rgb
            # no copy: the QImage reads the array's memory; self.frame keeps the array alive
            self._qimage = QtGui.QImage(rgb.data, value.width, value.height, rgb.strides[0],
                                        QtGui.QImage.Format.Format_RGB888)
            self.viewport.set_image(value.width, value.height)
        self.update()

    # -- painting -----------------------------------------------------------------------------------------
    def resizeEvent(self, event: QtGui.QResizeEvent) -> None:  # noqa: N802
        self.viewport.resize(self.width(), self.height())
        super().resizeEvent(event)

    def paintEvent(self, _event: QtGui.QPaintEvent) -> None:  # noqa: N802
        p = QtGui.QPainter(self)
        p.fillRect(self.rect(), QtGui.QColor(14, 17, 22))
        frame, img = self.frame, self._qimage
        if frame is not None and img is not None:
            vp = self.viewport
            vp.resize(self.width(), self.height())
            x, y, w, h = vp.rect()
            if frame.smooth and vp.scale < 4:
                p.setRenderHint(QtGui.QPainter.RenderHint.SmoothPixmapTransform, True)
            p.drawImage(QtCore.QRectF(x, y, w, h), img, QtCore.QRectF(0, 0, frame.width, frame.height))
            p.setRenderHint(QtGui.QPainter.RenderHint.SmoothPixmapTransform, False)
        self._paint_status(p)
        p.end()
        if frame is not None and frame.index != self._last_painted_index:
            self._last_painted_index = frame.index
            now = time.time()
            self._painted_times.append(now)
            del self._painted_times[:-60]
            if len(self._painted_times) > 1 and now > self._painted_times[0]:
                self.painted_fps = (len(self._painted_times) - 1) / (now - self._painted_times[0])
            if self.on_painted is not None:
                self.on_painted(frame, now)

    def _paint_status(self, p: QtGui.QPainter) -> None:
        state, frame = self._state, self.frame
        font = p.font()
        font.setPointSizeF(max(7.0, font.pointSizeF() * 0.85))
        p.setFont(font)
        if frame is None:
            text = "waiting for images…"
            if state is not None and state.error:
                text = state.error
            elif state is not None and not state.running:
                text = "not running"
            p.setPen(QtGui.QColor(170, 180, 195))
            p.drawText(self.rect().adjusted(8, 8, -8, -8),
                       QtCore.Qt.AlignmentFlag.AlignCenter | QtCore.Qt.TextFlag.TextWordWrap, text)
            return
        lines = []
        show = getattr(self.model.settings, "show_overlay", True)
        if show:
            fps = self.painted_fps or frame.fps
            age = time.time() - (frame.stamp or frame.received)
            age_txt = f"{age * 1000:.0f} ms" if age < 10 else f"{age:.0f} s"
            lines.append((f"{fps:4.1f} fps" if fps > 0 else "– fps") + f" · age {age_txt}")
            lines.append(frame.info)
            if not self.viewport.fitted:
                lines.append(f"zoom ×{self.viewport.zoom:.1f} (double-tap to fit)")
        if state is not None and state.error:
            lines.append("⚠ " + state.error)
        if not lines:
            return
        fm = QtGui.QFontMetrics(p.font())
        w = max(fm.horizontalAdvance(s) for s in lines) + 12
        h = fm.height() * len(lines) + 8
        p.fillRect(QtCore.QRectF(6, 6, w, h), QtGui.QColor(0, 0, 0, 150))
        p.setPen(QtGui.QColor(235, 240, 245))
        for i, s in enumerate(lines):
            p.drawText(QtCore.QPointF(12, 10 + fm.ascent() + i * fm.height()), s)

    # -- touch: pan, pinch, double tap -----------------------------------------------------------------
    def event(self, e: QtCore.QEvent) -> bool:
        t = e.type()
        if t in (QtCore.QEvent.Type.TouchBegin, QtCore.QEvent.Type.TouchUpdate, QtCore.QEvent.Type.TouchEnd,
                 QtCore.QEvent.Type.TouchCancel):
            self._touch(e)
            e.accept()
            return True
        return super().event(e)

    def _touch(self, e: Any) -> None:
        t = e.type()
        pts = {p.id(): p.position() for p in e.points()
               if p.state() != QtGui.QEventPoint.State.Released}
        if t == QtCore.QEvent.Type.TouchBegin:
            self._touch_moved = False
        if t == QtCore.QEvent.Type.TouchCancel:
            self._touch_last = {}
            return
        common = [i for i in pts if i in self._touch_last]
        if len(common) >= 2:
            a, b = common[:2]
            old_d = _dist(self._touch_last[a], self._touch_last[b])
            new_d = _dist(pts[a], pts[b])
            old_c = _mid(self._touch_last[a], self._touch_last[b])
            new_c = _mid(pts[a], pts[b])
            self.viewport.pan_by(new_c.x() - old_c.x(), new_c.y() - old_c.y())
            if old_d > 4:
                self.viewport.zoom_at(new_d / old_d, new_c.x(), new_c.y())
            self._touch_moved = True
        elif len(common) == 1 and len(pts) == 1:
            i = common[0]
            d = pts[i] - self._touch_last[i]
            if abs(d.x()) + abs(d.y()) > 0.5:
                self.viewport.pan_by(d.x(), d.y())
                self._touch_moved = True
        if t == QtCore.QEvent.Type.TouchEnd:
            released = [p for p in e.points()]
            if not self._touch_moved and len(released) == 1:
                self._tap(released[0].position())
            self._touch_last = {}
        else:
            self._touch_last = pts
        self.update()

    def _tap(self, pos: QtCore.QPointF) -> None:
        now = time.monotonic()
        if self._last_tap is not None:
            when, where = self._last_tap
            if now - when < DOUBLE_TAP_S and _dist(pos, where) < DOUBLE_TAP_PX:
                self.fit()
                self._last_tap = None
                return
        self._last_tap = (now, pos)

    def fit(self) -> None:
        """Show the whole image again."""
        self.viewport.fit()
        self.update()

    # -- mouse -----------------------------------------------------------------------------------------
    def mousePressEvent(self, e: QtGui.QMouseEvent) -> None:  # noqa: N802
        self._drag_from = e.position()

    def mouseMoveEvent(self, e: QtGui.QMouseEvent) -> None:  # noqa: N802
        if self._drag_from is not None:
            d = e.position() - self._drag_from
            self._drag_from = e.position()
            self.viewport.pan_by(d.x(), d.y())
            self.update()

    def mouseReleaseEvent(self, _e: QtGui.QMouseEvent) -> None:  # noqa: N802
        self._drag_from = None

    def mouseDoubleClickEvent(self, _e: QtGui.QMouseEvent) -> None:  # noqa: N802
        self.fit()

    def wheelEvent(self, e: QtGui.QWheelEvent) -> None:  # noqa: N802
        steps = e.angleDelta().y() / 120.0
        if steps:
            pos = e.position()
            self.viewport.zoom_at(1.25 ** steps, pos.x(), pos.y())
            self.update()


def _dist(a: QtCore.QPointF, b: QtCore.QPointF) -> float:
    return math.hypot(a.x() - b.x(), a.y() - b.y())


def _mid(a: QtCore.QPointF, b: QtCore.QPointF) -> QtCore.QPointF:
    return QtCore.QPointF((a.x() + b.x()) / 2, (a.y() + b.y()) / 2)
