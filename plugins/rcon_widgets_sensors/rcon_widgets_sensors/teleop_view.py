"""The Multi-Touch teleop pad's Qt view: a round pad; the finger's offset from the centre drives.

Each pad takes its own touch points (touch events are delivered per widget), so two pads on one canvas
work at once with two thumbs. The first finger on a pad drives it; lifting it, a cancelled touch, the
window losing focus or the pad being hidden all call ``model.release()`` (the model sends the zero).
Mouse dragging works the same on a desktop.

A pad the app runs offline on purpose (the add panel's preview, marked PREVIEW ONLY) says "preview: not
driving the robot" instead of "link down": the app tells by setting ``model.dry_run = True`` (an
attribute the model need not define; absent means a real widget).

Painting: what stays put while a finger drives (the background, the pad's disc and rings, the axes, the
axis labels) is painted once into two cached pixmaps at the widget's device pixel ratio and repainted
only when the size, ratio, ring colour, dead zone, axes, palette or font change; each paint draws
those, the trail, the knob and the status line (a 300x260 pad held still, offscreen: about 0.26 ms of
CPU per repaint instead of 0.85 ms).
"""

from __future__ import annotations

import math
import re
import time
from typing import Any

from qtpy import QtCore, QtGui, QtWidgets

from .teleop import TeleopValue, axis_words

TRAIL_S = 0.6
#: the status line of a pad the app runs offline on purpose (the add panel's preview)
PREVIEW_TEXT = "preview: not driving the robot"


