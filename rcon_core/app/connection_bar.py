"""The bar across the top: robot URL (with history), connect/disconnect, link state and latency."""

from __future__ import annotations

from qtpy import QtCore, QtWidgets

from rcon_core.app.config import AppConfig
from rcon_core.app.link import BadUrl, Link
from rcon_core.app.theme import repolish


def normalize_url(text: str) -> str:
    """What the operator typed, as a rosbridge URL: ``localhost:9300`` -> ``ws://localhost:9300`` (no
    scheme means ``ws://``; ``ws://`` and ``wss://`` are kept). Other schemes are left for
    :func:`rcon_core.app.link.check_url` to reject with its message."""
    text = text.strip()
    if text and "://" not in text:
        return f"ws://{text}"
    return text


STATE_TEXT = {
    "connecting": "CONNECTING",
    "connected": "CONNECTED",
    "degraded": "DEGRADED",  # connected, but the link is stalled: commands are not sent (bridge/freshness.py)
    "reconnecting": "RECONNECTING",
    "closed": "DISCONNECTED",
}


class ConnectionBar(QtWidgets.QFrame):
    """Shows and drives the :class:`Link`; call :meth:`poll` once per frame."""

    state_changed = QtCore.Signal(str)

    def __init__(self, link: Link, config: AppConfig, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.setObjectName("connectionBar")
        self.link, self.config = link, config
        self.state = "closed"
        self._last_latency_text = ""

        self.url = QtWidgets.QComboBox()
        self.url.setObjectName("urlField")
        self.url.setEditable(True)
        self.url.setInsertPolicy(QtWidgets.QComboBox.InsertPolicy.NoInsert)
        self.url.setMinimumWidth(220)  # a 1024 px screen keeps its side panel toggle and state
        self.url.addItems(config.url_history or [config.last_url])
        self.url.setCurrentText(config.last_url)
        line = self.url.lineEdit()
        assert line is not None  # the combo is editable
        # only a tap on it gives it the keyboard: never Tab, never a focused button disappearing (with its
        # text selected, one key would replace the robot's URL)
        for w in (self.url, line):
            w.setFocusPolicy(QtCore.Qt.FocusPolicy.ClickFocus)
        line.returnPressed.connect(self._return_pressed)
        self._return_seen = False

        self.connect_button = QtWidgets.QPushButton("Connect")
        self.connect_button.setObjectName("connectButton")
        self.connect_button.setProperty("primary", True)
        self.connect_button.clicked.connect(self.toggle)
        fm = self.connect_button.fontMetrics()  # room for the longer label: "Disconnect" is never cut
        self.connect_button.setMinimumWidth(max(fm.horizontalAdvance(t) for t in ("Connect", "Disconnect")) + 48)

        self.state_label = QtWidgets.QLabel()
        self.state_label.setObjectName("linkState")
        self.state_label.setAlignment(QtCore.Qt.AlignmentFlag.AlignCenter)
        self.latency_label = QtWidgets.QLabel("—")
        self.latency_label.setObjectName("latency")
        self.latency_label.setToolTip("round-trip time to the robot")
        self.message = QtWidgets.QLabel()
        self.message.setProperty("role", "problem")

        row = QtWidgets.QHBoxLayout(self)
        row.setContentsMargins(10, 8, 10, 8)
        row.setSpacing(10)
        row.addWidget(QtWidgets.QLabel("Robot"))
        row.addWidget(self.url, 1)
        row.addWidget(self.connect_button)
        row.addWidget(self.state_label)
        row.addWidget(self.latency_label)
        row.addWidget(self.message, 1)
        self._show_state("closed")

    # ---------------------------------------------------------------------------------------- actions
    def toggle(self) -> None:
        if self.link.client is None:
            self.connect_clicked()
        else:
            self.link.disconnect()
            self._show_state("closed")

    def _return_pressed(self) -> None:
        # an editable combo hands the ignored Return back to its line edit, which emits returnPressed a
        # second time: one key press connects once
        if self._return_seen:
            return
        self._return_seen = True
        QtCore.QTimer.singleShot(0, lambda: setattr(self, "_return_seen", False))
        self.connect_clicked()

    def connect_clicked(self, remember: bool = True) -> None:
        """Connect to the URL in the field (``remember=False``: not put in the URL history, e.g. the
        demo's embedded robot, whose port is gone after the run)."""
        text = normalize_url(self.url.currentText())
        try:
            self.link.connect_to(text)
        except BadUrl as exc:
            active = self.link.url if self.link.client is not None else None
            if active:  # the field shows the URL actually in use, never the rejected text
                self._set_field(active)
                self.message.setText(f"{exc}; still connected to {active}")
            else:
                self.message.setText(str(exc))
            return
        self.message.clear()
        if remember:
            self.config.remember_url(text)
        self._set_field(text)
        self._show_state("connecting")

    def _set_field(self, text: str) -> None:
        self.url.blockSignals(True)
        self.url.clear()
        self.url.addItems(self.config.url_history)
        self.url.setCurrentText(text)
        self.url.blockSignals(False)

    # ------------------------------------------------------------------------------------ per frame
    def poll(self, _now: float = 0.0) -> None:
        ok, state = self.link.state_box.take()
        if ok and state != self.state:
            self._show_state(state)
        ok, error = self.link.error_box.take()
        if ok and self.link.client is not None:
            self.message.setText(str(error))
        latency = self.link.latency if self.state in ("connected", "degraded") else None
        text = "—" if latency is None else ("<1 ms" if latency < 0.0005 else f"{latency * 1000:.0f} ms")
        if text != self._last_latency_text:
            self._last_latency_text = text
            self.latency_label.setText(text)

    def _show_state(self, state: str) -> None:
        self.state = state
        self.state_label.setText(STATE_TEXT.get(state, state.upper()))
        self.state_label.setProperty("state", state)
        repolish(self.state_label)
        self.connect_button.setText("Connect" if self.link.client is None else "Disconnect")
        if state == "connected":
            self.message.clear()
        self.state_changed.emit(state)
