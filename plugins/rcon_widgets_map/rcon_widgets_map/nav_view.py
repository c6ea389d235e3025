"""The map's "Navigate here" controls (Qt): a long press proposes the point in the map's bubble, *Navigate
here* sends the goal (:mod:`.navigate`), a chip tells how it goes (distance remaining, then how it
ended), *Stop* cancels it. Only when the map's settings name a navigation action."""

from __future__ import annotations

from typing import Any

from qtpy import QtCore, QtGui, QtWidgets

#: how long a finger stays down (without moving) to make a long press
LONG_PRESS_MS = 600
NAV_COLOUR = QtGui.QColor("#0050d0")
#: phase -> (words, colour) on the chip
PHASE_CHIP = {
    "active": ("→ navigating", "#0050d0"),
    "canceling": ("⊘ stopping…", "#a05a00"),
    "succeeded": ("✓ arrived", "#006b1b"),
    "canceled": ("⊘ navigation canceled", "#a05a00"),
    "aborted": ("✗ navigation aborted", "#b00000"),
    "failed": ("✗ navigation failed", "#b00000"),
    "unknown": ("? navigation: fate unknown", "#a05a00"),
}


class NavigateControls:
    """Owned by a MapView; the view forwards presses, moves, releases and painting."""

    def __init__(self, view: Any) -> None:
        self.view = view
        self.pending: tuple[float, float] | None = None  #: the point proposed, until confirmed
        self.fired = False
        self._at: QtCore.QPointF | None = None
        self.timer = QtCore.QTimer(view)
        self.timer.setSingleShot(True)
        self.timer.setInterval(LONG_PRESS_MS)
        self.timer.timeout.connect(self._long_press)
        self.stop_button = QtWidgets.QToolButton(view)
        self.stop_button.setObjectName("mapNavStop")
        self.stop_button.setText("■ Stop")
        self.stop_button.setToolTip("Cancel the navigation goal")
        self.stop_button.clicked.connect(view.model.cancel_navigation)
        self.stop_button.hide()

    @property
    def enabled(self) -> bool:
        return bool(self.view.model.settings.navigate_action.strip())

    # -- gestures ---------------------------------------------------------------------------------
    def pressed(self, pos: QtCore.QPointF) -> None:
        self.fired = False
        if self.enabled:
            self._at = QtCore.QPointF(pos)
            self.timer.start()

    def moved(self) -> None:
        self.timer.stop()

    def released(self) -> bool:
        """True when the press was a long press (the view then does not take it as a tap)."""
        self.timer.stop()
        fired, self.fired = self.fired, False
        return fired

    def _long_press(self) -> None:
        if self._at is None or not self.enabled:
            return
        self.fired = True
        self.propose(self.view.viewport.to_latlon(self._at.x(), self._at.y()))

    def propose(self, point: tuple[float, float]) -> None:
        """Offer "Navigate here" for ``point`` in the bubble (nothing is sent yet)."""
        view = self.view
        view.pending = None  # one proposal at a time
        self.pending = point
        lat, lon = point
        view.bubble.label.setText(f"Navigate here?\n{lat:.6f}, {lon:.6f}\nvia {view.model.settings.navigate_action}")
        view.bubble.send.setText("Navigate here")
        view.bubble.adjustSize()
        view.bubble.show()
        view.bubble.raise_()
        view.place_bubble()
        view.update()

    def confirm(self) -> bool:
        if self.pending is None:
            return False
        lat, lon = self.pending
        self.close()
        return bool(self.view.model.navigate(lat, lon))

    def close(self) -> None:
        self.pending = None
        self.view.bubble.send.setText("Send goal")
        self.view.bubble.hide()
        self.view.update()

    # -- painting ---------------------------------------------------------------------------------
    def sync(self, value: Any) -> None:
        """A new map value: Stop is there while a navigation goal runs."""
        nav = getattr(value, "nav", None) if value is not None else None
        running = bool(nav is not None and nav.running)
        if running != self.stop_button.isVisible():
            self.stop_button.setVisible(running)

    def chip_text(self, nav: Any) -> tuple[str, str]:
        words, colour = PHASE_CHIP.get(nav.phase, (nav.phase, "#5a5a5a"))
        if nav.running and nav.remaining_m is not None:
            words += f": {nav.remaining_m:.0f} m to go"
        elif nav.text and not nav.running:
            words += f": {nav.text}"
        return words, colour

    def paint(self, p: QtGui.QPainter, value: Any, chip: Any) -> None:
        nav = getattr(value, "nav", None) if value is not None else None
        if self.pending is not None:
            self._marker(p, *self.pending, QtGui.QColor("#c05000"))
        if nav is None:
            return
        if nav.running:
            self._marker(p, nav.lat, nav.lon, NAV_COLOUR)
        words, colour = self.chip_text(nav)
        chip(p, QtCore.QPointF(8, self.view.height() - 84), words, QtGui.QColor(colour))

    def _marker(self, p: QtGui.QPainter, lat: float, lon: float, colour: QtGui.QColor) -> None:
        x, y = self.view.viewport.to_screen(lat, lon)
        p.setPen(QtGui.QPen(colour, 3))
        p.setBrush(QtCore.Qt.BrushStyle.NoBrush)
        p.drawRect(QtCore.QRectF(x - 9, y - 9, 18, 18))
        p.drawLine(QtCore.QPointF(x, y - 16), QtCore.QPointF(x, y + 16))
        p.drawLine(QtCore.QPointF(x - 16, y), QtCore.QPointF(x + 16, y))

    def place(self) -> None:
        """Put Stop at the bottom left, above the scale bar."""
        self.stop_button.adjustSize()
        self.stop_button.move(8, self.view.height() - 84 - self.stop_button.height() - 8)