class TeleopView(QtWidgets.QWidget):
    def __init__(self, model: Any, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.model = model
        #: the status line under the pad as last painted (elided to the width; tests, accessibility)
        self.status_shown = ""
        self._touch_id: int | None = None
        self._dead_touch = False  # focus was lost mid-touch: ignore this touch until it ends
        self._mouse_down = False
        self._finger: QtCore.QPointF | None = None
        self._trail: list[tuple[float, QtCore.QPointF]] = []
        self._value = TeleopValue()
        self._state: Any = None
        self._layers: tuple[QtGui.QPixmap, QtGui.QPixmap] | None = None
        self._layers_key: tuple[Any, ...] | None = None
        #: how often the cached backdrop and labels were painted (tests, diagnostics)
        self.layer_builds = 0
        #: the axis labels as last painted: (vertical words, its field or "", horizontal words, its field or "")
        self.axis_labels: tuple[str, str, str, str] = ("", "", "", "")
        self.setAttribute(QtCore.Qt.WidgetAttribute.WA_AcceptTouchEvents, True)
        # for assistive technology: an area to drag in (the app names it after the widget's title)
        self.setProperty("accessibleRole", "Canvas")
        self.setAccessibleDescription(f"drag to drive {getattr(model.binding, 'name', '')}; lift to stop")
        self.setFocusPolicy(QtCore.Qt.FocusPolicy.StrongFocus)
        self.setMinimumSize(120, 120)
        self.setSizePolicy(QtWidgets.QSizePolicy.Policy.Expanding, QtWidgets.QSizePolicy.Policy.Expanding)

    # -- geometry -----------------------------------------------------------------------------------------
    def pad(self) -> tuple[QtCore.QPointF, float]:
        """Centre and radius of the pad (leaving room for the labels)."""
        line = QtGui.QFontMetrics(self._small_font()).height()
        # room for the axis labels (one row, or two: see label_rows) and the status line (the text size's)
        top, bottom = self.label_rows() * line + 2, line + 6
        r = max(10.0, min(self.width() - 8, self.height() - top - bottom) / 2 - 4)
        return QtCore.QPointF(self.width() / 2, top + (self.height() - top - bottom) / 2), r

    def _axis_words(self) -> tuple[str, str]:
        """The two axis labels whole: ("↑ forward", "turn right →"), "" for an axis not driven."""
        h_axis, v_axis = self.model.axes() if hasattr(self.model, "axes") else ("", "")
        v_word = "↑ " + (axis_words(v_axis) or v_axis) if v_axis else ""
        h_word = (axis_words(h_axis) or h_axis) + " →" if h_axis else ""
        return v_word, h_word

    def label_rows(self) -> int:
        """1, or 2 when the two axis labels do not fit whole side by side, each in its half of the row (a
        large text size, a narrow pad): then the vertical axis's on the first row (left), the horizontal
        axis's under it (right), each whole if the pad is wide enough for it alone. Fixed by the axes, the
        width and the text size, never by what the pad is doing: the pad does not move under a driving
        finger."""
        v_word, h_word = self._axis_words()
        if not (v_word and h_word):
            return 1
        fm = QtGui.QFontMetricsF(self._small_font())
        half = (self.width() - 8) / 2 - 4  # one row: each word in its half (_paint_labels)
        return 1 if max(fm.horizontalAdvance(v_word), fm.horizontalAdvance(h_word)) <= half else 2

    def to_axes(self, pos: QtCore.QPointF) -> tuple[float, float]:
        c, r = self.pad()
        return (pos.x() - c.x()) / r, -(pos.y() - c.y()) / r

    # -- state ---------------------------------------------------------------------------------------------
    def refresh(self, state: Any) -> None:
        self._state = state
        if isinstance(state.value, TeleopValue):
            self._value = state.value
        self.update()

    # -- input -------------------------------------------------------------------------------------------
    def _press(self, pos: QtCore.QPointF) -> None:
        self._finger = pos
        self._trail = [(time.monotonic(), pos)]
        self.model.set_axes(*self.to_axes(pos))
        self.update()

    def _move(self, pos: QtCore.QPointF) -> None:
        self._finger = pos
        now = time.monotonic()
        self._trail.append((now, pos))
        self._trail = [(t, p) for t, p in self._trail if now - t < TRAIL_S][-40:]
        self.model.set_axes(*self.to_axes(pos))
        self.update()

    def _lift(self, reason: str = "released") -> None:
        self._finger = None
        self._trail = []
        self.model.release(reason)
        self.update()

    def event(self, e: QtCore.QEvent) -> bool:
        t = e.type()
        T = QtCore.QEvent.Type
        if t in (T.TouchBegin, T.TouchUpdate, T.TouchEnd, T.TouchCancel):
            self._touch(e)
            e.accept()
            return True
        return super().event(e)

    def _touch(self, e: Any) -> None:
        T = QtCore.QEvent.Type
        S = QtGui.QEventPoint.State
        if e.type() == T.TouchCancel:
            if self._touch_id is not None and not self._dead_touch:
                self._lift("touch cancelled")
            self._touch_id = None
            self._dead_touch = False
            return
        for p in e.points():
            if self._touch_id is None and p.state() == S.Pressed:
                self._touch_id = p.id()
                self._dead_touch = False
                self._press(p.position())
            elif p.id() == self._touch_id:
                if p.state() == S.Released:
                    self._touch_id = None
                    if self._dead_touch:
                        self._dead_touch = False
                        self.model.release("released")  # unlock for the next touch
                    else:
                        self._lift()
                elif not self._dead_touch and p.state() == S.Updated:
                    self._move(p.position())
        if e.type() == T.TouchEnd and self._touch_id is not None:
            self._touch_id = None
            if not self._dead_touch:
                self._lift()
            self._dead_touch = False

    def mousePressEvent(self, e: QtGui.QMouseEvent) -> None:  # noqa: N802
        if e.button() == QtCore.Qt.MouseButton.LeftButton and self._touch_id is None:
            self._mouse_down = True
            self._press(e.position())

    def mouseMoveEvent(self, e: QtGui.QMouseEvent) -> None:  # noqa: N802
        if self._mouse_down:
            self._move(e.position())

    def mouseReleaseEvent(self, e: QtGui.QMouseEvent) -> None:  # noqa: N802
        if self._mouse_down and e.button() == QtCore.Qt.MouseButton.LeftButton:
            self._mouse_down = False
            self._lift()

    def _lose(self, reason: str) -> None:
        if self._finger is not None or self._mouse_down:
            self._mouse_down = False
            if self._touch_id is not None:
                self._dead_touch = True
            self._finger = None
            self._trail = []
            self.model.release(reason)
            self.update()

    def focusOutEvent(self, e: QtGui.QFocusEvent) -> None:  # noqa: N802
        if e.reason() == QtCore.Qt.FocusReason.ActiveWindowFocusReason or not self.window().isActiveWindow():
            self._lose("focus lost")
        super().focusOutEvent(e)

    def changeEvent(self, e: QtCore.QEvent) -> None:  # noqa: N802
        if e.type() == QtCore.QEvent.Type.ActivationChange and not self.isActiveWindow():
            self._lose("focus lost")
        super().changeEvent(e)

    def hideEvent(self, e: QtGui.QHideEvent) -> None:  # noqa: N802
        self._lose("hidden")
        super().hideEvent(e)

    # -- painting --------------------------------------------------------------------------------------
    def paintEvent(self, _e: QtGui.QPaintEvent) -> None:  # noqa: N802
        backdrop, labels = self._cached_layers()
        p = QtGui.QPainter(self)
        p.drawPixmap(QtCore.QPointF(0, 0), backdrop)
        p.setRenderHint(QtGui.QPainter.RenderHint.Antialiasing, True)
        c, r = self.pad()
        # trail and knob
        now = time.monotonic()
        for i in range(1, len(self._trail)):
            t0, a = self._trail[i - 1]
            _t1, b = self._trail[i]
            alpha = max(0, int(200 * (1 - (now - t0) / TRAIL_S)))
            p.setPen(QtGui.QPen(QtGui.QColor(70, 160, 255, alpha), 4, QtCore.Qt.PenStyle.SolidLine,
                                QtCore.Qt.PenCapStyle.RoundCap))
            p.drawLine(a, b)
        knob = c
        if self._finger is not None:
            fx, fy = self.to_axes(self._finger)
            d = math.hypot(fx, fy)
            if d > 1:
                fx, fy = fx / d, fy / d
            knob = QtCore.QPointF(c.x() + fx * r, c.y() - fy * r)
            p.setPen(QtGui.QPen(QtGui.QColor(70, 160, 255, 140), 2))
            p.drawLine(c, knob)
        kr = max(10.0, r * 0.18)
        p.setPen(QtGui.QPen(QtGui.QColor(30, 60, 110), 2))
        p.setBrush(QtGui.QColor(70, 160, 255) if self._finger is not None else QtGui.QColor(150, 158, 170))
        p.drawEllipse(knob, kr, kr)
        p.drawPixmap(QtCore.QPointF(0, 0), labels)  # the axis labels over the knob, never under it
        # status line
        font = self._small_font()
        p.setFont(font)
        p.setPen(self.palette().color(QtGui.QPalette.ColorRole.WindowText))
        line = p.fontMetrics().height()
        room = QtCore.QRectF(4, self.height() - line - 2, self.width() - 8, line)
        # a narrow pad (a fleet tile) shows the line's beginning and "…", never both ends cut off
        self.status_shown = fit_status(self.status_text(), p.fontMetrics(), int(room.width()))
        p.drawText(room, QtCore.Qt.AlignmentFlag.AlignCenter, self.status_shown)
        p.end()

    def _small_font(self) -> QtGui.QFont:
        """The labels' and the status line's font: the widget's, 0.8 times (at least 10 px), so it follows
        the app's text size (the theme gives the font in pixels: its point size reads -1)."""
        font = QtGui.QFont(self.font())
        px = font.pixelSize() if font.pixelSize() > 0 else QtGui.QFontInfo(font).pixelSize()
        font.setPixelSize(max(10, round(px * 0.8)))
        return font

    def _cached_layers(self) -> tuple[QtGui.QPixmap, QtGui.QPixmap]:
        """The parts that stay put while a finger drives, painted once: the backdrop (background, the pad's
        disc and ring, dead-zone ring, axes) and the axis labels (transparent, drawn over the knob).
        Repainted only when what they show changed: the size, the device pixel ratio, the ring's colour
        (driving or not), the dead zone, the axes, the palette (a theme or style change) or the font."""
        pal = self.palette()
        h_axis, v_axis = self.model.axes() if hasattr(self.model, "axes") else ("", "")
        key = (self.width(), self.height(), self.devicePixelRatioF(), bool(self._value.active),
               float(getattr(self.model.settings, "dead_zone", 0.0)), h_axis, v_axis, pal.cacheKey(),
               self.font().key())
        if self._layers is None or key != self._layers_key:
            self._layers = (self._paint_backdrop(pal), self._paint_labels(pal, h_axis, v_axis))
            self._layers_key = key
            self.layer_builds += 1
        return self._layers

    def _new_layer(self) -> QtGui.QPixmap:
        ratio = self.devicePixelRatioF()
        pm = QtGui.QPixmap(max(1, math.ceil(self.width() * ratio - 1e-6)),
                           max(1, math.ceil(self.height() * ratio - 1e-6)))
        pm.setDevicePixelRatio(ratio)
        return pm

    def _paint_backdrop(self, pal: QtGui.QPalette) -> QtGui.QPixmap:
        pm = self._new_layer()
        pm.fill(pal.color(QtGui.QPalette.ColorRole.Window))
        p = QtGui.QPainter(pm)
        p.setRenderHint(QtGui.QPainter.RenderHint.Antialiasing, True)
        c, r = self.pad()
        ring = QtGui.QColor(70, 160, 255) if self._value.active else QtGui.QColor(120, 128, 140)
        p.setPen(QtGui.QPen(ring, 2))
        p.setBrush(QtGui.QColor(ring.red(), ring.green(), ring.blue(), 28))
        p.drawEllipse(c, r, r)
        dz = float(getattr(self.model.settings, "dead_zone", 0.0))
        if dz > 0:
            p.setPen(QtGui.QPen(QtGui.QColor(120, 128, 140, 160), 1, QtCore.Qt.PenStyle.DashLine))
            p.setBrush(QtCore.Qt.BrushStyle.NoBrush)
            p.drawEllipse(c, r * dz, r * dz)
        p.setPen(QtGui.QPen(QtGui.QColor(120, 128, 140, 120), 1))
        p.drawLine(QtCore.QPointF(c.x() - r, c.y()), QtCore.QPointF(c.x() + r, c.y()))
        p.drawLine(QtCore.QPointF(c.x(), c.y() - r), QtCore.QPointF(c.x(), c.y() + r))
        p.end()
        return pm

    def _paint_labels(self, pal: QtGui.QPalette, h_axis: str, v_axis: str) -> QtGui.QPixmap:
        """What moving the finger does, in words ("↑ forward", "turn right →"), each with the field it
        drives in small print beside it ("linear.x"); the small print goes first when the pad is too narrow
        for both; an axis without words shows its field. On one row, or on two when the words do not fit
        whole side by side (``label_rows``); each row as tall as the text."""
        pm = self._new_layer()
        pm.fill(QtCore.Qt.GlobalColor.transparent)
        p = QtGui.QPainter(pm)
        p.setRenderHint(QtGui.QPainter.RenderHint.Antialiasing, True)
        big, small = self._small_font(), self._fine_font()
        fm_big, fm_small = QtGui.QFontMetricsF(big), QtGui.QFontMetricsF(small)
        line = QtGui.QFontMetrics(big).height()
        rows = self.label_rows()
        width = self.width() - 8
        # each label in its half of the row when they share it: "…" rather than overlap
        room = width / 2 - 4 if v_axis and h_axis and rows == 1 else width
        elide = QtCore.Qt.TextElideMode.ElideRight
        v_full, h_full = self._axis_words()
        v_word = fm_elide(big, v_full, elide, room) if v_axis else ""
        h_word = fm_elide(big, h_full, elide, room) if h_axis else ""
        v_fine = v_axis if v_axis and axis_words(v_axis) else ""
        h_fine = h_axis if h_axis and axis_words(h_axis) else ""
        gap = 6.0

        def fits(word: str, fine_text: str) -> bool:
            return fm_big.horizontalAdvance(word) + gap + fm_small.horizontalAdvance(fine_text) + 6 <= width

        if rows == 1:  # room for the fields in small print too
            need = (fm_big.horizontalAdvance(v_word) + fm_big.horizontalAdvance(h_word) + 2 * gap
                    + fm_small.horizontalAdvance(v_fine) + fm_small.horizontalAdvance(h_fine) + 12)
            v_fine_shown = v_fine if need <= width else ""
            h_fine_shown = h_fine if need <= width else ""
        else:
            v_fine_shown = v_fine if fits(v_word, v_fine) else ""
            h_fine_shown = h_fine if fits(h_word, h_fine) else ""
        self.axis_labels = (v_word, v_fine_shown, h_word, h_fine_shown)
        text_colour = pal.color(QtGui.QPalette.ColorRole.WindowText)
        muted = QtGui.QColor(text_colour)
        muted.setAlpha(150)
        mid = QtCore.Qt.AlignmentFlag.AlignVCenter
        left, right = QtCore.Qt.AlignmentFlag.AlignLeft | mid, QtCore.Qt.AlignmentFlag.AlignRight | mid
        x0, x1 = 4.0, self.width() - 4.0
        v_top, h_top = 1.0, 1.0 + (line if rows == 2 else 0)
        if v_word:
            p.setFont(big)
            p.setPen(text_colour)
            p.drawText(QtCore.QRectF(x0, v_top, width, line), left, v_word)
            if v_fine_shown:
                p.setFont(small)
                p.setPen(muted)
                p.drawText(QtCore.QRectF(x0 + fm_big.horizontalAdvance(v_word) + gap, v_top, width, line), left,
                           v_fine_shown)
        if h_word:
            p.setFont(big)
            p.setPen(text_colour)
            p.drawText(QtCore.QRectF(x0, h_top, width, line), right, h_word)
            if h_fine_shown:
                p.setFont(small)
                p.setPen(muted)
                end = x1 - fm_big.horizontalAdvance(h_word) - gap
                p.drawText(QtCore.QRectF(x0, h_top, end - x0, line), right, h_fine_shown)
        p.end()
        return pm

    def _fine_font(self) -> QtGui.QFont:
        """The small print beside the axis words: the labels' font, 0.65 times (at least 8 px). In
        pixels, as ``_small_font`` gives it: its point size reads -1, which had left the small print at the
        6 pt floor at every text size."""
        font = QtGui.QFont(self._small_font())
        font.setPixelSize(max(8, round(font.pixelSize() * 0.65)))
        return font

    @property
    def dry_run(self) -> bool:
        """Whether the app runs this pad offline on purpose (a preview): nothing it does reaches a robot."""
        return bool(self.model.dry_run)

    def status_text(self) -> str:
        """The line under the pad: what the pad is doing, or why it is not driving."""
        v = self._value
        st = self._state
        if self.dry_run:
            return PREVIEW_TEXT
        if st is not None and st.link_down:
            return "link down: stopped"
        if st is not None and st.error:
            return st.error
        if v.commands_held:  # nothing is sent: it would wait behind the robot's unanswered call
            busy = v.commands_held.rpartition("busy with ")[2] if "busy with " in v.commands_held else ""
            return f"⚠ not sending: bridge busy with {busy}" if busy else f"⚠ {v.commands_held}: not sending"
        if v.locked:
            return f"stopped ({v.reason}): lift your finger"
        if v.unheard:  # nothing moves: never animate as if the robot drove
            return f"⚠ {v.unheard}"
        held = f" · {v.held}" if v.held else ""  # what holds the command below the pad's own maximum
        if v.active:  # what is sent, after the envelope and the speed limit; the vertical axis (forward) first
            axes = self.model.axes() if hasattr(self.model, "axes") else ("", "")
            up = axes[1].lstrip("-")
            command = sorted(v.command, key=lambda pv: not (up and pv[0].endswith(up)))
            parts = [f"{path.rsplit('.', 2)[-2] + '.' if '.' in path else ''}{path.rsplit('.', 1)[-1]} "
                     f"{val:+.2f}" for path, val in command]
            return ("  ".join(parts) or "driving") + held
        if v.held:  # the limit matters more than the rate on a narrow pad
            return f"touch to drive {v.held}"
        rate = getattr(self.model.settings, "rate_hz", 0)
        return f"idle · touch to drive ({rate:g} Hz)"


_TRAILING_REMARK = re.compile(r"\s*\([^()]*\)$")


def fit_status(text: str, fm: QtGui.QFontMetrics, width: int) -> str:
    """The status line as it fits ``width``: whole; else without its closing remark in brackets ("touch to
    drive ≤ 1.5 m/s (safety envelope)" -> "... ≤ 1.5 m/s", "idle · touch to drive (10 Hz)" -> "idle · touch
    to drive"), which cuts no word of what the pad does; else, for a line that gives a limit, the limit
    alone ("≤ 1.5 m/s": on a narrow pad it matters more than the invitation to touch); else its beginning
    and "…"."""
    if fm.horizontalAdvance(text) <= width:
        return text
    short = _TRAILING_REMARK.sub("", text) or text
    if fm.horizontalAdvance(short) <= width:
        return short
    limit = short[short.find("≤"):] if "≤" in short else ""
    if limit and fm.horizontalAdvance(limit) <= width:
        return limit
    return fm.elidedText(short, QtCore.Qt.TextElideMode.ElideRight, width)


def fm_elide(font: QtGui.QFont, text: str, mode: QtCore.Qt.TextElideMode, width: float) -> str:
    """``text`` elided to ``width`` pixels in ``font``."""
    return QtGui.QFontMetricsF(font).elidedText(text, mode, width)
