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
    """A small secondary line (status, age, the server's reply) that elides instead of growing."""

    def __init__(self, text: str = "", parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(text, parent)
        font = self.font()
        font.setPointSizeF(max(7.0, font.pointSizeF() * 0.85))
        self.setFont(font)
        self.setSizePolicy(QtWidgets.QSizePolicy.Policy.Ignored, QtWidgets.QSizePolicy.Policy.Preferred)
        self.set_colour(MUTED)

    def set_colour(self, colour: str) -> None:
        self.setStyleSheet(f"color: {colour}; background: transparent;")

    def show_text(self, text: str, colour: str = MUTED, tooltip: str | None = None) -> None:
        self.set_colour(colour)
        self.setText(text)
        self.setToolTip(tooltip if tooltip is not None else text)


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
    would override ``setFont``)."""
    weight = "bold" if bold else "normal"
    tint = f" color: {colour};" if colour else ""
    label.setStyleSheet(f"font-size: {px}px; font-weight: {weight};{tint} background: transparent;")


def big_font(widget: QtWidgets.QWidget, factor: float = 1.8, bold: bool = True) -> QtGui.QFont:
    font = QtGui.QFont(widget.font())
    font.setPointSizeF(font.pointSizeF() * factor)
    font.setBold(bold)
    return font
