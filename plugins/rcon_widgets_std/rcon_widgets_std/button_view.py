"""Button's Qt view: a push button; underneath, the call in progress, its result or the server's error."""

from __future__ import annotations

from typing import Any

from qtpy import QtCore, QtWidgets

from .view_common import BAD, MUTED, OK, Caption, fit_caption, vbox


class ButtonView(QtWidgets.QWidget):
    def __init__(self, model: Any, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.model = model
        layout = vbox(self)
        text = model.settings.text or model.binding.name.rsplit("/", 1)[-1] or "Press"
        self.button = QtWidgets.QPushButton(text)
        self.button.setProperty("primary", True)
        self.button.setSizePolicy(QtWidgets.QSizePolicy.Policy.Expanding, QtWidgets.QSizePolicy.Policy.Expanding)
        self.button.pressed.connect(model.press)
        self.button.released.connect(model.release)
        layout.addWidget(self.button, 1)
        self.result = Caption("")
        self.result.setAlignment(QtCore.Qt.AlignmentFlag.AlignCenter)
        layout.addWidget(self.result)

    def resizeEvent(self, event: Any) -> None:  # noqa: N802 - Qt override
        super().resizeEvent(event)
        fit_caption(self, self.button, self.result)  # too small for both: the result becomes the tooltip

    def refresh(self, state: Any) -> None:
        self._show_result(state)
        if self.result.isHidden():
            fit_caption(self, self.button, self.result)

    def _show_result(self, state: Any) -> None:
        st = state.value
        if st is None:
            self.result.show_text(state.error or "", BAD if state.error else MUTED)
            return
        if st.busy:
            self.result.show_text(f"calling {st.target}…", MUTED)
        elif st.phase == "failed":
            self.result.show_text(f"✗ {st.text}", BAD, tooltip=state.error or st.text)
        else:
            took = f" ({st.seconds * 1000:.0f} ms)" if st.seconds else ""
            self.result.show_text(f"✓ {st.text}{took}", OK, tooltip=st.text)
