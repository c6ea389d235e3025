"""A one-line label that never widens its window: long text is cut with "…", the whole text in its tooltip."""

from __future__ import annotations

from qtpy import QtCore, QtWidgets


class ElidedLabel(QtWidgets.QLabel):
    """Asks for no minimum width (a layout may give it any width) and shows as much of its text as fits;
    ``text()`` is the whole text, ``shown()`` what is on screen."""

    def __init__(self, text: str = "", parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self._full = ""
        self.setSizePolicy(QtWidgets.QSizePolicy.Policy.Ignored, QtWidgets.QSizePolicy.Policy.Preferred)
        self.setMinimumWidth(0)
        self.setText(text)

    def setText(self, text: str) -> None:  # noqa: N802 - Qt's name
        text = " ".join(str(text).split())  # one line: a newline would grow the bar's height
        if text == self._full and self.toolTip() == text:
            return
        self._full = text
        self.setToolTip(text)
        self._elide()

    def text(self) -> str:
        return self._full

    def shown(self) -> str:
        return super().text()

    def clear(self) -> None:
        self.setText("")

    def minimumSizeHint(self) -> QtCore.QSize:  # noqa: N802
        return QtCore.QSize(0, super().minimumSizeHint().height())

    def sizeHint(self) -> QtCore.QSize:  # noqa: N802
        return QtCore.QSize(0, super().sizeHint().height())

    def resizeEvent(self, event: object) -> None:  # noqa: N802
        super().resizeEvent(event)  # type: ignore[arg-type]
        self._elide()

    def _elide(self) -> None:
        width = max(0, self.contentsRect().width())
        shown = self.fontMetrics().elidedText(self._full, QtCore.Qt.TextElideMode.ElideRight, width)
        if shown != super().text():
            super().setText(shown)
