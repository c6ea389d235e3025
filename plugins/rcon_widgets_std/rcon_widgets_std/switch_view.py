"""Switch's Qt view: one big toggle button with the state's text, and a line for the server's reply."""

from __future__ import annotations

from typing import Any

from qtpy import QtCore, QtWidgets

from rcon_core.plugins import Role

from .view_common import BAD, MUTED, OK, Caption, fit_caption, vbox


class SwitchView(QtWidgets.QWidget):
    def __init__(self, model: Any, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.model = model
        layout = vbox(self)
        self.button = QtWidgets.QPushButton("?")
        self.button.setCheckable(True)
        self.button.setSizePolicy(QtWidgets.QSizePolicy.Policy.Expanding, QtWidgets.QSizePolicy.Policy.Expanding)
        self.button.setEnabled(model.binding.role is not Role.SUBSCRIBE)
        self.button.clicked.connect(self._clicked)
        layout.addWidget(self.button, 1)
        self.reply = Caption("")
        self._reply: tuple[str, str] | None = None  # (text, colour) shown in the reply line
        self.reply.setAlignment(QtCore.Qt.AlignmentFlag.AlignCenter)
        layout.addWidget(self.reply)
        self._paint(None, "", None)

    def _clicked(self, checked: bool) -> None:
        self.model.set(bool(checked))
        self.refresh(self.model.state)

    def refresh(self, state: Any) -> None:
        v = state.value
        on = getattr(v, "on", None)
        self._paint(on, getattr(v, "reply", ""), state.error, busy=getattr(v, "busy", False),
                    wanted=getattr(v, "wanted", None))

    def _paint(self, on: bool | None, reply: str, error: str | None, busy: bool = False,
               wanted: bool | None = None) -> None:
        s = self.model.settings
        self.button.blockSignals(True)
        self.button.setChecked(bool(on))
        self.button.blockSignals(False)
        if busy:
            self.button.setText(f"{s.on_text if wanted else s.off_text}…")
        elif on is None:
            self.button.setText("?")
        else:
            self.button.setText(s.on_text if on else s.off_text)
        if error:
            shown = (error, BAD)
        elif busy:
            shown = ("asking the robot…", MUTED)
        elif reply:
            shown = (reply, OK)
        else:
            shown = ("", MUTED)
        if shown != self._reply:  # show_text sets a style sheet (a re-polish): only when it changes
            self._reply = shown
            self.reply.show_text(*shown)
            fit_caption(self, self.button, self.reply)

    def resizeEvent(self, event: Any) -> None:  # noqa: N802 - Qt override
        super().resizeEvent(event)
        fit_caption(self, self.button, self.reply)  # too small for both: the reply becomes the tooltip
