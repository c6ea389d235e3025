"""Button's Qt view: a push button whose face tells the operator what happened ("Dock…" while the call
is in flight, then "✓ docking started" in green or "✗ already docked" in red for two seconds, then its
label again); underneath, when the frame has room, the call in progress, its result or the server's
error in full."""

from __future__ import annotations

from typing import Any

from qtpy import QtCore, QtWidgets

from rcon_core.plugins import CallPhase

from .send_guard import SendGuard
from .view_common import BAD, MUTED, OK, ButtonFace, Caption, fit_caption, vbox


class ButtonView(QtWidgets.QWidget):
    def __init__(self, model: Any, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.model = model
        layout = vbox(self)
        text = model.settings.text or model.binding.name.rsplit("/", 1)[-1] or "Press"
        self.button = QtWidgets.QPushButton(text)
        self.button.setProperty("primary", True)
        self.button.setSizePolicy(QtWidgets.QSizePolicy.Policy.Expanding, QtWidgets.QSizePolicy.Policy.Expanding)
        self.button.setMinimumWidth(40)  # the face elides; its text must not make the widget wider
        self.button.pressed.connect(model.press)
        self.button.released.connect(model.release)
        layout.addWidget(self.button, 1)
        self.face = ButtonFace(self.button, text)
        # "ask before sending" / "hold to send": the guard takes the presses (pressed/released never fire)
        self.guard = SendGuard(self.button, ask=model.settings.confirm, hold=model.settings.hold_to_send,
                               describe=model.describe_send, send=model.press, release=model.release,
                               face=self.face)
        self.result = Caption("")
        self.result.setAlignment(QtCore.Qt.AlignmentFlag.AlignCenter)
        layout.addWidget(self.result)
        # what was already there when this view was built (a rebuilt view must not flash an old answer)
        self._seen: tuple[Any, str | None] = (model.state.value, model.state.error)

    def resizeEvent(self, event: Any) -> None:  # noqa: N802 - Qt override
        super().resizeEvent(event)
        self.face.fit()
        fit_caption(self, self.button, self.result)  # too small for both: the result becomes the tooltip

    def refresh(self, state: Any) -> None:
        self._show_result(state)
        self._show_face(state)
        if self.result.isHidden():
            fit_caption(self, self.button, self.result)

    def _show_face(self, state: Any) -> None:
        st, error = state.value, state.error
        seen_st, seen_error = self._seen
        self._seen = (st, error)
        if st is not None and st is not seen_st:
            if st.busy:
                self.face.busy()
            else:
                self.face.answer(st.phase is not CallPhase.FAILED, st.text)
        elif error and error != seen_error and (st is None or not st.busy):
            self.face.answer(False, error)  # refused before any call (a bad request, no binding)

    def _show_result(self, state: Any) -> None:
        st = state.value
        if st is None:
            self.result.show_text(state.error or "", BAD if state.error else MUTED)
            return
        if st.busy:
            self.result.show_text(f"calling {st.target}…", MUTED)
        elif st.phase is CallPhase.FAILED:
            self.result.show_text(f"✗ {st.text}", BAD, tooltip=state.error or st.text)
        else:
            took = f" ({st.seconds * 1000:.0f} ms)" if st.seconds else ""
            self.result.show_text(f"✓ {st.text}{took}", OK, tooltip=st.text)
