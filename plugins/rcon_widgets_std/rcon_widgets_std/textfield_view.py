"""Text Field's Qt view. Subscribe: the data as text (read-only, selectable). Publish: a line to type
YAML/JSON (or a plain string) and a Send button; Enter sends too. Errors name the field.

Inside a Compound the line has no Send button (nothing reaches the robot until the compound's Publish):
each change is checked at once and the line below says "will send: …" or what is wrong.

The line under the input is shown only when the frame has room for both (``fit_caption``): in a frame too
short for it, it becomes the input's tooltip (errors also show as the frame's ERROR badge) instead of
being painted over the input."""

from __future__ import annotations

from typing import Any

from qtpy import QtWidgets

from rcon_core.plugins import Role

from .view_common import BAD, MUTED, OK, STALE, Caption, fit_caption, vbox


class TextFieldView(QtWidgets.QWidget):
    def __init__(self, model: Any, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.model = model
        self.publishing = model.binding.role is Role.PUBLISH
        layout = vbox(self)
        if self.publishing:
            row = QtWidgets.QHBoxLayout()
            self.edit = QtWidgets.QLineEdit()
            self.edit.setPlaceholderText(model.settings.placeholder or "YAML or JSON, e.g. {x: 1.0}")
            self.edit.returnPressed.connect(self.send)
            row.addWidget(self.edit, 1)
            self.button = None
            if model.in_compound:
                self.edit.textChanged.connect(model.set_draft)
            else:
                self.button = QtWidgets.QPushButton("Send")
                self.button.clicked.connect(self.send)
                row.addWidget(self.button)
            layout.addLayout(row)
            self.text = None
        else:
            self.text = QtWidgets.QPlainTextEdit()
            self.text.setReadOnly(True)
            self.text.setLineWrapMode(QtWidgets.QPlainTextEdit.LineWrapMode.NoWrap)
            layout.addWidget(self.text, 1)
        self.status = Caption("")
        layout.addWidget(self.status)

    def resizeEvent(self, event: Any) -> None:  # noqa: N802 - Qt override
        super().resizeEvent(event)
        if self.text is None:
            fit_caption(self, self.edit, self.status)

    def send(self) -> None:
        self.model.submit(self.edit.text())
        if not self.model.in_compound:
            self.status.show_text("sending…", MUTED)

    def refresh(self, state: Any) -> None:
        v = state.value
        if self.text is not None:
            if v is not None and v.text != self.text.toPlainText():
                self.text.setPlainText(v.text)
            self.status.show_text(state.error or "", BAD if state.error else MUTED)
            return
        if state.error:
            self.status.show_text(state.error, BAD)
        elif self.model.in_compound:
            ready = v is not None and v.ready
            self.status.show_text(f"will send: {v.text}" if ready else "nothing typed yet", OK if ready else MUTED)
        elif v is not None and v.sent:
            if v.note:  # the robot's safety envelope changed what went out: said, never silent
                self.status.show_text(f"sent, {v.note}", STALE, tooltip=f"typed: {v.text}")
            else:
                self.status.show_text(f"sent: {v.text}", OK)
            if self.model.settings.clear_after_send and self.edit.text() == v.text:
                self.edit.clear()
        else:
            self.status.show_text("", MUTED)
        if self.status.isHidden():
            fit_caption(self, self.edit, self.status)  # the new text becomes the input's tooltip
