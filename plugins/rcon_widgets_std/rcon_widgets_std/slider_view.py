"""Slider's Qt view: a horizontal slider with the value above it and the range underneath.

Publish: dragging calls ``model.drag`` (publishes only in continuous mode, rate-limited), letting go
``model.release`` (always publishes). Tapping the track jumps the handle there (and drags from there).
Until something is sent or heard the value reads "not set" (the handle rests at the start value).
Subscribe: the handle follows the robot and cannot be moved.
"""

from __future__ import annotations

from typing import Any

from qtpy import QtCore, QtGui, QtWidgets

from rcon_core.plugins import Role

from .common import format_number
from .slider import NumberRange, SliderModel
from .view_common import STALE, Caption, style_text, vbox

#: what a publish slider's value reads before anything was sent or heard on its topic
NOT_SET = "not set"


class TapSlider(QtWidgets.QSlider):
    """A slider whose track jumps to where it is tapped (a plain QSlider moves one page step), then drags
    from there: the press puts the slider down *before* moving it, so the move is a drag (published only
    in continuous mode) and letting go is the release (``sliderReleased``), exactly as for a handle drag."""

    def mousePressEvent(self, event: QtGui.QMouseEvent) -> None:  # noqa: N802 - Qt override
        if event.button() == QtCore.Qt.MouseButton.LeftButton and self.isEnabled():
            value = self.value_at(event.position())
            if value is not None:
                self.setSliderDown(True)  # first: the jump below is part of a drag
                self.setValue(value)
        super().mousePressEvent(event)  # the handle is now under the finger: Qt starts dragging it

    def value_at(self, pos: QtCore.QPointF) -> int | None:
        """The value under ``pos`` on the track, or None when ``pos`` is on the handle itself."""
        opt = QtWidgets.QStyleOptionSlider()
        self.initStyleOption(opt)
        style = self.style()
        cc = QtWidgets.QStyle.ComplexControl.CC_Slider
        handle = style.subControlRect(cc, opt, QtWidgets.QStyle.SubControl.SC_SliderHandle, self)
        if handle.contains(pos.toPoint()):
            return None
        groove = style.subControlRect(cc, opt, QtWidgets.QStyle.SubControl.SC_SliderGroove, self)
        if self.orientation() == QtCore.Qt.Orientation.Horizontal:
            span, at = groove.width() - handle.width(), pos.x() - groove.x() - handle.width() / 2
        else:
            span, at = groove.height() - handle.height(), pos.y() - groove.y() - handle.height() / 2
        return QtWidgets.QStyle.sliderValueFromPosition(
            self.minimum(), self.maximum(), round(min(max(at, 0), max(span, 1))), max(span, 1), opt.upsideDown)


