"""A dialog sized to the window it opens over: the room it has, and its own size within it.

Qt sizes a new top-level window to at most two thirds of the screen (``QWidget::adjustSize``), down to the
minimum its layout reports; a layout with word-wrapped text reports that minimum for a wider line than the
dialog gets, so on a 600 px tablet the PIN keypad's rows were laid over each other. :func:`fit_to_window`
gives a dialog the size it asks for, bounded by the window (and its screen), its height reckoned for the
width it gets (:func:`fitted_size`).
"""

from __future__ import annotations

from qtpy import QtCore, QtWidgets

__all__ = ["room_for", "fitted_size", "fit_to_window"]


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


def fitted_size(dialog: QtWidgets.QDialog, room: QtCore.QSize) -> QtCore.QSize:
    """The size ``dialog`` asks for within ``room``: its size hint's width, bounded; the height its layout
    needs at that width (word-wrapped text takes more lines when the width is bounded), bounded too -- a
    result taller than ``room`` can only be ``room``'s height: the dialog does not fit."""
    dialog.ensurePolished()
    layout = dialog.layout()
    if layout is not None:
        layout.activate()
    hint = dialog.sizeHint()
    width = min(hint.width(), room.width())
    height = hint.height()
    if layout is not None and layout.hasHeightForWidth():
        height = max(height if width == hint.width() else 0, layout.totalHeightForWidth(width))
    return QtCore.QSize(width, height)


def fit_to_window(dialog: QtWidgets.QDialog, parent: QtWidgets.QWidget) -> None:
    """Resize ``dialog`` to :func:`fitted_size` within :func:`room_for` ``parent`` (call before showing it)."""
    room = room_for(parent)
    dialog.resize(fitted_size(dialog, room).boundedTo(room))
