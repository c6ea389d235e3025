"""Qt helpers shared by the standard widgets' views (imports Qt: only view modules import this)."""

from __future__ import annotations

from typing import Any

from qtpy import QtCore, QtGui, QtWidgets

OK = "#006b1b"
BAD = "#b00000"
STALE = "#a85400"
MUTED = "#5a5a5a"
LEVEL_COLOURS = {"debug": "#6a6a6a", "info": "#000000", "warn": "#a85400", "error": "#b00000", "fatal": "#8a0070"}
#: the same meanings on a dark palette (the app's night theme): light enough to read, not glaring
ON_DARK = {OK: "#5fd47a", BAD: "#ff7b72", STALE: "#f0a040", MUTED: "#a0a6ad", "#6a6a6a": "#9aa0a6",
           "#000000": "#e2e4e7", "#8a0070": "#ff6ad5", "#00558f": "#6cb6ff"}


def tone(widget: QtWidgets.QWidget, colour: str) -> str:
    """``colour`` as it reads on ``widget``'s palette: one of the colours above is swapped for its light
    twin when the widget sits on a dark background (another colour, or "" for the palette's text, is kept)."""
    if not colour:
        return colour
    behind: QtWidgets.QWidget | None = widget  # the first one with a background of its own
    while behind is not None and behind.palette().color(QtGui.QPalette.ColorRole.Window).alpha() < 255:
        behind = behind.parentWidget()
    if (behind or widget).palette().color(QtGui.QPalette.ColorRole.Window).lightness() < 128:
        return ON_DARK.get(colour.lower(), colour)
    return colour


def age_text(age: float | None) -> str:
    """``0.4 s ago``, ``3 min ago``; "no data yet" before the first value."""
    if age is None:
        return "no data yet"
    if age < 60:
        return f"{age:.1f} s ago"
    if age < 3600:
        return f"{age / 60:.0f} min ago"
    return f"{age / 3600:.1f} h ago"


