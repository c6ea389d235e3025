"""The canvas tab bar: a name is shown whole (up to about 12 letters) and the bar scrolls instead.

Qt's tab bar with right-eliding shrinks *every* tab a little ("Senso…") as soon as the tabs do not all
fit, before it shows its scroll buttons. A canvas name cut mid-word is hard to read on a tablet, so a
tab is never made narrower than its whole name; only a name longer than about 12 letters is elided.
"""

from __future__ import annotations

from qtpy import QtCore, QtWidgets

#: a longer canvas name is elided to about this many letters
READABLE_LETTERS = 12


class CanvasTabs(QtWidgets.QTabBar):
    def __init__(self, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.setObjectName("canvasTabs")
        self.setExpanding(False)
        self.setDrawBase(False)
        self.setElideMode(QtCore.Qt.TextElideMode.ElideRight)
        self.setUsesScrollButtons(True)

    def minimumTabSizeHint(self, index: int) -> QtCore.QSize:  # noqa: N802 - Qt override
        whole = self.tabSizeHint(index)
        readable = self.fontMetrics().horizontalAdvance("M" * READABLE_LETTERS)
        return QtCore.QSize(min(whole.width(), readable), whole.height())
