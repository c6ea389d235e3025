"""Stepper's Qt view: − value + ; holding a button repeats (the model limits the publish rate). Until the
first step the value reads "not set" (the first step starts from the start value); inside a Compound it
shows the start value, which is what the compound sends until it is stepped."""

from __future__ import annotations

from typing import Any

from qtpy import QtCore, QtWidgets

from .common import format_number
from .slider_view import NOT_SET
from .stepper import StepperModel
from .view_common import BAD, MUTED, Caption, style_text, vbox


class StepperView(QtWidgets.QWidget):
    def __init__(self, model: StepperModel, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.model = model
        layout = vbox(self)
        row = QtWidgets.QHBoxLayout()
        self.minus = QtWidgets.QPushButton("−")
        self.plus = QtWidgets.QPushButton("+")
        for b in (self.minus, self.plus):
            b.setAutoRepeat(True)
            b.setAutoRepeatDelay(400)
            b.setAutoRepeatInterval(120)
            style_text(b, 24)
        self.value = QtWidgets.QLabel()
        self.value.setAlignment(QtCore.Qt.AlignmentFlag.AlignCenter)
        style_text(self.value, 22)
        row.addWidget(self.minus)
        row.addWidget(self.value, 1)
        row.addWidget(self.plus)
        layout.addLayout(row, 1)
        self.note = Caption("")
        self._note: tuple[str, str] | None = None  # (text, colour) shown in the note
        self.note.setAlignment(QtCore.Qt.AlignmentFlag.AlignCenter)
        layout.addWidget(self.note)
        self.minus.clicked.connect(lambda: self._show(model.down()))
        self.plus.clicked.connect(lambda: self._show(model.up()))
        # nothing sent yet: no number that passes for the robot's -- except inside a Compound, which sends the
        # number shown (the start value until stepped): there it is shown, as what will be sent
        self._show(model.current, shown=model.in_compound)
        if model.in_compound:
            self.value.setToolTip("the compound sends this value (the start value) until you step it")

    def _show(self, v: float, shown: bool = True) -> None:
        s = self.model.settings
        r = self.model.range
        text = format_number(v, -1 if r.integer else s.decimals)
        self.value.setText(f"{text} {s.units}".strip() if shown else NOT_SET)
        self.value.setToolTip("" if shown else f"nothing sent yet; the first step starts from {text} {s.units}".strip())
        self.minus.setEnabled(v > r.minimum)
        self.plus.setEnabled(v < r.maximum)

    def refresh(self, state: Any) -> None:
        if isinstance(state.value, (int, float)):
            self._show(state.value)
        r = self.model.range
        note = (state.error or f"{format_number(r.minimum)} … {format_number(r.maximum)}, "
                               f"step {format_number(r.step)}", BAD if state.error else MUTED)
        if note != self._note:  # show_text sets a style sheet (a re-polish): only when it changes
            self._note = note
            self.note.show_text(*note)
