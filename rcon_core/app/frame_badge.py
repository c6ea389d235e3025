"""A widget frame's status badge (LINK DOWN, STALE, ERROR...) and the line a tap on it shows.

The badge sits at the right end of the frame's title bar (``widget_frame.WidgetFrame.layout_overlays``
places it); on a narrow frame it is compact so the title stays readable (:func:`badge_form`). The frame it
belongs to is its parent widget: anything with ``layout_overlays()`` and a ``reason_line``.
"""

from __future__ import annotations

from typing import Any

from qtpy import QtCore, QtGui, QtWidgets

from rcon_core.app.elided_label import OneLineLabel

__all__ = ["Badge", "ReasonLine", "badge_form"]


def _is_frame(widget: Any) -> bool:
    """Whether ``widget`` is a frame a badge belongs to (``layout_overlays()`` and a ``reason_line``)."""
    return widget is not None and hasattr(widget, "layout_overlays") and hasattr(widget, "reason_line")


class Badge(QtWidgets.QLabel):
    """A small status pill at the right end of the frame's title bar. Its tooltip is the reason (hover);
    a tap shows the reason on the frame, on one line under the title (:class:`ReasonLine`), and a second
    tap hides it.

    On a narrow frame the pill is compact, so the title stays readable (an operator must tell Battery from
    Dock exactly while their link is down): the frame picks the longest of its forms -- the whole word
    (``LINK DOWN``), the short one (``DOWN``), a sign (``!``) -- that leaves the title its whole text, or
    at least half the bar (:func:`badge_form`, from ``WidgetFrame.layout_overlays``). What the widget's status is stays in
    :attr:`status` (the whole word, whatever the pill shows), in its accessible name, and, while the pill
    is compact, at the head of its tooltip and of the tapped reason line."""

    COLOURS = {"stale": "#a85400", "down": "#b00000", "problem": "#b00000", "ok": "#006b1b",
               "view-only": "#3a3a3a"}
    #: the short word of each status word, for a frame with no room for the whole one
    SHORT = {"LINK DOWN": "DOWN", "PREVIEW ONLY": "PREVIEW", "VIEW ONLY": "VIEW"}
    #: the sign, for a frame with no room even for the short word (kinds without one keep the short word)
    SIGN = {"down": "!", "problem": "!", "stale": "!"}
    #: px of padding each side of the whole word (half of it around a compact form)
    PAD = 8

    def __init__(self, parent: QtWidgets.QWidget) -> None:
        super().__init__(parent)
        self.setObjectName("frameBadge")
        self.kind = ""
        self.reason = ""
        #: the status in words, whole ("LINK DOWN"), whatever form the pill shows; "" while hidden
        self.status = ""
        #: what the pill may show, longest first: the whole word, the short word, the sign
        self.forms: tuple[str, ...] = ()
        self.font_sheet = ""  #: the frame's text size for it (WidgetFrame.fit_text), "" for the app's
        self._refitting = False
        self.setCursor(QtCore.Qt.CursorShape.PointingHandCursor)
        self.setAlignment(QtCore.Qt.AlignmentFlag.AlignCenter)
        self.hide()

    def show_status(self, kind: str, text: str, reason: str = "") -> None:
        """Show ``text`` in ``kind``'s colour (``""``: hide); ``reason`` is the sentence behind it, shown on
        hover (the tooltip) and on a tap (the frame's reason line)."""
        if kind == self.kind and text == self.status and reason == self.reason:
            return
        self.kind, self.reason = kind, reason
        self.status = text if kind else ""
        forms = [text]
        for form in (self.SHORT.get(text, ""), self.SIGN.get(kind, "")):
            if form and form not in forms:
                forms.append(form)
        self.forms = tuple(forms)
        self.setAccessibleName(f"status: {text}" if kind else "")
        self.setAccessibleDescription(reason)
        frame = self._frame()
        if not kind:
            self.hide()
        else:
            self._show_form(text)
            self.restyle()
            self.show()
            self.raise_()
        if frame is not None:
            frame.layout_overlays()  # hidden: the title gets its full width back; shown: its form fitted
            frame.reason_line.follow(self)

    def _frame(self) -> Any:
        """The frame it belongs to (its parent, see the module docstring), or None."""
        parent = self.parentWidget()
        return parent if _is_frame(parent) else None

    @property
    def compact(self) -> bool:
        """Whether the pill shows less than the whole word (a short word or a sign)."""
        return bool(self.status) and self.text() != self.status

    def told(self) -> str:
        """What a hover or a tap tells: the reason; while compact, the whole status word before it."""
        if not self.compact:
            return self.reason
        return f"{self.status}: {self.reason}" if self.reason else self.status

    def _pad(self, form: str) -> int:
        """The pill's padding each side of ``form``: less for a compact one (more room for the title)."""
        return self.PAD if form == self.status else self.PAD // 2

    def form_width(self, form: str) -> int:
        """The pill's width showing ``form`` (its text, padding and border as styled)."""
        pad = self._pad(form)
        width = self.fontMetrics().horizontalAdvance(form) + 2 * pad + 2 * self.frameWidth()
        return max(width, self.sizeHint().height()) if len(form) == 1 else width

    def _show_form(self, form: str) -> None:
        self.setText(form)
        self.setToolTip(self.told())
        pad = self._pad(form)
        self.setContentsMargins(pad, 0, pad, 0)
        self._fit()

    def _fit(self) -> None:
        """Its size for what it shows; a sign is a square pill, never narrower than it is tall."""
        self.setMinimumWidth(min(self.sizeHint().height(), self.maximumHeight()) if len(self.text()) == 1 else 0)
        self.adjustSize()

    def show_form(self, form: str) -> None:
        """Show ``form`` (one of :attr:`forms`); the tooltip and the reason line follow."""
        if form == self.text():
            self._fit()  # the same form, in a bar that may have grown (another text size)
            return
        self._show_form(form)
        frame = self._frame()
        if frame is not None:
            frame.reason_line.follow(self)

    def restyle(self) -> None:
        """Its colour for its kind, at its frame's text size (a style sheet only when it changed)."""
        colour = self.COLOURS.get(self.kind, "#000000")
        sheet = (f"background:{colour}; color:#ffffff; font-weight:bold; border-radius:4px; padding:2px 0px;"
                 f"{self.font_sheet}")  # the sides: contents margins (_show_form), known without a restyle
        if sheet != self.styleSheet():
            self.setStyleSheet(sheet)
            self.adjustSize()

    def changeEvent(self, event: QtCore.QEvent) -> None:  # noqa: N802 - Qt's name
        super().changeEvent(event)
        # another text size (the app's, or the frame's): the pill's size follows, and its form with it
        if event.type() in (QtCore.QEvent.Type.FontChange, QtCore.QEvent.Type.StyleChange) and self.kind \
                and not self._refitting:
            self._refitting = True
            try:
                self._show_form(self.text())
                frame = self._frame()
                if frame is not None:
                    frame.layout_overlays()
            finally:
                self._refitting = False

    def mouseReleaseEvent(self, event: QtGui.QMouseEvent) -> None:  # noqa: N802 - Qt's name
        if event.button() == QtCore.Qt.MouseButton.LeftButton and self.rect().contains(event.position().toPoint()):
            frame = self._frame()
            if frame is not None:
                frame.reason_line.toggle(self)
        super().mouseReleaseEvent(event)


