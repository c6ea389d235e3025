"""The robot URL's line edit (inside the connection bar's combo box): a URL too long for the field shows
its beginning and its end, ``wss://operations-ves…example.org:9090``, while the field is not being edited.

A line edit scrolled to its cursor cuts the scheme off (``'s://127…``), and a plain right elision would
cut the port: the two parts that tell robots apart. The field's value is always the whole URL; while it
has the keyboard it shows the whole text to edit; the whole URL is also its tooltip.
"""

from __future__ import annotations

from qtpy import QtCore, QtGui, QtWidgets

__all__ = ["UrlLineEdit", "elide_url"]

#: QLineEdit's own horizontal text margin (qlineedit_p.h's horizontalMargin)
TEXT_MARGIN = 2


def elide_url(fm: QtGui.QFontMetrics, url: str, width: int) -> str:
    """``url`` made to fit ``width`` pixels: the scheme (``wss://``) and the port and path (``:9090``) kept
    whole and the host's middle elided, so a narrow field still tells ``ws://`` from ``wss://`` and one
    port from another; a field too narrow even for those two ends gets Qt's middle elision."""
    if fm.horizontalAdvance(url) <= width:
        return url
    scheme_end = url.find("://")
    head = url[: scheme_end + 3] if scheme_end >= 0 else ""
    rest = url[len(head):]
    cut = min((i for i in (rest.rfind(":"), rest.find("/")) if i > 0), default=len(rest))
    host, tail = rest[:cut], rest[cut:]
    room = width - fm.horizontalAdvance(head) - fm.horizontalAdvance(tail)
    if head and host and room >= fm.horizontalAdvance("…"):
        return head + fm.elidedText(host, QtCore.Qt.TextElideMode.ElideMiddle, room) + tail
    return fm.elidedText(url, QtCore.Qt.TextElideMode.ElideMiddle, width)


class UrlLineEdit(QtWidgets.QLineEdit):
    def __init__(self, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        #: what the last paint showed (tests, accessibility): the text, or its middle-elided form
        self.painted = ""
        self.textChanged.connect(self.setToolTip)

    def _text_rect(self) -> QtCore.QRect:
        opt = QtWidgets.QStyleOptionFrame()
        self.initStyleOption(opt)
        rect = self.style().subElementRect(QtWidgets.QStyle.SubElement.SE_LineEditContents, opt, self)
        m = self.textMargins()
        return rect.adjusted(m.left() + TEXT_MARGIN, m.top(), -m.right() - TEXT_MARGIN, -m.bottom())

    def shown_text(self) -> str:
        """What the field shows now: the whole text while editing or when it fits, else its two ends."""
        text = self.text()
        if self.hasFocus() or not text:
            return text
        return elide_url(self.fontMetrics(), text, self._text_rect().width())

    def paintEvent(self, event: QtGui.QPaintEvent) -> None:  # noqa: N802 - Qt's name
        shown = self.shown_text()
        self.painted = shown
        if shown == self.text():
            super().paintEvent(event)
            return
        painter = QtWidgets.QStylePainter(self)
        opt = QtWidgets.QStyleOptionFrame()
        self.initStyleOption(opt)
        painter.drawPrimitive(QtWidgets.QStyle.PrimitiveElement.PE_PanelLineEdit, opt)
        painter.setPen(self.palette().color(QtGui.QPalette.ColorRole.Text))
        painter.drawText(self._text_rect(), int(QtCore.Qt.AlignmentFlag.AlignLeft | QtCore.Qt.AlignmentFlag.AlignVCenter),
                         shown)
        painter.end()
