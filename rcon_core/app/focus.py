"""Where the keyboard goes when the widget that had it disappears (a page rebuilt, a notice dismissed).

Qt otherwise hands the focus to the next widget in the window's tab chain, which may be a field far away
(the robot URL, its text selected: one key would replace it).
"""

from __future__ import annotations

from qtpy import QtCore, QtWidgets


def first_focusable(container: QtWidgets.QWidget) -> QtWidgets.QWidget | None:
    """The first visible, enabled widget inside ``container`` that takes the focus from Tab, in tab order."""
    widget = container.nextInFocusChain()
    seen = 0
    while widget is not None and widget is not container and seen < 10_000:
        seen += 1
        if (container.isAncestorOf(widget) and widget.isVisible() and widget.isEnabled()
                and widget.focusPolicy() & QtCore.Qt.FocusPolicy.TabFocus):
            return widget
        widget = widget.nextInFocusChain()
    return None


def focus_into(container: QtWidgets.QWidget) -> QtWidgets.QWidget:
    """Give the focus to the first focusable widget inside ``container`` (else to ``container`` itself).
    Returns the widget that got it."""
    target = first_focusable(container) or container
    target.setFocus(QtCore.Qt.FocusReason.OtherFocusReason)
    return target


def has_focus_inside(container: QtWidgets.QWidget) -> bool:
    focus = QtWidgets.QApplication.focusWidget()
    return focus is not None and (focus is container or container.isAncestorOf(focus))
