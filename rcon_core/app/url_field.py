"""The robot URL's line edit (inside the connection bar's combo box): a URL too long for the field shows
the robot's host, the part that tells robots apart, while the field is not being edited.

A line edit scrolled to its cursor shows the URL's end and a plain right elision its scheme: on a 1024 px
tablet both hid the host (``ws:…971``, ``ws://1…1:45991``), so an operator could not see which robot the
window was on. :func:`elide_url` gives the URL up in this order, its host last: the path, the scheme (a
``…`` says something is left out; not for ``ws://``, which the field supplies to a URL typed without
one), the port; then the host itself is cut, keeping the end of an address (``…168.1.10``) and the start
of a name (``kingfisher-07.har…``). The field's value is always the whole
URL; while it has the keyboard it shows the whole text to edit; the whole URL is also its tooltip.
"""

from __future__ import annotations

import re

from qtpy import QtCore, QtGui, QtWidgets

__all__ = ["UrlCombo", "UrlLineEdit", "elide_url", "host_text", "url_parts"]

#: QLineEdit's own horizontal text margin (qlineedit_p.h's horizontalMargin)
TEXT_MARGIN = 2
#: an IPv4 address, or an IPv6 one in brackets: its end tells machines on one network apart
_ADDRESS = re.compile(r"^(\d{1,3}(\.\d{1,3}){3}|\[[0-9A-Fa-f:.]*\])$")


def url_parts(url: str) -> tuple[str, str, str, str]:
    """``url`` as (scheme with ``://``, host, ``:port``, path and the rest); parts it lacks are ""."""
    scheme_end = url.find("://")
    head = url[: scheme_end + 3] if scheme_end >= 0 else ""
    rest = url[len(head):]
    cut = min((i for i in (rest.find("/"), rest.find("?"), rest.find("#")) if i >= 0), default=len(rest))
    where, path = rest[:cut], rest[cut:]
    colon = where.rfind(":")
    if colon > where.rfind("]"):  # a port (an IPv6 host's colons are inside its brackets)
        return head, where[:colon], where[colon:], path
    return head, where, "", path


def host_text(url: str) -> str:
    """What :func:`elide_url` shows of ``url`` once its scheme and path are left out: ``…host:port``; a
    plain ``ws://`` URL without a path as ``host:port``, nothing marked left out: the field reads that as
    the same URL (no scheme means ``ws://``)."""
    head, host, port, path = url_parts(url)
    if not host:
        return url
    return _lead(head, path) + host + port + ("…" if path else "")


def _lead(head: str, path: str) -> str:
    """"…" before the host when what is left out before it changes the URL (not a plain ``ws://``)."""
    return "" if head in ("", "ws://") and not path else "…"


def elide_url(fm: QtGui.QFontMetrics, url: str, width: int) -> str:
    """``url`` made to fit ``width`` pixels, its host kept longest: whole; without its path; without its
    scheme (:func:`host_text`: ``…robot.example.org:9090``, ``localhost:9090``); without its port
    (``192.168.1.10…``); then the host cut to fit, an address keeping its end and a name its start."""
    if fm.horizontalAdvance(url) <= width:
        return url
    head, host, port, path = url_parts(url)
    if not host:
        return fm.elidedText(url, QtCore.Qt.TextElideMode.ElideMiddle, width)
    candidates = [head + host + port + "…"] if path and head else []
    candidates.append(host_text(url))
    if port:
        candidates.append(_lead(head, path) + host + "…")
    for text in candidates:
        if fm.horizontalAdvance(text) <= width:
            return text
    mode = QtCore.Qt.TextElideMode.ElideLeft if _ADDRESS.match(host) else QtCore.Qt.TextElideMode.ElideRight
    return fm.elidedText(host, mode, width)


class UrlLineEdit(QtWidgets.QLineEdit):
    def __init__(self, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        #: what the last paint showed (tests, accessibility): the text, or its middle-elided form
        self.painted = ""
        self.textChanged.connect(self.setToolTip)

    def text_rect(self) -> QtCore.QRect:
        opt = QtWidgets.QStyleOptionFrame()
        self.initStyleOption(opt)
        rect = self.style().subElementRect(QtWidgets.QStyle.SubElement.SE_LineEditContents, opt, self)
        m = self.textMargins()
        return rect.adjusted(m.left() + TEXT_MARGIN, m.top(), -m.right() - TEXT_MARGIN, -m.bottom())

    def shown_text(self) -> str:
        """What the field shows now: the whole text while editing or when it fits, else its host in sight."""
        text = self.text()
        if self.hasFocus() or not text:
            return text
        return elide_url(self.fontMetrics(), text, self.text_rect().width())

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
        painter.drawText(self.text_rect(), int(QtCore.Qt.AlignmentFlag.AlignLeft | QtCore.Qt.AlignmentFlag.AlignVCenter),
                         shown)
        painter.end()


class UrlCombo(QtWidgets.QComboBox):
    """The editable combo box holding a :class:`UrlLineEdit`: its size hint asks for :attr:`extra` px more
    than its minimum, the room its bar found for showing the robot's host, or the whole URL
    (ConnectionBar._share_room); :meth:`width_for` measures what a text needs."""

    def __init__(self, parent: QtWidgets.QWidget | None = None) -> None:
        self.extra = 0
        super().__init__(parent)
        self.setEditable(True)
        self.setLineEdit(UrlLineEdit())

    def url_line(self) -> UrlLineEdit:
        line = self.lineEdit()
        assert isinstance(line, UrlLineEdit)
        return line

    def width_for(self, text: str) -> int:
        """The field's width that shows ``text`` whole, as laid out now (0 before it is: the room its frame
        and arrow take is measured)."""
        line = self.url_line()
        if not self.isVisible() or line.width() <= 0:
            return 0
        chrome = self.width() - line.text_rect().width()
        return chrome + line.fontMetrics().horizontalAdvance(text) + 1

    def set_extra(self, px: int) -> None:
        if px != self.extra:
            self.extra = px
            self.updateGeometry()

    def sizeHint(self) -> QtCore.QSize:  # noqa: N802 - Qt's name
        hint = super().sizeHint()
        return QtCore.QSize(max(hint.width(), self.minimumSizeHint().width() + self.extra), hint.height())
