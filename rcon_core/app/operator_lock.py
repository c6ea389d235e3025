"""The operator lock: Operate mode that only the operator PIN leaves.

Two notions, kept apart:

- **Operate mode** (``Canvas.locked``, saved in the layout) is a convenience: the widgets take touches and
  nothing moves by accident. Anyone can tap *Edit* to leave it.
- **The operator lock** (this module, a state of the running app, never saved in the layout) keeps the
  app in Operate mode: while it is engaged, leaving Operate mode, editing (adding widgets, the canvas
  menu's new/rename/duplicate/delete/import), turning view-only off, changing the robot (connect,
  disconnect, the URL) and quitting ask for the PIN first. The right PIN disengages the lock and the
  action goes on; a wrong one changes nothing. Switching between canvases stays free; each canvas shown
  is put in Operate mode. ``rcon --locked`` starts with the lock engaged, full screen (a kiosk).

The PIN is set in the app (*Canvas ▾ → Operator PIN…*) and kept hashed in the app config (see
:mod:`rcon_core.app.pin`), never in the layout. After :data:`MAX_TRIES` wrong PINs in a row, every try is
refused for :data:`BACKOFF_S` seconds (doubling each time), so guessing a 4-digit PIN takes days. The
count and the wait are kept in the app config too, so restarting RCON does not start them afresh. A PIN
entered right whose record was made at a lower scrypt cost (an older ``app.json``) is stored again at the
current cost. A PIN that could not be saved still locks this run: a full disk is told by the app
config's problem listeners, a read-only config (another RCON is the folder's writer) by ``problem(sentence)``;
the window shows either.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

from qtpy import QtCore, QtWidgets

from rcon_core.app.config import AppConfig
from rcon_core.app.dialog_fit import fit_to_window, fitted_size, room_for
from rcon_core.app.pin import PIN_MAX, PIN_MIN, check_pin, make_record, needs_upgrade, pin_problem

MAX_TRIES = 5
BACKOFF_S = 30.0

#: ``guard(what, then)``: runs ``then`` now, or after the operator PIN while the lock is engaged
#: (:meth:`OperatorLock.guard`); the parts that change the robot or the layout are built with one
Guard = Callable[[str, Callable[[], object]], object]


def no_guard(_what: str, then: Callable[[], object]) -> object:
    """The guard of a part built without the operator lock (tests, embedders): runs ``then`` now."""
    return then()


class PinDialog(QtWidgets.QDialog):
    """Asks for a PIN (twice with ``repeat``), with a digit pad for a touch screen. ``check(pin)`` decides
    on OK: None accepts, a sentence is shown and the dialog stays open (the field is cleared).

    One column (the prompt, the field(s), the keypad, OK) where it fits the room it has; where it does not
    and the room is wider than tall (a 600 px landscape tablet at a large text size: 674 px asked), two:
    the keypad beside the rest (:meth:`arrange_for`). Its keys never go below the touch size (gloves)."""

    def __init__(self, parent: QtWidgets.QWidget, title: str, prompt: str,
                 check: Callable[[str], str | None], *, repeat: bool = False) -> None:
        super().__init__(parent)
        self.setObjectName("pinDialog")
        self.setWindowTitle(title)
        self.setWindowModality(QtCore.Qt.WindowModality.WindowModal)
        self._check = check
        self.grid = QtWidgets.QGridLayout(self)
        self.heading = QtWidgets.QLabel(prompt)
        self.heading.setObjectName("pinPrompt")
        self.heading.setWordWrap(True)
        self.heading.setProperty("role", "heading")
        self.field = self._pin_field("pinField", "PIN")
        self.repeat: QtWidgets.QLineEdit | None = None
        if repeat:
            self.repeat = self._pin_field("pinRepeat", "the same PIN again")
        #: the keypad, one widget: it moves beside the rest in two columns
        self.keypad = QtWidgets.QWidget()
        self.keypad.setObjectName("pinKeypad")
        pad = QtWidgets.QGridLayout(self.keypad)
        pad.setContentsMargins(0, 0, 0, 0)
        self.keys: dict[str, QtWidgets.QPushButton] = {}
        for i, key in enumerate("123456789⌫0"):
            button = QtWidgets.QPushButton(key)
            button.setObjectName(f"pinKey{key if key.isdigit() else 'Back'}")
            button.setFocusPolicy(QtCore.Qt.FocusPolicy.NoFocus)
            # as tall as the room gives in two columns, never lower than the touch size
            button.setSizePolicy(QtWidgets.QSizePolicy.Policy.Preferred, QtWidgets.QSizePolicy.Policy.Expanding)
            button.clicked.connect(lambda _=False, k=key: self._key(k))
            self.keys[key] = button
            pad.addWidget(button, i // 3, i % 3)
        self.message = QtWidgets.QLabel()
        self.message.setObjectName("pinMessage")
        self.message.setProperty("role", "problem")
        self.message.setWordWrap(True)
        self.buttons = QtWidgets.QDialogButtonBox()
        self.ok = self.buttons.addButton("OK", QtWidgets.QDialogButtonBox.ButtonRole.AcceptRole)
        self.ok.setObjectName("pinOk")
        self.cancel = self.buttons.addButton(QtWidgets.QDialogButtonBox.StandardButton.Cancel)
        self.cancel.setObjectName("pinCancel")
        self.ok.clicked.connect(self.submit)
        self.cancel.clicked.connect(self.reject)
        self.field.returnPressed.connect(self.submit)
        if self.repeat is not None:
            self.repeat.returnPressed.connect(self.submit)
        #: 1 or 2 (:meth:`arrange`)
        self.columns = 0
        self.arrange(1)

    def arrange(self, columns: int) -> None:
        """Lay the parts out in one column, or in two (the keypad on the right, beside the rest)."""
        if columns == self.columns:
            return
        self.columns = columns
        grid = self.grid
        parts: list[QtWidgets.QWidget] = [self.heading, self.field, *([self.repeat] if self.repeat else []),
                                          self.keypad, self.message, self.buttons]
        for part in parts:
            grid.removeWidget(part)
        for r in range(grid.rowCount()):
            grid.setRowStretch(r, 0)
        for c in range(grid.columnCount()):
            grid.setColumnStretch(c, 0)
        if columns == 1:
            for row, part in enumerate(parts):
                grid.addWidget(part, row, 0)
            grid.setRowStretch(parts.index(self.keypad), 1)
            return
        side = [part for part in parts if part is not self.keypad]
        for row, part in enumerate(side):
            grid.addWidget(part, row, 0)
        grid.setRowStretch(side.index(self.message), 1)  # OK and Cancel at the foot of the column
        grid.addWidget(self.keypad, 0, 1, len(side), 1)
        grid.setColumnStretch(0, 2)  # the prompt's lines the room they want; the keys' still glove-sized
        grid.setColumnStretch(1, 1)
        grid.setHorizontalSpacing(max(grid.horizontalSpacing(), 16))

    def arrange_for(self, room: QtCore.QSize) -> None:
        """One column when it fits ``room`` (the dialog's room over its window, ``dialog_fit.room_for``);
        else two where the room is wider than tall (the keypad needs the height two columns leave it)."""
        self.arrange(1)
        if fitted_size(self, room).height() > room.height() and room.width() > room.height():
            self.arrange(2)

    def _pin_field(self, name: str, placeholder: str) -> QtWidgets.QLineEdit:
        field = QtWidgets.QLineEdit()
        field.setObjectName(name)
        field.setEchoMode(QtWidgets.QLineEdit.EchoMode.Password)
        field.setPlaceholderText(placeholder)
        field.setMaxLength(PIN_MAX)
        field.setInputMethodHints(QtCore.Qt.InputMethodHint.ImhDigitsOnly
                                  | QtCore.Qt.InputMethodHint.ImhSensitiveData)
        return field

    def _key(self, key: str) -> None:
        target = self.repeat if self.repeat is not None and self.repeat.hasFocus() else self.field
        if key == "⌫":
            target.backspace()
        else:
            target.insert(key)

    def submit(self) -> None:
        pin = self.field.text()
        if self.repeat is not None and self.repeat.text() != pin:
            self._refuse("the two PINs differ")
            return
        problem = self._check(pin)
        if problem:
            self._refuse(problem)
            return
        self.accept()

    def _refuse(self, text: str) -> None:
        self.message.setText(text)
        self.field.clear()
        if self.repeat is not None:
            self.repeat.clear()
        self.field.setFocus()


class OperatorLock(QtCore.QObject):
    """Whether the operator lock is engaged, and the PIN dialogs. ``changed(engaged)`` on every change."""

    changed = QtCore.Signal(bool)
    #: one sentence for the operator: the PIN could not be saved
    problem = QtCore.Signal(str)

    def __init__(self, config: AppConfig, window: QtWidgets.QWidget,
                 clock: Callable[[], float] = time.monotonic, wall: Callable[[], float] = time.time) -> None:
        super().__init__(window)
        self.config = config
        self.window = window
        self.clock = clock
        self.wall = wall
        self.engaged = False
        saved = config.pin_lockout  # kept across restarts
        self.wrong = int(saved["wrong"]) % MAX_TRIES
        self._backoff = max(BACKOFF_S, saved["backoff"])
        left = min(saved["until"] - wall(), self._backoff)  # a clock set back never waits longer
        self.blocked_until = clock() + left if left > 0 else 0.0
        self.dialog: PinDialog | None = None

    @property
    def has_pin(self) -> bool:
        return self.config.pin_record is not None

    # ------------------------------------------------------------------------------- engaging
    def engage(self) -> bool:
        """Engage the lock; False (nothing changes) when no PIN is set."""
        if not self.has_pin:
            return False
        if not self.engaged:
            self.engaged = True
            self.changed.emit(True)
        return True

    def disengage(self) -> None:
        if self.engaged:
            self.engaged = False
            self.changed.emit(False)

    def try_pin(self, pin: str) -> str | None:
        """Disengage with ``pin``: None when it was right, else why not (wrong, or wait after too many)."""
        now = self.clock()
        if now < self.blocked_until:
            return f"too many wrong PINs: try again in {int(self.blocked_until - now + 0.999)} s"
        record = self.config.pin_record
        if check_pin(record, pin):
            if self.wrong or self._backoff != BACKOFF_S:
                self.wrong = 0
                self._backoff = BACKOFF_S
                self.config.set_pin_lockout(0, 0.0, 0.0)
            if needs_upgrade(record):  # an older app.json: the same PIN at today's cost
                self.config.set_pin_record(make_record(pin))
            self.disengage()
            return None
        self.wrong += 1
        if self.wrong >= MAX_TRIES:
            self.wrong = 0
            self.blocked_until = now + self._backoff
            wait = self._backoff
            self._backoff *= 2
            self.config.set_pin_lockout(0, self.wall() + wait, self._backoff)
            return f"wrong PIN; too many wrong PINs: try again in {int(wait)} s"
        self.config.set_pin_lockout(self.wrong, 0.0, self._backoff)
        return "wrong PIN"

    # ------------------------------------------------------------------------------- asking
    def guard(self, what: str, then: Callable[[], object]) -> PinDialog | None:
        """Run ``then`` now when the lock is not engaged; else ask for the PIN (saying it is needed to
        ``what``) and run it once the right PIN disengaged the lock. Returns the open dialog, if any."""
        if not self.engaged:
            then()
            return None
        return self._open(PinDialog(self.window, "Operator lock", f"Operator lock: enter the PIN to {what}.",
                                    self.try_pin), then)

    def engage_dialog(self) -> PinDialog | None:
        """The lock button: engage, asking for a new PIN first when none is set."""
        if self.engage():
            return None
        return self.set_pin_dialog(then=self.engage)

    def set_pin_dialog(self, then: Callable[[], object] | None = None) -> PinDialog | None:
        """Set or change the PIN (asked twice); changing it asks for the current one first."""
        def ask_new() -> None:
            def store(pin: str) -> str | None:
                problem = pin_problem(pin)
                if problem:
                    return problem
                saved = self.config.set_pin_record(make_record(pin))  # in memory at least: it locks this run
                if not saved and self.config.read_only_reason:  # else the config's listeners were told
                    self.problem.emit(f"⚠ The operator PIN is not saved ({self.config.read_only_reason}): "
                                      "it locks this window only.")
                return None

            self._open(PinDialog(self.window, "Operator PIN",
                                 f"Choose the operator PIN ({PIN_MIN} to {PIN_MAX} digits; 6 or more resist "
                                 "guessing from a copy of the device's files): it locks Operate mode.", store,
                                 repeat=True), then or (lambda: None))

        if not self.has_pin:
            ask_new()
            return self.dialog

        def check_current(pin: str) -> str | None:
            return None if check_pin(self.config.pin_record, pin) else "wrong PIN"

        return self._open(PinDialog(self.window, "Operator PIN", "Enter the current operator PIN to change it.",
                                    check_current), ask_new)

    def _open(self, dialog: PinDialog, then: Callable[[], object]) -> PinDialog:
        if self.dialog is not None and self.dialog.isVisible():
            self.dialog.reject()
        self.dialog = dialog
        dialog.accepted.connect(lambda: then())
        dialog.finished.connect(lambda _r, d=dialog: self._closed(d))
        dialog.arrange_for(room_for(self.window))  # two columns where one does not fit (200 % text, 600 px)
        fit_to_window(dialog, self.window)  # the keypad whole on a 600 px tablet (dialog_fit.py)
        dialog.open()
        dialog.field.setFocus()
        return dialog

    def _closed(self, dialog: PinDialog) -> None:
        if self.dialog is dialog:
            self.dialog = None
        dialog.deleteLater()

    def status_text(self) -> str:
        return "Locked" if self.engaged else "Lock"


def lock_tooltip(lock: Any) -> str:
    if lock.engaged:
        return "Operator lock on: editing, leaving Operate mode, changing the robot and quitting need the PIN"
    return "Lock Operate mode with the operator PIN" if lock.has_pin else "Choose an operator PIN and lock"
