"""Switch's Qt view: one big toggle button with the state's text, and a line for the server's reply.

The face reads as a state, not as an action: "● On" / "○ Off" (a lamp lit or not), and, while there is
no reply to show, the line under it says what a tap does ("tap for On").

While a call is in flight the button says "On…"; when the frame is too short for the reply line, the
answer is flashed on the button itself ("✓ lights on" in green, "✗ interlock open" in red, two seconds)
before it shows the state again: a touch operator has no tooltip to hover."""

from __future__ import annotations

from typing import Any

from qtpy import QtCore, QtWidgets

from rcon_core.plugins import Role

from .send_guard import SendGuard
from .view_common import BAD, MUTED, OK, ButtonFace, Caption, fit_caption, vbox


class SwitchView(QtWidgets.QWidget):
    def __init__(self, model: Any, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.model = model
        layout = vbox(self)
        self.button = QtWidgets.QPushButton("?")
        self.button.setCheckable(True)
        self.button.setSizePolicy(QtWidgets.QSizePolicy.Policy.Expanding, QtWidgets.QSizePolicy.Policy.Expanding)
        self.button.setEnabled(model.binding.role is not Role.SUBSCRIBE)
        self.button.setMinimumWidth(40)  # the face elides; its text must not make the widget wider
        self.button.clicked.connect(self._clicked)
        layout.addWidget(self.button, 1)
        self.face = ButtonFace(self.button, "?")
        #: the state a confirm dialog showed: what is sent on Send, even if the robot's state moved meanwhile
        self._pending: bool | None = None
        self.guard = SendGuard(self.button, ask=model.settings.confirm, hold=model.settings.hold_to_send,
                               describe=self._describe, send=self._send_guarded, face=self.face)
        self._was_busy = False
        self.reply = Caption("")
        self._reply: tuple[str, str] | None = None  # (text, colour) shown in the reply line
        self.reply.setAlignment(QtCore.Qt.AlignmentFlag.AlignCenter)
        layout.addWidget(self.reply)
        self._paint(None, "", None)
        self._live = False  # refreshed at least once (an error already there when built is not news)

    def _target(self) -> bool:
        return not bool(getattr(self.model.state.value, "on", None))

    def _describe(self) -> tuple[str, str] | None:
        self._pending = self._target()
        return self.model.describe_set(self._pending)

    def _send_guarded(self) -> None:
        target = self._pending if self._pending is not None else self._target()
        self._pending = None
        self.model.set(target)
        self.refresh(self.model.state)

    def _clicked(self, checked: bool) -> None:
        self.model.set(bool(checked))
        self.refresh(self.model.state)

    def refresh(self, state: Any) -> None:
        v = state.value
        on = getattr(v, "on", None)
        self._paint(on, getattr(v, "reply", ""), state.error, busy=getattr(v, "busy", False),
                    wanted=getattr(v, "wanted", None))
        self._live = True

    def _paint(self, on: bool | None, reply: str, error: str | None, busy: bool = False,
               wanted: bool | None = None) -> None:
        s = self.model.settings
        self.button.blockSignals(True)
        self.button.setChecked(bool(on))
        self.button.blockSignals(False)
        self.face.set_label("?" if on is None else f"● {s.on_text}" if on else f"○ {s.off_text}")
        hint = False
        if error:
            shown = (error, BAD)
        elif busy:
            shown = ("asking the robot…", MUTED)
        elif reply:
            shown = (reply, OK)
        elif on is not None and self.button.isEnabled():
            shown, hint = (f"tap for {s.off_text if on else s.on_text}", MUTED), True
        else:
            shown = ("", MUTED)
        fresh = shown != self._reply
        if fresh:  # show_text sets a style sheet (a re-polish): only when it changes
            self._reply = shown
            self.reply.show_text(*shown)
            fit_caption(self, self.button, self.reply)
        if busy:
            if not self._was_busy:
                self.face.busy(f"{s.on_text if wanted else s.off_text}…")
        elif fresh and shown[0] and not hint and (self._was_busy or (error and self._live)) and self.reply.isHidden():
            self.face.answer(not error, reply or shown[0])  # the short answer, where the operator looks
        elif self._was_busy:
            self.face.rest()
        self._was_busy = busy

    def resizeEvent(self, event: Any) -> None:  # noqa: N802 - Qt override
        super().resizeEvent(event)
        self.face.fit()
        fit_caption(self, self.button, self.reply)  # too small for both: the reply becomes the tooltip
