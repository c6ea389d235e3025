"""Canvas ▾ → Safety envelope…: each robot's maximum linear and angular speed, and the check of a widget's
settings against it. Qt; the envelope itself is ``rcon_core/bridge/envelope.py`` (no Qt).

The dialog lists the workspace's robots, one row each: its name, the maximum linear speed (m/s) and the
maximum angular speed (rad/s); an empty field is no limit. OK checks every value (a number, more than 0,
at most 100 m/s and 50 rad/s: 999999999999 is refused with its reason and nothing changes) and replaces the
robots in one undo step (``Document.set_robots``): the envelope is saved with the workspace, and each
robot's link applies it at once (``FleetLinks.sync``). While the operator lock is engaged the dialog opens
only after the PIN (:func:`install` gates the action).

:func:`beyond_envelope` is what the Configure dialog asks before saving (and :func:`check_placed` right after a
widget is placed from the add panel: Cancel takes it away again) a widget whose settings could
command more than its robot's envelope allows (a slider on ``/cmd_vel`` ``linear.x`` up to 5 m/s with an
envelope of 1 m/s): the widget's settings say what they may send through the optional
``settings.commands(binding) -> [(field path, largest value)]`` (the std Slider, Stepper and Compound and
the teleop pad have it).
"""

from __future__ import annotations

import copy
import math
from typing import Any

import attrs
from qtpy import QtGui, QtWidgets

from rcon_core.app.canvas_bar import CanvasBar
from rcon_core.app.dialog_fit import fit_to_window
from rcon_core.app.notice_bar import NoticeBar
from rcon_core.app.operator_lock import Guard
from rcon_core.bridge.envelope import MAX_ANGULAR, MAX_LINEAR, Envelope
from rcon_core.canvas import Document
from rcon_core.canvas.robots import Robot
from rcon_core.plugins import WidgetCatalog
from rcon_core.plugins.api import settings_commands

__all__ = ["EnvelopeControl", "EnvelopeDialog", "ask_beyond", "beyond_envelope", "parse_limit"]

COLUMNS = ("Robot", "Max linear (m/s)", "Max angular (rad/s)")


def parse_limit(text: str, what: str, top: float, units: str = "") -> float | None:
    """A limit typed by the operator: None for an empty field, else a number in (0, ``top``]; ValueError
    with a sentence otherwise."""
    text = text.strip()
    if not text:
        return None
    try:
        value = float(text)
    except ValueError:
        raise ValueError(f"{what}: {text!r} is not a number") from None
    if not math.isfinite(value) or value > top:
        raise ValueError(f"{what}: {text} is more than {top:g} {units}, the most an envelope may allow "
                         "(a slip of a finger?)".replace(" ,", ","))
    if value <= 0:
        raise ValueError(f"{what}: it must be more than 0 (empty: no limit)")
    return value


def beyond_envelope(envelope: Envelope | None, binding: Any, settings: Any,
                    catalog: WidgetCatalog | None = None) -> list[str]:
    """What ``settings`` (of a widget bound by ``binding``) could send beyond ``envelope``, one sentence
    each ("linear.x up to 5 m/s: the safety envelope holds it to 1 m/s"); empty when nothing is beyond or
    the settings do not say what they send (no ``commands(binding)``; ``catalog``: the enabled kinds, for
    settings whose commands are their children's)."""
    if envelope is None or not envelope.limited or settings is None:
        return []
    pairs = settings_commands(settings, binding, catalog)  # a hint that fails says nothing
    out = []
    for path, value in pairs:
        limit = envelope.limit_for(binding.type, path)
        if limit is not None and abs(value) > limit:
            units = "rad/s" if ".angular" in f".{path}" or path.startswith("angular") else "m/s"
            out.append(f"{path} up to {value:g} {units}: the safety envelope holds it to {limit:g} {units}")
    return out


