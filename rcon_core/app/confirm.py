"""The window's two-button question (``MainWindow.confirm``): delete a canvas, reset the demo layout,
duplicate a canvas for another robot, set a parameter."""

from __future__ import annotations

from collections.abc import Callable

from qtpy import QtWidgets

__all__ = ["ask"]


def ask(parent: QtWidgets.QWidget, question: str, detail: str, yes: str, then: Callable[[], object],
        closed: Callable[[], object]) -> QtWidgets.QMessageBox:
    """A window-modal question with two large buttons (``yes`` and Cancel); ``then`` runs on yes,
    ``closed`` after either answer. Returns at once (the dialog is open), so the event loop and the robot
    link keep running."""
    box = QtWidgets.QMessageBox(parent)
    box.setObjectName("confirmDialog")
    box.setIcon(QtWidgets.QMessageBox.Icon.Warning)
    box.setWindowTitle(question)
    box.setText(question)
    box.setInformativeText(detail)
    ok = box.addButton(yes, QtWidgets.QMessageBox.ButtonRole.DestructiveRole)
    ok.setObjectName("confirmYes")
    cancel = box.addButton(QtWidgets.QMessageBox.StandardButton.Cancel)
    cancel.setObjectName("confirmCancel")
    box.setDefaultButton(cancel)
    for button in (ok, cancel):
        button.setMinimumWidth(max(button.sizeHint().width(), 160))
    box.buttonClicked.connect(lambda button: then() if button is ok else None)
    box.finished.connect(lambda _result: closed())
    box.open()
    return box
