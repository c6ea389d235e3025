"""For dangerous commands (Qt, view side): "ask before sending" and "hold to send" on a Button or Switch.

A :class:`SendGuard` sits on the control's push button as an event filter. With neither setting it
does nothing (the control works as before). Otherwise it takes the button's presses itself:

- **hold to send**: the button must be held for :data:`HOLD_S` (1 s); a bar along the button's bottom
  edge fills while it is held. Let go earlier and nothing is sent (the face says "✗ hold 1 s", short
  enough for the smallest control: "hold 1 s to send" was cut to "✗ hold 1…");
  the keyboard cannot hold, so Space/Enter send nothing either.
- **ask before sending**: a confirm dialog names exactly what goes to the robot: the service (or topic),
  its type and the request (or message) as YAML. Cancel sends nothing. With both settings the dialog
  comes once the hold is complete.

``describe()`` returns ``(what, detail)`` for the dialog at the moment it opens (a request built from the
settings; None when it cannot be built: then ``send()`` runs and the model reports why nothing was sent).
``send()`` sends; ``release()`` (optional, the Button's release call) runs when the finger lifts after a
hold, or right after ``send()`` when the dialog was confirmed.

The decisions (how long, what a release means, the counts) are the core's Qt-free
:class:`rcon_core.plugins.send_guard.SendGate`, a documented API any widget can use; this module is the
Qt side for a push button, and re-exports the core's names.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from qtpy import QtCore, QtGui, QtWidgets

from rcon_core.plugins.send_guard import HOLD_S, Outcome, SendGate, describe_send

__all__ = ["HOLD_S", "SendGate", "SendGuard", "describe_send"]

TICK_MS = 30
#: what the face flashes after a press too short to send (the tooltip says it in full)
HOLD_FACE = f"hold {HOLD_S:g} s"


class SendGuard(QtCore.QObject):
    def __init__(self, button: QtWidgets.QPushButton, *, ask: bool, hold: bool,
                 describe: Callable[[], tuple[str, str] | None], send: Callable[[], None],
                 release: Callable[[], None] | None = None, face: Any = None) -> None:
        super().__init__(button)
        self.button = button
        self.ask, self.hold = bool(ask), bool(hold)
        self.describe, self.send, self.release = describe, send, release
        self.face = face
        self.dialog: QtWidgets.QMessageBox | None = None
        self.gate = SendGate(ask=ask, hold=hold)  #: the decisions (rcon_core.plugins.send_guard)
        self._tick = QtCore.QTimer(self)
        self._tick.setInterval(TICK_MS)
        self._tick.timeout.connect(self._step)
        self.progress = QtWidgets.QProgressBar(button)
        self.progress.setObjectName("holdProgress")
        self.progress.setRange(0, 100)
        self.progress.setTextVisible(False)
        self.progress.setStyleSheet("QProgressBar { border: 0; background: #d0d0d0; }"
                                    " QProgressBar::chunk { background: #b00000; }")
        self.progress.hide()
        if self.active:
            button.installEventFilter(self)
            tips = [t for t, on in (("hold 1 s to send", self.hold), ("asks before sending", self.ask)) if on]
            button.setToolTip(" · ".join(tips).capitalize())

    @property
    def active(self) -> bool:
        return self.gate.active

    @property
    def sent(self) -> int:
        """Commands this guard let through."""
        return self.gate.sent

    @property
    def refused(self) -> int:
        """Presses that sent nothing (a short press, Cancel)."""
        return self.gate.refused

    # ------------------------------------------------------------------------------------ events
    def eventFilter(self, obj: QtCore.QObject, event: QtCore.QEvent) -> bool:  # noqa: N802 - Qt's name
        kind = event.type()
        E = QtCore.QEvent.Type
        if kind in (E.MouseButtonPress, E.MouseButtonDblClick) and isinstance(event, QtGui.QMouseEvent):
            if event.button() == QtCore.Qt.MouseButton.LeftButton and self.button.isEnabled():
                self._press()
            return True
        if kind == E.MouseButtonRelease and isinstance(event, QtGui.QMouseEvent):
            if event.button() == QtCore.Qt.MouseButton.LeftButton:
                self._release()
            return True
        if kind in (E.KeyPress, E.KeyRelease) and isinstance(event, QtGui.QKeyEvent) and event.key() in (
                QtCore.Qt.Key.Key_Space, QtCore.Qt.Key.Key_Return, QtCore.Qt.Key.Key_Enter, QtCore.Qt.Key.Key_Select):
            if kind == E.KeyRelease and not event.isAutoRepeat() and not self.hold:
                self._confirm()  # a key is a click: asked like one; it cannot hold
            return True
        return False

    def _press(self) -> None:
        self.button.setDown(True)
        if not self.hold:
            return
        self.gate.press()
        self.progress.setGeometry(0, self.button.height() - 8, self.button.width(), 8)
        self.progress.setValue(0)
        self.progress.show()
        self.progress.raise_()
        self._tick.start()

    def _step(self) -> None:
        if not self.gate.holding:
            return
        self.progress.setValue(int(self.gate.progress() * 100))
        if self.gate.due():
            self._tick.stop()
            if self.ask:
                self._end_hold()
                self._confirm()
            else:
                self._go(release=False)

    def _release(self) -> None:
        outcome = self.gate.release()
        self._end_hold()
        if outcome is Outcome.CONFIRM:
            self._confirm()
        elif outcome is Outcome.TOO_SHORT:
            if self.face is not None:  # short enough for the face of the smallest control, never cut
                self.face.answer(False, HOLD_FACE)
        elif outcome is Outcome.HELD and not self.ask and self.release is not None:
            self.release()

    def _end_hold(self) -> None:
        self._tick.stop()
        self.progress.hide()
        self.button.setDown(False)

    def _closed(self, box: QtWidgets.QMessageBox) -> None:
        if self.dialog is box:
            self.dialog = None
        box.deleteLater()

    # ------------------------------------------------------------------------------------ sending
    def _go(self, release: bool) -> None:
        self.gate.sent_one()
        self.send()
        if release and self.release is not None:
            self.release()

    def _confirm(self) -> None:
        self.button.setDown(False)
        if not self.ask:
            self._go(release=True)
            return
        try:
            described = self.describe()
        except Exception:
            described = None
        if described is None:
            self._go(release=True)  # the model says why nothing could be built and sent
            return
        what, detail = described
        box = QtWidgets.QMessageBox(self.button.window())
        box.setObjectName("sendConfirmDialog")
        box.setIcon(QtWidgets.QMessageBox.Icon.Warning)
        box.setWindowTitle("Send to the robot?")
        box.setText(what)
        box.setInformativeText(detail)
        box.setTextInteractionFlags(QtCore.Qt.TextInteractionFlag.TextSelectableByMouse)
        yes = box.addButton("Send", QtWidgets.QMessageBox.ButtonRole.AcceptRole)
        yes.setObjectName("sendConfirmYes")
        cancel = box.addButton(QtWidgets.QMessageBox.StandardButton.Cancel)
        cancel.setObjectName("sendConfirmCancel")
        box.setDefaultButton(cancel)
        for b in (yes, cancel):
            b.setMinimumWidth(max(b.sizeHint().width(), 160))

        def answered(button: Any) -> None:
            self.gate.answered(button is yes)
            if button is yes:
                self._go(release=True)

        box.buttonClicked.connect(answered)
        box.finished.connect(lambda _r: self._closed(box))
        self.dialog = box
        box.open()
