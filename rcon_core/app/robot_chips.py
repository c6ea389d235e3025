"""The robots bar under the connection bar: a chip per robot (its colour, name, link state, round trip),
all shown together, and the side panel's robot picker.

A tap on a chip picks that robot for the side panel (its topics and services; new widgets are bound to
it); the picked chip is filled. The bar shows only when the workspace has more than one robot, so a
one-robot window looks as it always did (the connection bar says its state and round trip). The picker
(:class:`RobotPicker`, one at the top of the Topics and of the Services list) says which robot the list
is of and picks another the same way.
"""

from __future__ import annotations

from qtpy import QtCore, QtGui, QtWidgets

from rcon_core.app.connection_bar import LIVE_STATES, STATE_TEXT
from rcon_core.bridge import ConnectionState

#: chip text colour on each state (the chip's own colour is its robot's, on its left edge)
STATE_STYLE = {
    ConnectionState.CONNECTED: ("#ffffff", "#006b2e"),
    ConnectionState.DEGRADED: ("#000000", "#ffcc00"),
    ConnectionState.CONNECTING: ("#000000", "#d8d8d8"),
    ConnectionState.RECONNECTING: ("#000000", "#ffcc00"),
    ConnectionState.CLOSED: ("#ffffff", "#a00000"),
}


def latency_text(latency: float | None) -> str:
    if latency is None:
        return "—"
    return "<1 ms" if latency < 0.0005 else f"{latency * 1000:.0f} ms"


