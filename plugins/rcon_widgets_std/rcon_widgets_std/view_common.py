"""Qt helpers shared by the standard widgets' views (imports Qt: only view modules import this)."""

from __future__ import annotations

from typing import Any

from qtpy import QtCore, QtGui, QtWidgets

OK = "#006b1b"
BAD = "#b00000"
STALE = "#a85400"
MUTED = "#5a5a5a"
LEVEL_COLOURS = {"debug": "#6a6a6a", "info": "#000000", "warn": "#a85400", "error": "#b00000", "fatal": "#8a0070"}


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
        self.setStyleSheet(f"color: {colour}; background: transparent;")

    def show_text(self, text: str, colour: str = MUTED, tooltip: str | None = None) -> None:
        self.set_colour(colour)
        if text != self.text():
            self.setText(text)
        tip = tooltip if tooltip is not None else text
        if tip != self.toolTip():
            self.setToolTip(tip)


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


def style_text(label: QtWidgets.QLabel, px: int, colour: str = "", bold: bool = True) -> None:
    """Size and colour through a style sheet (the app's theme sets font sizes by style sheet too, which
    would override ``setFont``). Does nothing when the label already has exactly this style (setting a
    style sheet re-polishes the widget, even an identical one)."""
    weight = "bold" if bold else "normal"
    tint = f" color: {colour};" if colour else ""
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
