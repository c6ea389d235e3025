"""A label that never widens (or heightens) its window: text that does not fit on one line goes on a second
line when the height it was given has room for two, and what still does not fit is cut with "…"; the
whole text is in its tooltip."""

from __future__ import annotations

from qtpy import QtCore, QtGui, QtWidgets


class OneLineLabel(QtWidgets.QLabel):
    """The base of a one-line label that elides its own text: no minimum width, one line's height, and
    :meth:`_elide` (the subclass's) run again whenever its room or font changes."""

    def __init__(self, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.setSizePolicy(QtWidgets.QSizePolicy.Policy.Ignored, QtWidgets.QSizePolicy.Policy.Preferred)

    def _elide(self) -> None:
        raise NotImplementedError

    def minimumSizeHint(self) -> QtCore.QSize:  # noqa: N802 - Qt's name
        return QtCore.QSize(0, super().minimumSizeHint().height())

    def resizeEvent(self, event: QtGui.QResizeEvent) -> None:  # noqa: N802
        super().resizeEvent(event)
        self._elide()

    def changeEvent(self, event: QtCore.QEvent) -> None:  # noqa: N802
        super().changeEvent(event)
        if event.type() in (QtCore.QEvent.Type.FontChange, QtCore.QEvent.Type.StyleChange,
                            QtCore.QEvent.Type.ContentsRectChange):
            self._elide()


class ElidedLabel(QtWidgets.QLabel):
    """Asks for no minimum width (a layout may give it any width) and one line's height, and shows as much
    of its text as fits; ``text()`` is the whole text, ``shown()`` what is on screen."""

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

    def _line_height(self) -> int:
        margins = self.contentsMargins()
        return self.fontMetrics().height() + margins.top() + margins.bottom() + 2 * self.margin()

    def minimumSizeHint(self) -> QtCore.QSize:  # noqa: N802
        return QtCore.QSize(0, self._line_height())

    def sizeHint(self) -> QtCore.QSize:  # noqa: N802
        return QtCore.QSize(0, self._line_height())

    def resizeEvent(self, event: object) -> None:  # noqa: N802
        super().resizeEvent(event)  # type: ignore[arg-type]
        self._elide()

    def _elide(self) -> None:
        rect = self.contentsRect()
        width = max(0, rect.width())
        fm = self.fontMetrics()
        full = self._full
        shown = fm.elidedText(full, QtCore.Qt.TextElideMode.ElideRight, width)
        if shown != full and rect.height() >= 2 * fm.lineSpacing():
            words, first = full.split(" "), ""
            for n in range(1, len(words) + 1):  # the most words that fit on the first line
                candidate = " ".join(words[:n])
                if fm.horizontalAdvance(candidate) > width:
                    break
                first = candidate
            if first:
                rest = full[len(first):].strip()
                shown = first + "\n" + fm.elidedText(rest, QtCore.Qt.TextElideMode.ElideRight, width)
        if shown != super().text():
            super().setText(shown)