class RobotChip(QtWidgets.QPushButton):
    """One robot: ``● name  STATE  12 ms``; checked when it is the side panel's robot."""

    def __init__(self, robot_id: str, name: str, colour: str, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.robot_id = robot_id
        self.setObjectName(f"robotChip-{robot_id}")
        self.setCheckable(True)
        self.setAccessibleName(f"robot {name}")
        self.name, self.colour = name, colour
        self.state: ConnectionState = ConnectionState.CLOSED
        self.latency: float | None = None
        self.why: str | None = None
        #: why the operator may only watch this robot (None: it takes commands); shown on the chip
        self.view_only: str | None = None
        self._shown: tuple[str, ConnectionState, bool, str | None] | None = None
        self.full_text = ""  #: what the chip says; shown cut with "…" when the chip is narrower (many robots)
        self.show_state(ConnectionState.CLOSED, None)

    def show_state(self, state: ConnectionState, latency: float | None, why: str | None = None) -> None:
        """The link's state, its round trip (while connected) and why it is not up (the tooltip)."""
        self.state, self.latency, self.why = state, latency, why
        lat = latency_text(latency) if state in LIVE_STATES else ""
        name = f"{self.name} · view only" if self.view_only else self.name
        text = f"{name}  {STATE_TEXT[state]}" + (f"  {lat}" if lat else "")
        key = (text, state, self.isChecked(), why)
        if key == self._shown:
            return
        self._shown = key
        self.full_text = text
        self.setText(text)  # whole: the bar lays the chips out for it; cut once it has (a chip too narrow)
        QtCore.QTimer.singleShot(0, self._fit)
        self.setToolTip(f"{self.name}: {STATE_TEXT[state]}" + (f", round trip {lat}" if lat else "")
                        + (f" ({why})" if why else "")
                        + (f"; {self.view_only}: nothing is sent to it" if self.view_only else "")
                        + ". Tap to show its topics and services.")
        fg, bg = STATE_STYLE[state]
        edge = "#000000" if self.isChecked() else "#707070"
        weight = 4 if self.isChecked() else 2
        self.setStyleSheet(
            f"QPushButton#{self.objectName()} {{ border: {weight}px solid {edge}; border-left: 14px solid "
            f"{self.colour}; background: {bg}; color: {fg}; font-weight: bold; padding: 4px 10px; "
            "border-radius: 6px; }")

    def nextCheckState(self) -> None:  # noqa: N802 - Qt's name: a tap picks, never un-picks
        self.setChecked(True)

    #: the chip's edges as styled: the colour strip on the left, borders and padding
    CHROME_PX = 14 + 4 + 2 * 10 + 4

    def _fit(self) -> None:
        """The text as far as the chip's width allows: its name first, the state cut with "…" (six robots
        on a 1280 px window), never clipped at both ends."""
        fm = self.fontMetrics()
        chrome = QtWidgets.QPushButton.sizeHint(self).width() - fm.horizontalAdvance(self.text())  # as styled
        room = self.width() - max(chrome, 0)
        shown = self.full_text
        if room > 0 and fm.horizontalAdvance(shown) > room:
            shown = fm.elidedText(shown, QtCore.Qt.TextElideMode.ElideRight, room)
        if shown != self.text():
            self.setText(shown)

    def sizeHint(self) -> QtCore.QSize:  # noqa: N802 - Qt's name: the whole text's room, whatever is shown
        hint = super().sizeHint()
        fm = self.fontMetrics()
        return QtCore.QSize(hint.width() + fm.horizontalAdvance(self.full_text) - fm.horizontalAdvance(self.text()),
                            hint.height())

    def minimumSizeHint(self) -> QtCore.QSize:  # noqa: N802 - Qt's name: may be narrower than its words
        return QtCore.QSize(min(self.sizeHint().width(), self.CHROME_PX + self.fontMetrics().horizontalAdvance(
            self.name[:6] + "…")), super().minimumSizeHint().height())

    def resizeEvent(self, event: QtGui.QResizeEvent) -> None:  # noqa: N802 - Qt's name
        super().resizeEvent(event)
        self._fit()


class RobotChips(QtWidgets.QFrame):
    """The row of chips; ``picked(robot_id)`` when one is tapped."""

    picked = QtCore.Signal(str)

    def __init__(self, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.setObjectName("robotsBar")
        self.chips: dict[str, RobotChip] = {}
        self.group = QtWidgets.QButtonGroup(self)
        self.group.setExclusive(True)
        self.row = QtWidgets.QHBoxLayout(self)
        self.row.setContentsMargins(10, 4, 10, 4)
        self.row.setSpacing(8)
        self.row.addStretch(1)
        self.setVisible(False)

    def set_robots(self, robots: list[tuple[str, str, str]], current: str) -> None:
        """``robots``: (id, name, colour) in order; ``current``: the side panel's robot."""
        if [(c.robot_id, c.name, c.colour) for c in self.chips.values()] != list(robots):
            for chip in self.chips.values():
                self.group.removeButton(chip)
                chip.deleteLater()
            self.chips = {}
            for i, (rid, name, colour) in enumerate(robots):
                chip = RobotChip(rid, name, colour, self)
                chip.clicked.connect(lambda _checked=False, rid=rid: self.picked.emit(rid))
                self.group.addButton(chip)
                self.row.insertWidget(i, chip)
                self.chips[rid] = chip
        self.set_current(current)
        self.setVisible(len(robots) > 1)

    def set_current(self, robot_id: str) -> None:
        for rid, chip in self.chips.items():
            chip.setChecked(rid == robot_id)
            chip.show_state(chip.state, chip.latency, chip.why)

    def show_state(self, robot_id: str, state: ConnectionState, latency: float | None, why: str | None = None,
                   view_only: str | None = None) -> None:
        chip = self.chips.get(robot_id)
        if chip is not None:
            chip.view_only = view_only
            chip.show_state(state, latency, why)


class RobotPicker(QtWidgets.QWidget):
    """"Robot: [Bravo ▾]" at the top of a side list; ``picked(robot_id)`` when another is chosen."""

    picked = QtCore.Signal(str)

    def __init__(self, what: str, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.setObjectName(f"{what}RobotPicker")
        self.combo = QtWidgets.QComboBox()
        self.combo.setObjectName(f"{what}RobotCombo")
        self.combo.setAccessibleName("robot")
        self.combo.setToolTip("Whose topics and services this list shows; new widgets are bound to it")
        label = QtWidgets.QLabel("Robot")
        label.setBuddy(self.combo)
        row = QtWidgets.QHBoxLayout(self)
        row.setContentsMargins(0, 0, 0, 4)
        row.addWidget(label)
        row.addWidget(self.combo, 1)
        self.combo.activated.connect(lambda i: self.picked.emit(str(self.combo.itemData(i))))
        self.setVisible(False)

    def set_robots(self, robots: list[tuple[str, str, str]], current: str) -> None:
        ids = [self.combo.itemData(i) for i in range(self.combo.count())]
        names = [self.combo.itemText(i) for i in range(self.combo.count())]
        if ids != [r[0] for r in robots] or names != [r[1] for r in robots]:
            self.combo.blockSignals(True)
            self.combo.clear()
            for rid, name, _colour in robots:
                self.combo.addItem(name, rid)
            self.combo.blockSignals(False)
        self.set_current(current)
        self.setVisible(len(robots) > 1)

    def set_current(self, robot_id: str) -> None:
        i = self.combo.findData(robot_id)
        if i >= 0 and i != self.combo.currentIndex():
            self.combo.blockSignals(True)
            self.combo.setCurrentIndex(i)
            self.combo.blockSignals(False)
