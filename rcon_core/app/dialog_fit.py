"""A dialog sized to the window it opens over: the room it has, and its own size within it.

Qt sizes a new top-level window to at most two thirds of the screen (``QWidget::adjustSize``), down to the
minimum its layout reports; a layout with word-wrapped text reports that minimum for a wider line than the
dialog gets, so on a 600 px tablet the PIN keypad's rows were laid over each other. :func:`fit_to_window`
gives a dialog the size it asks for, bounded by the window (and its screen).
"""

from __future__ import annotations

from qtpy import QtCore, QtWidgets

__all__ = ["room_for", "fit_to_window"]


def room_for(parent: QtWidgets.QWidget) -> QtCore.QSize:
    """The largest frame-less size a dialog over ``parent``'s window may take: the window's size, bounded by
    its screen's free area, less the window frame's thickness (a dialog's frame is as thick)."""
    window = parent.window()
    screen = window.screen()
    room = window.size()
    if screen is not None:
        room = room.boundedTo(screen.availableGeometry().size())
    frame = window.frameGeometry().size() - window.size()
    return QtCore.QSize(room.width() - frame.width(), room.height() - frame.height())


def fit_to_window(dialog: QtWidgets.QDialog, parent: QtWidgets.QWidget) -> None:
    """Resize ``dialog`` to its size hint, bounded by :func:`room_for` ``parent`` (call before showing it)."""
    dialog.ensurePolished()
    layout = dialog.layout()
    if layout is not None:
        layout.activate()
    dialog.resize(dialog.sizeHint().boundedTo(room_for(parent)))
