"""Label's Qt view: the formatted value in large type, its age underneath; greyed out when stale."""

from __future__ import annotations

from typing import Any

from qtpy import QtCore, QtWidgets

from .view_common import MUTED, STALE, Caption, age_text, age_timer, style_text, vbox


class LabelView(QtWidgets.QWidget):
    def __init__(self, model: Any, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.model = model
        layout = vbox(self)
        self.value = QtWidgets.QLabel("–")
        self.value.setAlignment(QtCore.Qt.AlignmentFlag.AlignCenter)
        self.value.setTextInteractionFlags(QtCore.Qt.TextInteractionFlag.TextSelectableByMouse)
        self.value.setSizePolicy(QtWidgets.QSizePolicy.Policy.Ignored, QtWidgets.QSizePolicy.Policy.Expanding)
        self._multiline = False
        layout.addWidget(self.value, 1)
        self.age = Caption("no data yet")
        self.age.setAlignment(QtCore.Qt.AlignmentFlag.AlignCenter)
        layout.addWidget(self.age)
        style_text(self.value, 30)
        self._timer = age_timer(self, self._tick)

    def refresh(self, state: Any) -> None:
        v = state.value
        if v is not None:
            multiline = "\n" in v.text
            self._multiline = multiline or len(v.text) > 24
            self.value.setAlignment(
                (QtCore.Qt.AlignmentFlag.AlignLeft | QtCore.Qt.AlignmentFlag.AlignTop) if multiline
                else QtCore.Qt.AlignmentFlag.AlignCenter
            )
            self.value.setText(v.text)
            self.value.setToolTip(v.text if multiline else "")
        self._show_age(state)

    def _tick(self) -> None:
        self._show_age(self.model.state)

    def _show_age(self, state: Any) -> None:
        px, bold = (14, False) if self._multiline else (30, True)
        if state.stale:
            self.age.show_text(f"STALE · {age_text(state.age)}", STALE)
            style_text(self.value, px, MUTED, bold)
        else:
            self.age.show_text(age_text(state.age), MUTED)
            style_text(self.value, px, "", bold)
