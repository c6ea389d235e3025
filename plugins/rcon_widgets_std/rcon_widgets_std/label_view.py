"""Label's Qt view: the formatted value in large type, its age underneath; greyed out when stale.

A label may repaint up to 60 times a second: a refresh only touches what changed (text, alignment,
tooltip), and re-styles (a style sheet, which re-polishes the label) only when stale/multiline flips.
"""

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
        self._align = QtCore.Qt.AlignmentFlag.AlignCenter
        self._style: tuple[int, str, bool] | None = None  # (px, colour, bold) last given to style_text
        self._age_colour = MUTED  # Caption starts muted
        layout.addWidget(self.value, 1)
        self.age = Caption("no data yet")
        self.age.setAlignment(QtCore.Qt.AlignmentFlag.AlignCenter)
        layout.addWidget(self.age)
        self._set_style(30, "", True)
        self._timer = age_timer(self, self._tick)

    def refresh(self, state: Any) -> None:
        v = state.value
        if v is not None:
            multiline = "\n" in v.text
            self._multiline = multiline or len(v.text) > 24
            align = ((QtCore.Qt.AlignmentFlag.AlignLeft | QtCore.Qt.AlignmentFlag.AlignTop) if multiline
                     else QtCore.Qt.AlignmentFlag.AlignCenter)
            if align != self._align:
                self._align = align
                self.value.setAlignment(align)
            if v.text != self.value.text():
                self.value.setText(v.text)
            tip = v.text if multiline else ""
            if tip != self.value.toolTip():
                self.value.setToolTip(tip)
        self._show_age(state)

    def _tick(self) -> None:
        self._show_age(self.model.state)

    def _show_age(self, state: Any) -> None:
        px, bold = (14, False) if self._multiline else (30, True)
        if state.stale:
            self._show_caption(f"STALE · {age_text(state.age)}", STALE)
            self._set_style(px, MUTED, bold)
        else:
            self._show_caption(age_text(state.age), MUTED)
            self._set_style(px, "", bold)

    def _show_caption(self, text: str, colour: str) -> None:
        """What ``Caption.show_text`` shows, without re-styling when the colour is unchanged."""
        if colour != self._age_colour:
            self._age_colour = colour
            self.age.set_colour(colour)
        if text != self.age.text():
            self.age.setText(text)
            self.age.setToolTip(text)

    def _set_style(self, px: int, colour: str, bold: bool) -> None:
        if (px, colour, bold) != self._style:
            self._style = (px, colour, bold)
            style_text(self.value, px, colour, bold)
