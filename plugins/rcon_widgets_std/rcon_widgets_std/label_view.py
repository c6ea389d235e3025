"""Label's Qt view: the formatted value in large type, its age underneath; greyed out when stale.

A label may repaint up to 60 times a second: the value is a :class:`FitLabel` (painted directly, not a
selectable QLabel, which would lay out a text document per value), and a refresh only touches what
changed. A long value shrinks its font to fit the frame, eliding only as a last resort; the context
menu's *Copy value* puts the full text on the clipboard (the value is not mouse-selectable).
"""

from __future__ import annotations

from typing import Any

from qtpy import QtCore, QtGui, QtWidgets

from .view_common import MUTED, STALE, Caption, FitLabel, age_text, age_timer, vbox


class LabelView(QtWidgets.QWidget):
    def __init__(self, model: Any, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.model = model
        layout = vbox(self)
        self.value = FitLabel("–", 30, True)
        self.value.setSizePolicy(QtWidgets.QSizePolicy.Policy.Ignored, QtWidgets.QSizePolicy.Policy.Expanding)
        self._multiline = False
        self._age_colour = MUTED  # Caption starts muted
        layout.addWidget(self.value, 1)
        self.age = Caption("no data yet")
        self.age.setAlignment(QtCore.Qt.AlignmentFlag.AlignCenter)
        layout.addWidget(self.age)
        self.copy_action = QtGui.QAction("Copy value", self)
        self.copy_action.triggered.connect(self.copy_value)
        self.addAction(self.copy_action)
        self.setContextMenuPolicy(QtCore.Qt.ContextMenuPolicy.ActionsContextMenu)
        self._timer = age_timer(self, self._tick)

    def copy_value(self) -> None:
        """Put the value's full text on the clipboard (with units, as shown; a string shown shortened:
        all of it)."""
        v = self.model.state.value
        raw = getattr(v, "raw", None)
        whole = raw if isinstance(raw, str) and len(raw) > len(self.value.text()) else self.value.text()
        QtWidgets.QApplication.clipboard().setText(whole)

    def refresh(self, state: Any) -> None:
        v = state.value
        if v is not None:
            multiline = "\n" in v.text
            self._multiline = multiline or len(v.text) > 24
            align = ((QtCore.Qt.AlignmentFlag.AlignLeft | QtCore.Qt.AlignmentFlag.AlignTop) if multiline
                     else QtCore.Qt.AlignmentFlag.AlignCenter)
            self.value.setAlignment(align)
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
            self.value.set_style(px, MUTED, bold)
        else:
            self._show_caption(age_text(state.age), MUTED)
            self.value.set_style(px, "", bold)

    def _show_caption(self, text: str, colour: str) -> None:
        """What ``Caption.show_text`` shows (it skips what did not change)."""
        self.age.show_text(text, colour)