class ReasonLine(OneLineLabel):
    """The badge's reason on one line across the top of the frame's body, cut with "…" when it is too
    long (the whole sentence in its tooltip); shown by a tap on the badge, hidden by another tap on either."""

    def __init__(self, parent: QtWidgets.QWidget) -> None:
        super().__init__(parent)
        self.setObjectName("frameReason")
        self.full = ""  # its look: QLabel#frameReason in theme.qss
        self.hide()

    def toggle(self, badge: Badge) -> None:
        if self.isVisible() or not badge.told():
            self.hide()
            return
        self.full = ""
        self.follow(badge)
        self.show()
        self.raise_()

    def follow(self, badge: Badge) -> None:
        """The badge changed: the line says its new reason, or goes away with it."""
        told = badge.told()
        if not badge.isVisible() or not told:
            self.hide()
            return
        if told != self.full:
            self.full = told
            self.setToolTip(told)
            self.setAccessibleName(told)
            self._elide()

    def _elide(self) -> None:
        room = self.contentsRect().width()
        self.setText(self.fontMetrics().elidedText(self.full, QtCore.Qt.TextElideMode.ElideRight, max(0, room)))

    def mouseReleaseEvent(self, event: QtGui.QMouseEvent) -> None:  # noqa: N802 - Qt's name
        self.hide()
        super().mouseReleaseEvent(event)


def badge_form(badge: Badge, title: Any) -> str:
    """The longest of ``badge``'s forms that leaves ``title`` (the frame's ``FrameTitle``: its
    ``full_title``, its contents rect less its right margin for the badge) its whole text, or at least half
    the bar; the shortest where none does (see :class:`Badge`)."""
    forms = badge.forms
    if not forms:
        return badge.text()
    margins = title.contentsMargins()
    bar = title.contentsRect().width()
    need = min(title.fontMetrics().horizontalAdvance(title.full_title), bar // 2)
    for form in forms[:-1]:
        reserve = max(0, badge.form_width(form) + 6 - margins.right())
        if bar - reserve >= need:
            return form
    return forms[-1]