class EnvelopeDialog(QtWidgets.QDialog):
    """One row per robot: its maximum linear and angular speed (empty: no limit)."""

    def __init__(self, robots: list[Robot], parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.setObjectName("envelopeDialog")
        self.setWindowTitle("Safety envelope")
        self._robots = copy.deepcopy(list(robots))
        intro = QtWidgets.QLabel(
            "Every motion command (Twist) sent to a robot is held to its envelope, whichever widget sends "
            "it: each component is clamped to the limit; NaN and infinity are never sent. Empty: no limit.")
        intro.setWordWrap(True)
        intro.setProperty("role", "hint")
        self.grid = QtWidgets.QGridLayout()
        for c, text in enumerate(COLUMNS):
            head = QtWidgets.QLabel(text)
            head.setProperty("role", "heading")
            self.grid.addWidget(head, 0, c)
        self.fields: list[tuple[QtWidgets.QLineEdit, QtWidgets.QLineEdit]] = []
        self.problem = QtWidgets.QLabel()
        self.problem.setObjectName("envelopeProblem")
        self.problem.setProperty("role", "problem")
        self.problem.setWordWrap(True)
        for r, robot in enumerate(self._robots, start=1):
            self.grid.addWidget(QtWidgets.QLabel(robot.label), r, 0)
            env = robot.envelope or Envelope()
            pair = []
            for c, (value, name) in enumerate(((env.max_linear, "linear"), (env.max_angular, "angular")), start=1):
                edit = QtWidgets.QLineEdit("" if value is None else f"{value:g}")
                edit.setObjectName(f"envelope_{name}_{robot.id}")
                edit.setPlaceholderText("no limit")
                edit.setAccessibleName(f"{robot.label}: maximum {name} speed")
                edit.textChanged.connect(lambda _t: self.problem.setText(""))
                self.grid.addWidget(edit, r, c)
                pair.append(edit)
            self.fields.append((pair[0], pair[1]))
        buttons = QtWidgets.QDialogButtonBox(
            QtWidgets.QDialogButtonBox.StandardButton.Ok | QtWidgets.QDialogButtonBox.StandardButton.Cancel)
        buttons.accepted.connect(self._ok)
        buttons.rejected.connect(self.reject)
        self.ok_button = buttons.button(QtWidgets.QDialogButtonBox.StandardButton.Ok)
        self.ok_button.setObjectName("envelopeOk")
        col = QtWidgets.QVBoxLayout(self)
        col.addWidget(intro)
        col.addLayout(self.grid)
        col.addWidget(self.problem)
        col.addStretch(1)
        col.addWidget(buttons)
        self.grid.setHorizontalSpacing(16)
        self.grid.setVerticalSpacing(10)
        self.setMinimumWidth(600)
        self.adjustSize()  # every row at its touch size: the layout decides the height

    def set_limits(self, robot_id: str, linear: str | None = None, angular: str | None = None) -> None:
        """Type into a robot's fields (tests, as a person would)."""
        for robot, (lin, ang) in zip(self._robots, self.fields, strict=True):
            if robot.id == robot_id:
                if linear is not None:
                    lin.setText(linear)
                if angular is not None:
                    ang.setText(angular)

    def robots(self) -> list[Robot]:
        """The robots with their envelopes as typed; ValueError naming the robot and the field otherwise."""
        out = []
        for robot, (lin, ang) in zip(self._robots, self.fields, strict=True):
            linear = parse_limit(lin.text(), f"{robot.label}, maximum linear speed", MAX_LINEAR, "m/s")
            angular = parse_limit(ang.text(), f"{robot.label}, maximum angular speed", MAX_ANGULAR, "rad/s")
            env = Envelope(linear, angular)
            out.append(attrs.evolve(robot, envelope=env if env.limited else None))
        return out

    def _ok(self) -> None:
        try:
            self.robots()
        except ValueError as exc:
            self.problem.setText(str(exc))
            return
        self.accept()


class EnvelopeControl:
    """Canvas ▾ → Safety envelope… (``canvas_envelope``, the PIN first while the operator lock is on) and
    the check of a widget just placed; given the document, the notice bar, the lock's guard, the canvas
    bar (its menu) and the dialogs' parent. ``dialog`` and ``beyond_dialog``: the last ones opened."""

    def __init__(self, doc: Document, notice: NoticeBar, guard: Guard, bar: CanvasBar,
                 parent: QtWidgets.QWidget) -> None:
        self.doc, self.notice, self.parent = doc, notice, parent
        self.dialog: EnvelopeDialog | None = None
        self.beyond_dialog: QtWidgets.QMessageBox | None = None
        menu = bar.menu
        action = QtGui.QAction("Safety envelope…", menu)
        action.setObjectName("canvas_envelope")
        before = bar.canvas_actions.get("robots")
        if before is not None and before in menu.actions():
            idx = menu.actions().index(before)
            after = menu.actions()[idx + 1] if idx + 1 < len(menu.actions()) else None
            if after is not None:
                menu.insertAction(after, action)
            else:
                menu.addAction(action)
        else:
            menu.addAction(action)
        action.triggered.connect(lambda: guard("change the safety envelope", self.open_dialog))
        bar.canvas_actions["envelope"] = action

    def open_dialog(self) -> EnvelopeDialog:
        """Open the dialog (window-modal; returns at once). OK replaces the robots in one undo step."""
        dialog = EnvelopeDialog(self.doc.workspace.robots, self.parent)

        def apply() -> None:
            from rcon_core.canvas import EditError

            try:
                self.doc.set_robots(dialog.robots())
            except (EditError, ValueError) as exc:
                self.notice.show_notice(f"⚠ {exc}")

        dialog.accepted.connect(apply)
        dialog.finished.connect(lambda _r: dialog.deleteLater())
        self.dialog = dialog
        fit_to_window(dialog, self.parent)  # the width its headings ask for, not the 600 px floor
        dialog.open()
        return dialog

    def check_placed(self, draft: Any) -> QtWidgets.QMessageBox | None:
        """After a widget from the add panel was placed: when its settings could command more than its
        robot's safety envelope, ask whether to keep it (Cancel takes it away again, one undo). None when
        nothing is beyond (nothing asked)."""
        if draft is None:
            return None
        try:
            envelope = self.doc.workspace.robot(draft.robot).envelope
        except KeyError:
            return None
        beyond = beyond_envelope(envelope, draft.binding, draft.settings, draft.catalog)
        if not beyond:
            return None
        box = ask_beyond(self.parent, beyond, lambda: None, otherwise=self.doc.undo, save="Keep it")
        self.beyond_dialog = box
        return box


def ask_beyond(parent: QtWidgets.QWidget, problems: list[str], then: Any, otherwise: Any = None,
               save: str = "Save anyway") -> QtWidgets.QMessageBox:
    """Ask before saving settings that could command more than the envelope (``then`` runs on Save,
    ``otherwise`` on Cancel)."""
    box = QtWidgets.QMessageBox(parent)
    box.setObjectName("beyondEnvelopeDialog")
    box.setIcon(QtWidgets.QMessageBox.Icon.Warning)
    box.setWindowTitle("Beyond the safety envelope")
    box.setText("These settings ask for more than the robot's safety envelope allows.")
    box.setInformativeText("\n".join(problems) + "\n\nThe robot is never sent more than its envelope. Save anyway?")
    keep = box.addButton(save, QtWidgets.QMessageBox.ButtonRole.AcceptRole)
    keep.setObjectName("beyondEnvelopeSave")
    cancel = box.addButton(QtWidgets.QMessageBox.StandardButton.Cancel)
    cancel.setObjectName("beyondEnvelopeCancel")
    box.setDefaultButton(cancel)
    for b in (keep, cancel):
        b.setMinimumWidth(max(b.sizeHint().width(), 160))

    def answered(button: Any) -> None:
        if button is keep:
            then()
        elif otherwise is not None:
            otherwise()

    box.buttonClicked.connect(answered)
    box.finished.connect(lambda _r: box.deleteLater())
    box.open()
    return box