class SliderView(QtWidgets.QWidget):
    def __init__(self, model: SliderModel, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.model = model
        self.publishing = model.binding.role is Role.PUBLISH
        layout = vbox(self)
        self.value = QtWidgets.QLabel("–")
        self.value.setAlignment(QtCore.Qt.AlignmentFlag.AlignCenter)
        style_text(self.value, 22)
        self._stale = False  # what the value's style shows
        layout.addWidget(self.value)
        self.slider = TapSlider(QtCore.Qt.Orientation.Horizontal)
        self.slider.setEnabled(self.publishing)
        self.slider.setAccessibleDescription(f"{model.binding.name}: slide to set" if self.publishing
                                             else f"{model.binding.name}, as the robot reports it")
        self.slider.setMinimumHeight(32)
        layout.addWidget(self.slider)
        ends = QtWidgets.QHBoxLayout()
        self.low, self.high = Caption(), Caption()
        self.high.setAlignment(QtCore.Qt.AlignmentFlag.AlignRight)
        ends.addWidget(self.low)
        ends.addWidget(self.high)
        layout.addLayout(ends)
        self._range: NumberRange = model.range
        self._set_range(self._range)
        # nothing sent or received yet: the handle rests at the start value, the value says "not set"
        resting = model.resting if self.publishing else None
        self.slider.blockSignals(True)
        self.slider.setValue(self.position_of(resting if resting is not None else self._range.coerce(0)))
        self.slider.blockSignals(False)
        if self.publishing:
            self._show_unset()
        self.slider.valueChanged.connect(self._moved)
        self.slider.sliderReleased.connect(self._released)

    def resizeEvent(self, event: QtGui.QResizeEvent) -> None:  # noqa: N802 - Qt override
        """The range's ends show only when the value, the slider and they all fit (large text, a short
        frame): never squeezed over one another; the slider's tooltip then says the range."""
        super().resizeEvent(event)
        layout = self.layout()
        if layout is None:
            return
        m, spacing = layout.contentsMargins(), max(0, layout.spacing())
        need = (self.value.sizeHint().height() + self.slider.minimumHeight() + self.low.sizeHint().height()
                + 2 * spacing + m.top() + m.bottom())
        show = self.height() >= need
        for end in (self.low, self.high):
            if end.isHidden() == show:
                end.setVisible(show)
        tip = "" if show else f"{self.low.text()} … {self.high.text()}"
        if self.slider.toolTip() != tip:
            self.slider.setToolTip(tip)

    # -- range <-> positions ------------------------------------------------------------------------
    def _apply_range(self) -> None:
        r = self.model.range
        if r == self._range:
            return
        self._range = r
        self._set_range(r)

    def _set_range(self, r: NumberRange) -> None:
        self.slider.blockSignals(True)
        self.slider.setRange(0, min(r.steps, 100000))
        self.slider.blockSignals(False)
        units = getattr(self.model.settings, "units", "")
        self.low.show_text(f"{self._fmt(r.minimum)} {units}".strip())
        held = "envelope" in r.why
        # a range the robot's safety envelope holds in says so at its ends: what the slider can send
        self.high.show_text(f"{self._fmt(r.maximum)} {units}".strip() + (" · envelope" if held else ""),
                            tooltip=f"limited to {r.why}" if r.clamped else "")

    def _fmt(self, v: float) -> str:
        return format_number(v, -1 if self._range.integer else self.model.settings.decimals)

    def position_value(self, pos: int | None = None) -> float:
        r = self._range
        pos = self.slider.value() if pos is None else pos
        return r.minimum + (r.maximum - r.minimum) * pos / max(1, self.slider.maximum())

    def position_of(self, value: float) -> int:
        """The slider position (0..slider.maximum()) that shows ``value``."""
        r = self._range
        span = (r.maximum - r.minimum) or 1
        return round((float(value) - r.minimum) / span * self.slider.maximum())

    # -- user -----------------------------------------------------------------------------------------
    def _moved(self, pos: int) -> None:
        if not self.publishing:
            return
        v = self.position_value(pos)
        shown = self.model.drag(v) if self.slider.isSliderDown() else self.model.release(v)
        self._show(shown)

    def _released(self) -> None:
        if self.publishing:
            self._show(self.model.release(self.position_value()))

    def _show(self, v: float) -> None:
        units = getattr(self.model.settings, "units", "")
        text = f"{self._fmt(v)} {units}".strip()
        if text != self.value.text():
            self.value.setText(text)
            self.value.setToolTip("")

    def _show_unset(self) -> None:
        """Nothing was sent or heard on the topic: no number that could pass for the robot's setting.
        Inside a Compound the number the compound will send (the start value), said as such."""
        if self.model.in_compound:
            self._show(self.model.resting)
            self.value.setToolTip("the compound sends this value (the start value) until you move the slider")
            return
        if self.value.text() != NOT_SET:
            self.value.setText(NOT_SET)
            self.value.setToolTip(f"nothing sent or heard on {self.model.binding.name} yet; "
                                  "move the slider to set it")

    # -- state ----------------------------------------------------------------------------------------
    def refresh(self, state: Any) -> None:
        self._apply_range()
        v = state.value
        if isinstance(v, (int, float)) and not isinstance(v, bool):
            if not self.slider.isSliderDown():
                self.slider.blockSignals(True)
                self.slider.setValue(self.position_of(min(self._range.maximum, max(self._range.minimum, v))))
                self.slider.blockSignals(False)
            self._show(v)
        elif v is None and self.publishing and not self.slider.isSliderDown():
            self._show_unset()
        stale = state.stale and not self.publishing
        if stale != self._stale:  # a style sheet re-polishes the label: only when staleness flips
            self._stale = stale
            style_text(self.value, 22, STALE if stale else "")
            self.value.setToolTip("stale: no new value" if stale else "")