class Caption(QtWidgets.QLabel):
    """A small secondary line (status, age, the server's reply) that elides instead of growing.

    Every setter skips when nothing changed: a style sheet re-polishes the label and a new text re-lays
    it out, and views call these on every refresh (up to 60 times a second)."""

    def __init__(self, text: str = "", parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(text, parent)
        font = self.font()
        font.setPointSizeF(max(7.0, font.pointSizeF() * 0.85))
        self.setFont(font)
        self.setSizePolicy(QtWidgets.QSizePolicy.Policy.Ignored, QtWidgets.QSizePolicy.Policy.Preferred)
        self._colour: str | None = None
        self.set_colour(MUTED)

    @property
    def colour(self) -> str | None:
        """The colour last set (None before the first)."""
        return self._colour

    def set_colour(self, colour: str) -> None:
        if colour == self._colour:
            return
        self._colour = colour
        self._apply_colour()

    def _apply_colour(self) -> None:
        sheet = f"color: {tone(self, self._colour or MUTED)}; background: transparent;"
        if sheet != self.styleSheet():
            self.setStyleSheet(sheet)

    def changeEvent(self, event: QtCore.QEvent) -> None:  # noqa: N802 - Qt override
        super().changeEvent(event)
        if event.type() == QtCore.QEvent.Type.ParentChange or (
                event.type() == QtCore.QEvent.Type.StyleChange and self._colour is not None
                and not self.styleSheet().startswith(f"color: {tone(self, self._colour)};")):
            self._apply_colour()  # placed, or another theme: the colour's twin for it

    def paintEvent(self, event: Any) -> None:  # noqa: N802 - Qt override
        text, rect = self.text(), self.contentsRect()
        if not text or "\n" in text or self.fontMetrics().horizontalAdvance(text) <= rect.width():
            super().paintEvent(event)  # fits: QLabel's own painting
            return
        # too wide: a slightly smaller font, then "…" (QLabel alone would clip, centred: on both sides)
        font, shown = fit_line(self.font(), text, rect.width(), min_px=max(8, round(_pixel_size(self.font()) * 0.8)))
        painter = QtGui.QPainter(self)
        painter.setFont(font)
        painter.setPen(QtGui.QColor(tone(self, self._colour or MUTED)))
        align = self.alignment()
        if shown != text:  # elided: start at the left, so what is shown is the beginning
            align = (align & QtCore.Qt.AlignmentFlag.AlignVertical_Mask) | QtCore.Qt.AlignmentFlag.AlignLeft
        painter.drawText(rect, align, shown)
        painter.end()

    def show_text(self, text: str, colour: str = MUTED, tooltip: str | None = None) -> None:
        self.set_colour(colour)
        if text != self.text():
            self.setText(text)
        tip = tooltip if tooltip is not None else text
        if tip != self.toolTip():
            self.setToolTip(tip)


def _pixel_size(font: QtGui.QFont) -> float:
    """The font's size in pixels, whether it was given in pixels or points."""
    if font.pixelSize() > 0:
        return float(font.pixelSize())
    return float(QtGui.QFontInfo(font).pixelSize())


def fit_line(font: QtGui.QFont, text: str, width: float, min_px: int = 10) -> tuple[QtGui.QFont, str]:
    """The largest copy of ``font`` (never larger, never below ``min_px``) in which one line of ``text`` fits
    ``width`` pixels, and the text to draw: ``text`` itself, or elided with "…" when even ``min_px`` is
    too wide. Never clips silently."""
    fm = QtGui.QFontMetricsF(font)
    full = fm.horizontalAdvance(text)
    if full <= width or not text:
        return font, text
    px = _pixel_size(font)
    f = QtGui.QFont(font)
    size = max(min_px, int(px * width / full))
    while True:
        f.setPixelSize(size)
        if QtGui.QFontMetricsF(f).horizontalAdvance(text) <= width or size <= min_px:
            break
        size -= 1
    if QtGui.QFontMetricsF(f).horizontalAdvance(text) > width:
        return f, QtGui.QFontMetrics(f).elidedText(text, QtCore.Qt.TextElideMode.ElideRight, max(0, int(width)))
    return f, text


class FitLabel(QtWidgets.QWidget):
    """A value in large type that shrinks its font to fit its box (eliding with "…" only below
    ``min_px``), so a long value is never clipped silently.

    Painted directly: a new text costs one width measurement and one repaint of this widget -- no text
    document, no style sheet, no re-layout (a selectable QLabel lays out a text document per value).
    Multi-line text (a message as YAML) is shrunk to fit both ways, then cut per line and at the bottom.
    """

    def __init__(self, text: str = "", px: int = 30, bold: bool = True, min_px: int = 11,
                 parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self._text = text
        self._px, self._bold, self._colour = px, bold, ""
        self.min_px = min_px
        self._align = QtCore.Qt.AlignmentFlag.AlignCenter
        self._fitted: tuple[tuple[str, int, int, int, bool], QtGui.QFont, str] | None = None
        self._fonts: dict[tuple[int, bool], tuple[QtGui.QFont, QtGui.QFontMetricsF]] = {}
        self._pen: QtGui.QColor | None = None  # the colour to paint in (None: the palette's text colour)
        self.setAttribute(QtCore.Qt.WidgetAttribute.WA_OpaquePaintEvent, False)

    # -- QLabel-like API -----------------------------------------------------------------------------
    def text(self) -> str:
        return self._text

    def setText(self, text: str) -> None:  # noqa: N802 - QLabel's name
        if text != self._text:
            self._text = text
            self.update()

    def alignment(self) -> QtCore.Qt.AlignmentFlag:
        return self._align

    def setAlignment(self, align: QtCore.Qt.AlignmentFlag) -> None:  # noqa: N802 - QLabel's name
        if align != self._align:
            self._align = align
            self.update()

    def set_style(self, px: int, colour: str = "", bold: bool = True) -> None:
        """Largest size (px), colour ("" = the palette's text colour) and weight; repaints on a change only."""
        if (px, colour, bold) != (self._px, self._colour, self._bold):
            self._px, self._colour, self._bold = px, colour, bold
            self._pen = QtGui.QColor(colour) if colour else None
            self.update()

    def changeEvent(self, event: QtCore.QEvent) -> None:  # noqa: N802 - Qt override
        if event.type() in (QtCore.QEvent.Type.FontChange, QtCore.QEvent.Type.StyleChange):
            self._fonts.clear()  # the theme gave another family or size: measure again
            self._fitted = None
        super().changeEvent(event)

    @property
    def style_spec(self) -> tuple[int, str, bool]:
        return self._px, self._colour, self._bold

    def sizeHint(self) -> QtCore.QSize:  # noqa: N802 - Qt override
        return QtCore.QSize(80, round(self._px * 1.4))

    def minimumSizeHint(self) -> QtCore.QSize:  # noqa: N802 - Qt override
        return QtCore.QSize(20, round(self.min_px * 1.4))

    # -- fitting and painting ------------------------------------------------------------------------
    def _base(self, px: int) -> tuple[QtGui.QFont, QtGui.QFontMetricsF]:
        """The widget's font at ``px`` in the current weight, and its metrics (cached: fonts and metrics
        are costly to build, and a value changing 20 times a second mostly fits at the same size)."""
        key = (px, self._bold)
        got = self._fonts.get(key)
        if got is None:
            if len(self._fonts) > 64:
                self._fonts.clear()
            font = QtGui.QFont(self.font())
            font.setPixelSize(px)
            font.setBold(self._bold)
            got = self._fonts[key] = (font, QtGui.QFontMetricsF(font))
        return got

    def fitted(self) -> tuple[QtGui.QFont, str]:
        """(font, text) as painted at the current size; cached until the text, size or style changes."""
        rect = self.contentsRect()
        key = (self._text, rect.width(), rect.height(), self._px, self._bold)
        if self._fitted is not None and self._fitted[0] == key:
            return self._fitted[1], self._fitted[2]
        if "\n" in self._text:
            font, shown = self._fit_block(self._base(self._px)[0], rect)
        else:
            # the line height must fit too (a short, wide box)
            tall = max(self.min_px, min(self._px, int(rect.height() / 1.25))) if rect.height() > 0 else self._px
            font, metrics = self._base(tall)
            if metrics.horizontalAdvance(self._text) <= rect.width():
                shown = self._text  # the usual case: fits at full size
            else:
                font, shown = fit_line(font, self._text, rect.width(), min(self.min_px, tall))
        self._fitted = (key, font, shown)
        return font, shown

    def _fit_block(self, base: QtGui.QFont, rect: QtCore.QRect) -> tuple[QtGui.QFont, str]:
        lines = self._text.split("\n")
        fm = QtGui.QFontMetricsF(base)
        wide = max(fm.horizontalAdvance(line) for line in lines) or 1.0
        tall = fm.lineSpacing() * len(lines) or 1.0
        scale = min(1.0, rect.width() / wide, rect.height() / tall)
        font = QtGui.QFont(base)
        font.setPixelSize(max(self.min_px, int(self._px * scale)))
        fm = QtGui.QFontMetricsF(font)
        if scale * self._px >= self.min_px:
            return font, self._text
        room = max(1, int(rect.height() // fm.lineSpacing()))
        shown = lines[:room]
        if len(lines) > room:
            shown[-1] = "…"
        metrics = QtGui.QFontMetrics(font)
        elide = QtCore.Qt.TextElideMode.ElideRight
        return font, "\n".join(metrics.elidedText(line, elide, rect.width()) for line in shown)

    def paintEvent(self, event: Any) -> None:  # noqa: N802 - Qt override
        if not self._text:
            return
        font, shown = self.fitted()
        painter = QtGui.QPainter(self)
        painter.setFont(font)
        pen = QtGui.QColor(tone(self, self._colour)) if self._pen is not None else \
            self.palette().color(QtGui.QPalette.ColorRole.WindowText)
        painter.setPen(pen)
        painter.drawText(self.contentsRect(), int(self._align), shown)
        painter.end()


def vbox(widget: QtWidgets.QWidget, margins: int = 6, spacing: int = 4) -> QtWidgets.QVBoxLayout:
    layout = QtWidgets.QVBoxLayout(widget)
    layout.setContentsMargins(margins, margins, margins, margins)
    layout.setSpacing(spacing)
    return layout


def age_timer(view: QtWidgets.QWidget, fn: Any, ms: int = 500) -> QtCore.QTimer:
    """A timer that re-reads the model's state to age the shown value (no repaint of the rest)."""
    timer = QtCore.QTimer(view)
    timer.setInterval(ms)
    timer.timeout.connect(fn)
    timer.start()
    return timer


def style_text(label: QtWidgets.QWidget, px: int, colour: str = "", bold: bool = True) -> None:
    """Size and colour through a style sheet (the app's theme sets font sizes by style sheet too, which
    would override ``setFont``). Does nothing when the label already has exactly this style (setting a
    style sheet re-polishes the widget, even an identical one)."""
    weight = "bold" if bold else "normal"
    tint = f" color: {tone(label, colour)};" if colour else ""
    sheet = f"font-size: {px}px; font-weight: {weight};{tint} background: transparent;"
    if sheet != label.styleSheet():
        label.setStyleSheet(sheet)


def fit_caption(owner: QtWidgets.QWidget, main: QtWidgets.QWidget, caption: QtWidgets.QLabel) -> bool:
    """Show ``caption`` under ``main`` only when both fit in ``owner``'s height; otherwise hide it (its text
    stays reachable as ``main``'s tooltip) so the two never overlap in a small frame. Call from
    ``resizeEvent`` and after the caption's text changes. Returns whether the caption is shown."""
    layout = owner.layout()
    m = layout.contentsMargins() if layout is not None else QtCore.QMargins()
    spacing = max(0, layout.spacing()) if layout is not None else 0
    main_h = max(main.minimumSizeHint().height(), main.minimumHeight())
    need = main_h + spacing + caption.sizeHint().height() + m.top() + m.bottom()
    show = owner.height() >= need  # an empty caption keeps its line when there is room: no jumping
    if show == caption.isHidden():
        caption.setVisible(show)
    tip = "" if show else caption.text()
    if main.toolTip() != tip:
        main.setToolTip(tip)
    return show


def big_font(widget: QtWidgets.QWidget, factor: float = 1.8, bold: bool = True) -> QtGui.QFont:
    font = QtGui.QFont(widget.font())
    font.setPointSizeF(font.pointSizeF() * factor)
    font.setBold(bold)
    return font


#: how long a button's face shows an answer ("✓ docked", "✗ already docked") before its label returns
FLASH_MS = 2000


class ButtonFace:
    """What a push button's face says: its resting label, "<label>…" while a call is in flight, and an
    answer flashed in green or red for :data:`FLASH_MS` before the label returns. A touch operator looks
    at the button, not at a caption line (hidden in a short frame) or a tooltip (no hover on a touch
    screen). The text is elided to the button's width ("✗ interlock op…"); call :meth:`fit` from the
    owner's ``resizeEvent``."""

    def __init__(self, button: QtWidgets.QPushButton, label: str) -> None:
        self.button = button
        self.label = label
        self.text = label  #: what the face says now (before eliding)
        self.flashing: str | None = None  #: the colour of the answer being flashed, None when resting
        self._busy = False
        self._timer = QtCore.QTimer(button)
        self._timer.setSingleShot(True)
        self._timer.timeout.connect(self.rest)
        self._show(label, None)

    def set_label(self, label: str) -> None:
        """The resting text (a switch's On/Off): shown at once unless busy or flashing."""
        self.label = label
        if not self._busy and self.flashing is None:
            self._show(label, None)

    def busy(self, text: str | None = None) -> None:
        """A call is in flight: "<label>…" (or ``text``) until :meth:`answer` or :meth:`rest`."""
        self._timer.stop()
        self._busy = True
        self.flashing = None
        self._show(text if text is not None else f"{self.label}…", None)

    def answer(self, ok: bool, text: str, ms: int | None = None) -> None:
        """Flash "✓ text" (green) or "✗ text" (red) for ``ms`` (default :data:`FLASH_MS`), then the label."""
        self._busy = False
        self.flashing = OK if ok else BAD
        first = text.strip().splitlines()[0] if text.strip() else ""
        self._show(f"{'✓' if ok else '✗'} {first}".strip(), self.flashing)
        self._timer.start(FLASH_MS if ms is None else ms)

    def rest(self) -> None:
        """Back to the label now."""
        self._timer.stop()
        self._busy = False
        self.flashing = None
        self._show(self.label, None)

    def fit(self) -> None:
        """Elide the face's text to the button's current width."""
        width = self.button.width() - 20  # the theme's padding
        shown = self.text
        metrics = self.button.fontMetrics()
        if width > 0 and metrics.horizontalAdvance(shown) > width:
            shown = metrics.elidedText(shown, QtCore.Qt.TextElideMode.ElideRight, width)
        if shown != self.button.text():
            self.button.setText(shown)

    def _show(self, text: str, colour: str | None) -> None:
        self.text = text
        sheet = (f"QPushButton, QPushButton:checked {{ background: {colour}; color: #ffffff; "
                 f"border-color: {colour}; }}") if colour else ""
        if sheet != self.button.styleSheet():
            self.button.setStyleSheet(sheet)
        self.fit()
