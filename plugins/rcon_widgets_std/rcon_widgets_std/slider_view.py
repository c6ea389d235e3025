"""Slider's Qt view: a horizontal slider with the value above it and the range underneath.

Publish: dragging calls ``model.drag`` (publishes only in continuous mode, rate-limited), letting go
``model.release`` (always publishes). Subscribe: the handle follows the robot and cannot be moved.
"""

from __future__ import annotations

from typing import Any

from qtpy import QtCore, QtWidgets

from rcon_core.plugins import Role

from .common import format_number
from .view_common import STALE, Caption, style_text, vbox


class SliderView(QtWidgets.QWidget):
    def __init__(self, model: Any, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.model = model
        self.publishing = model.binding.role is Role.PUBLISH
        layout = vbox(self)
        self.value = QtWidgets.QLabel("–")
        self.value.setAlignment(QtCore.Qt.AlignmentFlag.AlignCenter)
        style_text(self.value, 22)
        self._stale = False  # what the value's style shows
        layout.addWidget(self.value)
        self.slider = QtWidgets.QSlider(QtCore.Qt.Orientation.Horizontal)
        self.slider.setEnabled(self.publishing)
        self.slider.setMinimumHeight(32)
        layout.addWidget(self.slider)
        ends = QtWidgets.QHBoxLayout()
        self.low, self.high = Caption(), Caption()
        self.high.setAlignment(QtCore.Qt.AlignmentFlag.AlignRight)
        ends.addWidget(self.low)
        ends.addWidget(self.high)
        layout.addLayout(ends)
        self._range = None
        self._apply_range()
        self.slider.blockSignals(True)  # nothing sent or received yet: rest at 0 (or the nearest end)
        self.slider.setValue(self._position(self._range.coerce(0)))
        self.slider.blockSignals(False)
        self.slider.valueChanged.connect(self._moved)
        self.slider.sliderReleased.connect(self._released)

    # -- range <-> positions ------------------------------------------------------------------------
    def _apply_range(self) -> None:
        r = self.model.range
        if r == self._range:
            return
        self._range = r
        self.slider.blockSignals(True)
        self.slider.setRange(0, min(r.steps, 100000))
        self.slider.blockSignals(False)
        units = getattr(self.model.settings, "units", "")
        self.low.show_text(f"{self._fmt(r.minimum)} {units}".strip())
        self.high.show_text(f"{self._fmt(r.maximum)} {units}".strip())
        if r.clamped:
            self.high.setToolTip(f"limited to what a {r.base} holds")

    def _fmt(self, v: float) -> str:
        return format_number(v, -1 if self._range and self._range.integer else self.model.settings.decimals)

    def position_value(self, pos: int | None = None) -> float:
        r = self._range
        pos = self.slider.value() if pos is None else pos
        return r.minimum + (r.maximum - r.minimum) * pos / max(1, self.slider.maximum())

    def _position(self, value: float) -> int:
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

    # -- state ----------------------------------------------------------------------------------------
    def refresh(self, state: Any) -> None:
        self._apply_range()
        v = state.value
        if isinstance(v, (int, float)) and not isinstance(v, bool):
            if not self.slider.isSliderDown():
                self.slider.blockSignals(True)
                self.slider.setValue(self._position(min(self._range.maximum, max(self._range.minimum, v))))
                self.slider.blockSignals(False)
            self._show(v)
        stale = state.stale and not self.publishing
        if stale != self._stale:  # a style sheet re-polishes the label: only when staleness flips
            self._stale = stale
            style_text(self.value, 22, STALE if stale else "")
            self.value.setToolTip("stale: no new value" if stale else "")
