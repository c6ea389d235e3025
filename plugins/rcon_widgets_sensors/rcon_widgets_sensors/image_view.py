"""The Image widget's Qt view: paints the newest decoded frame; pinch/pan/double-tap to zoom.

The view tells the model the size it paints at (``set_display_size``: the widget's size in device
pixels, times the zoom: :func:`.viewport.device_box`; on resize and on every zoom change), so the decode
worker makes frames no bigger than needed: a picture bigger than the view arrives exactly the size of the
rectangle it fills there (:func:`.viewport.fitted_pixels`: a 640x480 camera in a 320x260 view as 320x240;
zoomed in, at full resolution). The model hands over a ready frame (its pixels already in Qt's RGB32
layout, ``Frame.rgb32``); the view wraps them in a QImage without copying. Fitted, and the array exactly
that rectangle in device pixels (:func:`.viewport.unscaled_origin`), the view draws it unscaled: the
QImage gets the widget's device pixel ratio and is copied 1:1 (about 0.01 ms instead of a smooth scaling
of 0.2-0.6 ms, during which PySide holds the GIL). Otherwise (zoomed or panned, a frame still decoded for
the size before a resize, a picture smaller than the view, a scan or a map) it draws the whole array
scaled into the rectangle the SOURCE size (``Frame.width``/``height``, which the viewport's zoom and pan
work in) fills, so a smaller array lands exactly where the full one would. Touch: one finger pans, two fingers
pinch-zoom around their centre, a double tap fits the image again. Mouse: drag pans, the wheel zooms, a
double click fits.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any

from qtpy import QtCore, QtGui, QtWidgets

from .image import Frame
from .rates import human_bits, human_rate
from .viewport import Viewport, device_box, unscaled_origin

DOUBLE_TAP_S = 0.35
DOUBLE_TAP_PX = 40.0
#: no new frame for this long (s): the overlay says STALE and ages on its own, without new frames
STALE_AFTER_S = 1.0
#: how often (ms) a stale overlay re-reads its age; only the overlay's rectangle is repainted
OVERLAY_TICK_MS = 333
_STALE_BG = QtGui.QColor(168, 84, 0, 230)
_FRESH_BG = QtGui.QColor(0, 0, 0, 150)


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
        #: the display size last handed to the model (device pixels), None before the first
        self.display_size_sent: tuple[int, int] | None = None
        #: whether the last paint drew the frame 1:1 (the array was the fitted rectangle), else scaled
        self.drawn_unscaled = False
        self.setAttribute(QtCore.Qt.WidgetAttribute.WA_AcceptTouchEvents, True)
        self.setAttribute(QtCore.Qt.WidgetAttribute.WA_OpaquePaintEvent, True)
        self.setProperty("accessibleRole", "Canvas")  # a picture to zoom and pan (the app names it)
        self.setMinimumSize(80, 60)
        self.setSizePolicy(QtWidgets.QSizePolicy.Policy.Expanding, QtWidgets.QSizePolicy.Policy.Expanding)
        #: where the overlay was last painted (the stale ticker repaints only this, grown to the new text)
        self.overlay_rect = QtCore.QRect()
        #: the overlay's text as last painted (tests, accessibility)
        self.overlay_text: list[str] = []
        #: the sentence painted in the middle while there is no picture ("waiting for a keyframe…"), else ""
        self.center_text = ""
        # the overlay's age is computed when painting, and a view repaints on new frames: with the link
        # down nothing would repaint and the age would freeze. A cheap ticker ages a stale overlay.
        self._ticker = QtCore.QTimer(self)
        self._ticker.setInterval(OVERLAY_TICK_MS)
        self._ticker.timeout.connect(self.age_overlay)
        self._ticker.start()

    # -- state ------------------------------------------------------------------------------------------
    def refresh(self, state: Any) -> None:
        self._state = state
        value = state.value
        if isinstance(value, Frame) and value is not self.frame:
            self.frame = value
            px = value.rgb32
            # no copy: the QImage reads the array's memory; self.frame keeps the array alive. RGB32 (made
            # off the GUI thread) is the format the raster painter scales without converting it first
            self._qimage = QtGui.QImage(px.data, px.shape[1], px.shape[0], px.strides[0],
                                        QtGui.QImage.Format.Format_RGB32)
            self.viewport.set_image(value.width, value.height)
        self.update()

    def age_overlay(self) -> None:
        """Repaint only the overlay while the shown frame is older than :data:`STALE_AFTER_S` (the overlay
        ticker calls it; nothing is scheduled for a fresh frame)."""
        frame = self.frame
        if frame is None or not self.isVisible() or self.stale_for() is None:
            return
        lines, _bg = self._overlay_lines()
        fm = QtGui.QFontMetrics(self._overlay_font())
        self.update(self.overlay_rect.united(_overlay_box(fm, lines)).adjusted(-1, -1, 2, 2))

    def stale_for(self) -> float | None:
        """Seconds since the shown frame arrived when that is more than :data:`STALE_AFTER_S`, else None.
        Never for a static topic (a latched map: the model's ``state.static``), which sends one frame."""
        if self.frame is None or getattr(self._state, "static", False):
            return None
        idle = time.time() - self.frame.received
        return idle if idle >= STALE_AFTER_S else None

    # -- the size the model decodes for ---------------------------------------------------------------------
    def sync_display_size(self) -> None:
        """Hand the model the box the picture is painted into, in device pixels (widget size x device
        pixel ratio x zoom), when it changed. Models without ``set_display_size`` (the Camera widget's
        preview) are left alone."""
        setter = getattr(self.model, "set_display_size", None)
        if setter is None:
            return
        size = device_box(self.width(), self.height(), self.devicePixelRatioF(), self.viewport.zoom)
        if size != self.display_size_sent:
            self.display_size_sent = size
            setter(*size)

    # -- painting -----------------------------------------------------------------------------------------
    def resizeEvent(self, event: QtGui.QResizeEvent) -> None:  # noqa: N802
        self.viewport.resize(self.width(), self.height())
        self.sync_display_size()
        super().resizeEvent(event)

    def paintEvent(self, _event: QtGui.QPaintEvent) -> None:  # noqa: N802
        p = QtGui.QPainter(self)
        p.fillRect(self.rect(), QtGui.QColor(14, 17, 22))
        frame, img = self.frame, self._qimage
        if frame is not None and img is not None:
            vp = self.viewport
            vp.resize(self.width(), self.height())
            self.sync_display_size()  # a no-op unless changed; also follows a new device pixel ratio
            ratio = self.devicePixelRatioF()
            at = unscaled_origin(self.width(), self.height(), ratio, frame.width, frame.height,
                                 img.width(), img.height(), vp.fitted)
            self.drawn_unscaled = at is not None
            if at is not None:
                # the worker made the array exactly the fitted rectangle in device pixels: a plain copy
                img.setDevicePixelRatio(ratio)  # a no-op unless it changed
                p.drawImage(QtCore.QPointF(*at), img)
            else:
                x, y, w, h = vp.rect()
                if frame.smooth and vp.scale < 4:
                    p.setRenderHint(QtGui.QPainter.RenderHint.SmoothPixmapTransform, True)
                # the whole array (maybe smaller than the source) into the source's rectangle
                img.setDevicePixelRatio(1.0)
                p.drawImage(QtCore.QRectF(x, y, w, h), img, QtCore.QRectF(0, 0, img.width(), img.height()))
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
        p.setFont(self._overlay_font())
        if frame is None:
            text = "waiting for images…"
            notice = getattr(self.model, "notice", None)
            if state is not None and state.error:
                text = state.error
            elif state is not None and not state.running:
                text = "not running"
            elif notice:
                text = notice + "…"
            self.center_text = text
            p.setPen(QtGui.QColor(170, 180, 195))
            p.drawText(self.rect().adjusted(8, 8, -8, -8),
                       QtCore.Qt.AlignmentFlag.AlignCenter | QtCore.Qt.TextFlag.TextWordWrap, text)
            return
        self.center_text = ""
        lines, bg = self._overlay_lines()
        self.overlay_text = lines
        if not lines:
            self.overlay_rect = QtCore.QRect()
            return
        fm = QtGui.QFontMetrics(p.font())
        box = _overlay_box(fm, lines)
        self.overlay_rect = box
        p.fillRect(box, bg)
        p.setPen(QtGui.QColor(235, 240, 245) if bg is _FRESH_BG else QtGui.QColor(255, 255, 255))
        for i, s in enumerate(lines):
            p.drawText(QtCore.QPointF(12, 10 + fm.ascent() + i * fm.height()), s)

    def _overlay_font(self) -> QtGui.QFont:
        font = QtGui.QFont(self.font())
        font.setPointSizeF(max(7.0, font.pointSizeF() * 0.85))
        return font

    def _overlay_lines(self) -> tuple[list[str], QtGui.QColor]:
        """The overlay's lines and background: rate and age, or STALE with how long no frame came."""
        state, frame = self._state, self.frame
        lines: list[str] = []
        bg = _FRESH_BG
        if frame is None:
            return lines, bg
        show = getattr(self.model.settings, "show_overlay", True)
        stale = self.stale_for()
        if stale is not None:
            # always shown, overlay or not: an old picture must never pass for a live one
            lines.append(f"STALE · no new frame for {_duration(stale)}")
            bg = _STALE_BG
        elif show:
            fps = self.painted_fps or frame.fps
            age = time.time() - (frame.stamp or frame.received)
            lines.append((f"{fps:4.1f} fps" if fps > 0 else "– fps") + f" · age {_duration(age)}")
        if show:
            lines.append(frame.info + _rate_text(frame))
            source = getattr(self.model, "transport_note", None)
            if source:
                lines.append(source)
            if not self.viewport.fitted:
                lines.append(f"zoom ×{self.viewport.zoom:.1f} (double-tap to fit)")
        notice = getattr(self.model, "notice", None)
        if notice:  # always shown: the picture is held, not live
            lines.append(f"⏸ picture held: {notice}")
            bg = _STALE_BG
        if state is not None and state.error:
            lines.append("⚠ " + state.error)
        return lines, bg

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
                self.sync_display_size()
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
        self.sync_display_size()
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
            self.sync_display_size()
            self.update()


def _rate_text(frame: Frame) -> str:
    """What the frame's stream costs the link, for the overlay: video as a bit rate and bytes per second,
    images as bytes per second; nothing before the rate is known."""
    if frame.byte_rate <= 0:
        return ""
    if frame.kind == "video":
        return f" · {human_bits(frame.byte_rate)} ({human_rate(frame.byte_rate)})"
    return f" · {human_rate(frame.byte_rate)}"


def _duration(seconds: float) -> str:
    """``97 ms``, ``3.4 s``, ``12 s``, ``5 min``."""
    if seconds < 1:
        return f"{max(0.0, seconds) * 1000:.0f} ms"
    if seconds < 10:
        return f"{seconds:.1f} s"
    if seconds < 120:
        return f"{seconds:.0f} s"
    return f"{seconds / 60:.0f} min"


def _overlay_box(fm: QtGui.QFontMetrics, lines: list[str]) -> QtCore.QRect:
    if not lines:
        return QtCore.QRect()
    w = max(fm.horizontalAdvance(s) for s in lines) + 12
    return QtCore.QRect(6, 6, w, fm.height() * len(lines) + 8)


def _dist(a: QtCore.QPointF, b: QtCore.QPointF) -> float:
    return math.hypot(a.x() - b.x(), a.y() - b.y())


def _mid(a: QtCore.QPointF, b: QtCore.QPointF) -> QtCore.QPointF:
    return QtCore.QPointF((a.x() + b.x()) / 2, (a.y() + b.y()) / 2)
