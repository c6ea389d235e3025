"""The bar across the top: robot URL (with history), connect/disconnect, the robot's connection settings
(Security, the lock button), link state, latency, and a one-line message.

The message says why a link is not up, in the words of :mod:`rcon_core.bridge.reasons` ("connection
refused · retrying in 3 s", "certificate not trusted (self-signed? pass the CA file)"), within a frame of
the failed attempt; a fatal failure (TLS, refused authentication) ends the link, a retried one counts down.
While the robot's bridge holds the link's commands behind an unanswered service call
(``rcon_core/bridge/held.py``) it says "⚠ commands held: the robot's bridge is still busy with /x".
No text changes the window's width or the bar's height: the message takes a second line where the bar
has the height, then is elided, the whole of it in its tooltip.  Enter connects to exactly what the URL
field holds: the history is offered as the field's list, never completed inline.  A URL enters
the history once its link has come up, or, with rosauth, once its robot answered a call after the auth
op (a robot refusing the secret opens the link and then closes it).
"""

from __future__ import annotations

from importlib import resources
from typing import Any

from qtpy import QtCore, QtGui, QtWidgets

from rcon_core.app.bandwidth import BandwidthButton
from rcon_core.app.config import AppConfig
from rcon_core.app.dialog_fit import fit_to_window
from rcon_core.app.elided_label import ElidedLabel
from rcon_core.app.link import BadUrl, LinkSettings, RobotConnection, check_url
from rcon_core.app.link_settings import LinkSettingsDialog
from rcon_core.app.operator_lock import Guard, no_guard
from rcon_core.app.secret_store import SecretStore
from rcon_core.app.theme import colour as theme_colour
from rcon_core.app.theme import repolish, tinted_icon
from rcon_core.app.url_field import UrlCombo, host_text
from rcon_core.bridge import ConnectionState


def normalize_url(text: str) -> str:
    """What the operator typed, as a rosbridge URL: ``localhost:9300`` -> ``ws://localhost:9300`` (no
    scheme means ``ws://``; ``ws://`` and ``wss://`` are kept). Other schemes are left for
    :func:`rcon_core.app.link.check_url` to reject with its message."""
    text = text.strip()
    if text and "://" not in text:
        return f"ws://{text}"
    return text


#: the words the operator reads for each link state
STATE_TEXT = {
    ConnectionState.CONNECTING: "CONNECTING",
    ConnectionState.CONNECTED: "CONNECTED",
    # connected, but the link is stalled: commands are not sent (bridge/freshness.py)
    ConnectionState.DEGRADED: "DEGRADED",
    ConnectionState.RECONNECTING: "RECONNECTING",
    ConnectionState.CLOSED: "DISCONNECTED",
}
#: the URL field is never narrower than this many characters ("localhost", "10.0.0.12"); the bar gives it
#: the room for the robot's host and port before anything else (ConnectionBar._share_room)
HOST_CHARS = 8
#: the states in which a round trip means something
LIVE_STATES = (ConnectionState.CONNECTED, ConnectionState.DEGRADED)


class LatencyLabel(QtWidgets.QLabel):
    """The round-trip time: as wide as the bar lets it be (its maximum width, set by the bar), asking for no
    minimum, so it never keeps a window from shrinking (the bar takes its room away at once)."""

    def sizeHint(self) -> QtCore.QSize:  # noqa: N802 - Qt's name
        return QtCore.QSize(self.maximumWidth(), super().sizeHint().height())

    def minimumSizeHint(self) -> QtCore.QSize:  # noqa: N802 - Qt's name
        return QtCore.QSize(0, super().minimumSizeHint().height())


class ConnectionBar(QtWidgets.QFrame):
    """Shows and drives the :class:`RobotConnection`; call :meth:`poll` once per frame."""

    state_changed = QtCore.Signal(object)  # a ConnectionState

    def __init__(self, link: RobotConnection, config: AppConfig, parent: QtWidgets.QWidget | None = None, *,
                 guard: Guard = no_guard) -> None:
        super().__init__(parent)
        self.setObjectName("connectionBar")
        self.link, self.config = link, config
        #: the operator lock's PIN gate on changing the robot (Connect/Disconnect, the Security dialog)
        self.guard = guard
        self.secrets = SecretStore()
        #: settings from the command line (--ca-file, --client-cert/--client-key, the secret from
        #: RCON_AUTH_SECRET or --auth-secret-file): they apply to every robot of this run
        self.overrides = LinkSettings()
        self.state = ConnectionState.CLOSED
        self.failure: Any = None  # the last reasons.Failure shown, until the link comes up
        self.note = ""  # a rejected URL, said before the failure of the link still in use
        self.dialog: LinkSettingsDialog | None = None
        self._remember: str | None = None  # the URL to put in the history once connected
        self._remember_on_answer = False
        self._last_latency_text = ""
        #: why the robot's bridge holds this link's commands (shown as the message), None when it does not
        self.held: str | None = None

        # a URL too long for the field shows the robot's host (url_field.py)
        self.url = UrlCombo()
        self.url.setObjectName("urlField")
        # Enter connects to exactly what is typed: the history is the list to pick from, never completed
        # inline (an inline completion turned ":91" into the history's ":9191", another robot)
        self.url.setCompleter(None)  # type: ignore[arg-type]  # Qt takes None: no completer
        self.url.setInsertPolicy(QtWidgets.QComboBox.InsertPolicy.NoInsert)
        self.url.setAccessibleName("Robot URL")
        # the field is never narrower than HOST_CHARS characters at the text size in use, and the bar's room
        # goes to it first, as far as it shows the robot's host (url_field.py, _share_room); a long URL in
        # the history never widens the bar (and so the window)
        self.url.setSizeAdjustPolicy(QtWidgets.QComboBox.SizeAdjustPolicy.AdjustToMinimumContentsLengthWithIcon)
        self.url.setMinimumContentsLength(HOST_CHARS)
        self.url.addItems(config.url_history or [config.last_url])
        self.url.setCurrentText(config.last_url)
        self.url.currentTextChanged.connect(lambda _text: self._share_room())  # another host: its width
        line = self.url.lineEdit()
        assert line is not None  # the combo is editable
        # the field names itself (no "Robot" label beside it: the bar keeps its room for the lock and state)
        line.setPlaceholderText("robot URL, e.g. ws://192.168.1.10:9090")
        self.url.setToolTip("The robot's rosbridge URL (ws:// or wss://)")
        # only a tap on it gives it the keyboard: never Tab, never a focused button disappearing (with its
        # text selected, one key would replace the robot's URL)
        for w in (self.url, line):
            w.setFocusPolicy(QtCore.Qt.FocusPolicy.ClickFocus)
        line.returnPressed.connect(self._return_pressed)
        self._return_seen = False

        self.connect_button = QtWidgets.QPushButton("Connect")
        self.connect_button.setObjectName("connectButton")
        self.connect_button.setProperty("primary", True)
        self.connect_button.clicked.connect(lambda: self.guard("change the robot", self.toggle))

        # a square lock button (a word would not fit a 1024 px bar): the robot's connection settings
        self.settings_button = QtWidgets.QPushButton()
        self.settings_button.setObjectName("linkSettingsButton")
        self.settings_button.setProperty("square", True)
        self._tint_icon()
        self.settings_button.setIconSize(QtCore.QSize(22, 22))
        self.settings_button.setAccessibleName("Security")
        self.settings_button.setToolTip("Security: this robot's connection settings (CA file, client "
                                        "certificate, rosauth secret)")
        self.settings_button.clicked.connect(lambda: self.open_settings())

        self.state_label = QtWidgets.QLabel()
        self.state_label.setObjectName("linkState")
        self.state_label.setAlignment(QtCore.Qt.AlignmentFlag.AlignCenter)
        self.state_label.setProperty("state", ConnectionState.CLOSED.value)
        self._latency_yielded = False  # another part has the latency's place (yield_latency)
        self.latency_label = LatencyLabel("—")
        self.latency_label.setObjectName("latency")
        self.latency_label.setToolTip("round-trip time to the robot")
        #: the latency label's width for its widest reading, and the width the bar gives it (that, or 0: no
        #: room beside the URL field's, at a large text size on a small screen; the state's tooltip says it)
        self._latency_full = 0
        self._latency_room = 0
        #: parts that show a short form where the bar has no room for their whole reading (``full_width()``,
        #: ``set_room(px)``), served in this order after the URL field's host and before the latency (the
        #: recorder's indicator: record_control.py)
        self.givers: list[Any] = []
        #: bytes per second in, per robot and by topic (a tap shows the details)
        self.bandwidth = BandwidthButton(link)
        self.message = ElidedLabel()
        self.message.setObjectName("linkMessage")
        self.message.setProperty("role", "problem")

        row = QtWidgets.QHBoxLayout(self)
        row.setContentsMargins(10, 8, 10, 8)
        row.setSpacing(10)
        # the URL field before the readouts beside it: at 1024 px beside the bandwidth readout the field was
        # squeezed to "ws:…847" next to an empty message (see _share_room)
        row.addWidget(self.url)  # as wide as _share_room finds room for (its size hint); the message the rest
        row.addWidget(self.connect_button)
        row.addWidget(self.settings_button)
        row.addWidget(self.state_label)
        row.addWidget(self.latency_label)
        row.addWidget(self.bandwidth)
        row.addWidget(self.message, 1)
        self.message.setMinimumWidth(0)
        self._show_state(ConnectionState.CLOSED)

    # ---------------------------------------------------------------------------------------- actions
    def robot_url(self) -> str:
        """The robot's URL: the connected one, else what the URL field holds."""
        return self.link.url if self.link.client is not None and self.link.url else normalize_url(
            self.url.currentText())

    def view_only_reason(self) -> str | None:
        """Why the robot connection is view-only (marked so in the app config), or None."""
        url = self.robot_url()
        return f"robot {url} is view-only" if url and self.config.is_view_only(url) else None

    def toggle(self) -> None:
        if self.link.client is None:
            self.connect_clicked()
        else:
            self.link.disconnect()
            self.failure, self.note = None, ""
            self._say("")
            self._show_state(ConnectionState.CLOSED)

    def _return_pressed(self) -> None:
        # an editable combo hands the ignored Return back to its line edit, which emits returnPressed a
        # second time: one key press connects once
        if self._return_seen:
            return
        self._return_seen = True
        QtCore.QTimer.singleShot(0, lambda: setattr(self, "_return_seen", False))
        self.connect_clicked()

    def connect_to(self, url: str, *, remember: bool = True) -> None:
        """Connect to ``url``; ``remember=False`` keeps it out of the URL history (the demo's robot)."""
        self.url.setCurrentText(url)
        self.connect_clicked(remember=remember)

    def connect_clicked(self, remember: bool = True) -> None:
        """Connect to the URL in the field (``remember=False``: not put in the URL history, e.g. the
        demo's embedded robot, whose port is gone after the run)."""
        text = normalize_url(self.url.currentText())
        try:
            text = check_url(text)
        except BadUrl as exc:
            self._bad_url(exc)
            return
        settings = self.settings_for(text)
        if settings is None:  # the robot checks a secret and none is known in this run
            self._say("this robot checks a secret: enter it in Security (the lock)")
            self.open_settings(ask_secret=True)
            return
        self.failure, self.note = None, ""
        self.link.connect_to(text, settings)
        self.message.clear()
        self._remember = text if remember else None
        # without auth a link that comes up is a robot that accepted it; with auth, only an answer after
        # the auth op tells (a robot refusing the secret opens the link and then closes it)
        self._remember_on_answer = settings.secret is not None
        self._set_field(text)
        self._show_state(ConnectionState.CONNECTING)

    def _bad_url(self, exc: BadUrl) -> None:
        active = self.link.url if self.link.client is not None else None
        if active:  # the field shows the URL actually in use, never the rejected text
            self._set_field(active)
            verb = "still connected to" if self.state is ConnectionState.CONNECTED else "still trying"
            self.note = f"{exc} · {verb} {active}"
        else:
            self.note = str(exc)
        self._say(self.note if self.failure is None else f"{self.note}: {self.failure.text()}")

    def settings_for(self, url: str) -> LinkSettings | None:
        """How to connect to ``url``: its saved settings under this run's command-line ones; None when it
        checks a secret and none is known (not from the command line, the credential store or this run)."""
        saved = self.config.robot_settings(url)
        cli = self.overrides
        secret = cli.secret
        if saved["auth"] and not secret:
            secret = self.secrets.get(url)
            if not secret:
                return None
        return LinkSettings(ca_file=cli.ca_file or saved["ca_file"] or None,
                            client_cert=cli.client_cert or saved["client_cert"] or None,
                            client_key=cli.client_key or saved["client_key"] or None, secret=secret)

    def open_settings(self, ask_secret: bool = False) -> LinkSettingsDialog | None:
        """Open the Security dialog for the URL in the field (after the operator PIN while the lock is on:
        it holds the robot's TLS files and secret); saving it connects with the new settings."""
        opened: list[LinkSettingsDialog | None] = [None]
        self.guard("change the robot's connection settings",
                   lambda: opened.__setitem__(0, self._settings_dialog(ask_secret)))
        return opened[0]

    def _settings_dialog(self, ask_secret: bool) -> LinkSettingsDialog | None:
        try:
            url = check_url(normalize_url(self.url.currentText()))
        except BadUrl as exc:
            self._bad_url(exc)
            return None
        if self.dialog is not None:
            self.dialog.close()
        dialog = LinkSettingsDialog(url, self.config, self.secrets, self.window(), ask_secret=ask_secret)
        dialog.accepted.connect(lambda: self.connect_clicked())
        self.dialog = dialog
        fit_to_window(dialog, self)  # every word of it, also at a large text size (dialog_fit.py)
        dialog.open()
        return dialog

    def _set_field(self, text: str) -> None:
        self.url.blockSignals(True)
        self.url.clear()
        self.url.addItems(self.config.url_history)
        self.url.setCurrentText(text)
        self.url.blockSignals(False)

    def _keep_url(self) -> None:
        """The robot at ``_remember`` accepted the link: a URL worth keeping in the history."""
        url, self._remember = self._remember, None
        if url is None:
            return
        self.config.remember_url(url)
        line = self.url.lineEdit()
        if line is None or not line.hasFocus():
            self._set_field(url)

    def _fit_widths(self) -> None:
        """Room for the button's longer label, measured with its styled font (known once the theme is
        applied, so measured again at each state change): "Disconnect" is never cut, and the bar's minimum
        width is the same in every state."""
        button = self.connect_button
        shown = button.text()
        widths = []
        for text in ("Connect", "Disconnect"):
            button.setText(text)
            widths.append(button.sizeHint().width())  # text, padding and border as styled
        button.setText(shown)
        button.setMinimumWidth(max(widths))
        # the state label likewise keeps the width of its longest word (DISCONNECTED, RECONNECTING)
        label = self.state_label
        shown, widths = label.text(), []
        label.setMinimumWidth(0)
        for text in STATE_TEXT.values():
            label.setText(text)
            widths.append(label.sizeHint().width())
        label.setText(shown)
        label.setMinimumWidth(max(widths))
        # and the latency the widest it reads ("888 ms"), so a new reading never cuts it or moves the bar
        latency = self.latency_label
        latency.setMinimumWidth(0)
        latency.setMaximumWidth(16_777_215)
        self._latency_full = max(QtWidgets.QLabel.minimumSizeHint(latency).width(), 4 + max(
            latency.fontMetrics().horizontalAdvance(t) for t in ("888 ms", "<1 ms")))
        self._latency_room = -1  # measured again: given again
        self._share_room()

    def _share_room(self) -> None:
        """The room the bar has beyond its parts' minimums goes, in this order, to: the URL field, as far as
        it shows the robot's host and port whole (``url_field.host_text``: ``192.168.1.10:9090``); the latency (its widest reading,
        or nothing: never a cut figure); the bandwidth readout (up to its reading); the URL field again, as
        far as it shows the whole URL; the rest to the message. So at 200 % text on a 1024 px tablet the
        field shows which robot, the latency then being in the state's tooltip. Called on a resize, a text
        size change, a state change and another URL; the bar's minimum width is the same in every state."""
        layout = self.layout()
        if layout is None or not self._latency_full:
            return
        latency, url = self.latency_label, self.url
        spare = self.width() - layout.minimumSize().width()  # the latency and the readout have no minimum
        least = url.minimumSizeHint().width()
        text = normalize_url(url.currentText())
        host = min(max(0, spare), max(0, url.width_for(host_text(text)) - least))
        spare -= host
        for part in self.givers:
            low = part.minimumSizeHint().width()
            give = min(max(0, spare), max(0, part.full_width() - low)) if part.isVisibleTo(self) else 0
            part.set_room(low + give)
            spare -= give
        room = self._latency_full if spare >= self._latency_full else 0
        if room != self._latency_room:
            self._latency_room = room
            latency.setMaximumWidth(room)  # its size hint: no minimum, so the window may still shrink
            latency.setText(self._last_latency_text if room else "")
        spare -= room if latency.isVisible() else 0
        readout = max(0, min(spare, self.bandwidth.full_width()))
        self.bandwidth.set_room(readout)
        spare -= readout
        whole = min(max(0, spare), max(0, url.width_for(text) - least - host))
        url.set_extra(host + whole)

    def resizeEvent(self, event: QtGui.QResizeEvent) -> None:  # noqa: N802 - Qt's name
        super().resizeEvent(event)
        self._share_room()

    def event(self, event: QtCore.QEvent) -> bool:
        handled = super().event(event)
        if event.type() == QtCore.QEvent.Type.LayoutRequest:
            # a part came or went (the recorder's indicator in the latency's place): shared again (a fixed
            # point: nothing changes the second time)
            self._share_room()
        return handled

    def yield_latency(self, yielded: bool) -> None:
        """Another part takes the latency's place (the compact recorder's indicator while recording) or
        gives it back; the bar alone decides whether the latency shows (:meth:`_hold_latency_room`)."""
        if yielded != self._latency_yielded:
            self._latency_yielded = yielded
            self._hold_latency_room()

    def _hold_latency_room(self) -> None:
        """The latency shows only while connected, and not while another part has its place
        (:meth:`yield_latency`); otherwise the message holds its spacing, so the bar's minimum width is the
        same in every state."""
        spacing = layout.spacing() if (layout := self.layout()) is not None else 0
        if self.state is ConnectionState.CONNECTED and not self._latency_yielded:
            self.message.setMinimumWidth(0)
            self.latency_label.setVisible(True)
        else:
            self.latency_label.setVisible(False)
            self.message.setMinimumWidth(spacing)
        self._share_room()

    def _tint_icon(self) -> None:
        """The padlock in the theme's text colour (black on light, light grey at night)."""
        self.settings_button.setIcon(tinted_icon(str(resources.files("rcon_core.app") / "link-settings.svg"),
                                                 theme_colour("TEXT")))

    def changeEvent(self, event: QtCore.QEvent) -> None:  # noqa: N802 - Qt's name
        super().changeEvent(event)
        if event.type() == QtCore.QEvent.Type.PaletteChange:
            self._tint_icon()  # another theme
        if event.type() in (QtCore.QEvent.Type.StyleChange, QtCore.QEvent.Type.FontChange) and self.isVisible():
            # another text size: "DISCONNECTED" and "Disconnect" measured again, once every child has its
            # new font (the bar hears of the change before its children are polished again)
            QtCore.QTimer.singleShot(0, self._fit_widths)

    def showEvent(self, event: QtGui.QShowEvent) -> None:  # noqa: N802 - Qt's name
        super().showEvent(event)
        self._fit_widths()  # the stylesheet's font is in force by now

    # ------------------------------------------------------------------------------------ per frame
    def poll(self, _now: float = 0.0) -> None:
        ok, state = self.link.state_box.take()
        if ok and state != self.state:
            self._show_state(state)
        ok, error = self.link.error_box.take()
        if ok and self.link.client is not None:
            self._say(str(error))
        ok, failure = self.link.failure_box.take()
        if ok and (failure is not None or not getattr(self.failure, "fatal", False)):
            self.failure = failure
            if failure is not None and failure.fatal:
                self.link.disconnect()  # retrying cannot help: the operator changes a setting first
                self._show_state(ConnectionState.CLOSED)
            elif failure is None and self.state is not ConnectionState.CONNECTED:
                self._say("")
        ok, held = self.link.held_box.take()
        if ok:  # commands held behind an unanswered call (rcon_core/bridge/held.py): said until it answers
            if held:
                self._say(f"⚠ {held}")
            elif self.held:
                self._say(self.link.protocol_text() if self.state is ConnectionState.CONNECTED else "")
            self.held = held
        ok, answered = self.link.answered_box.take()
        if ok and answered is not None and answered == self._remember == self.link.url:
            self._keep_url()
        if self.failure is not None:
            why = self.failure.text()
            self._say(f"{self.note}: {why}" if self.note else why)
        latency = self.link.latency if self.state in LIVE_STATES else None
        text = "—" if latency is None else ("<1 ms" if latency < 0.0005 else f"{latency * 1000:.0f} ms")
        if text != self._last_latency_text:
            self._last_latency_text = text
            if self._latency_room:
                self.latency_label.setText(text)
            # also where the bar has no room for the latency (_share_room)
            self.state_label.setToolTip(f"round trip to the robot: {text}" if latency is not None else "")
        self.bandwidth.poll()

    def _say(self, text: str, role: str = "problem") -> None:
        """The one-line message (the reason comes first, then the countdown).  ``role``: "problem" (red,
        bold: why the link is not up) or "info" (the plain text colour: which protocol and server)."""
        self.message.setText(text)
        if text and self.message.property("role") != role:  # an empty line keeps its style
            self.message.setProperty("role", role)
            repolish(self.message)

    def _show_state(self, state: ConnectionState) -> None:
        self.state = state
        self.state_label.setText(STATE_TEXT[state])
        self.state_label.setProperty("state", state.value)  # the theme's selectors use the value
        repolish(self.state_label)
        self.connect_button.setText("Connect" if self.link.client is None else "Disconnect")
        self._fit_widths()
        connected = state is ConnectionState.CONNECTED
        self._hold_latency_room()
        if connected:
            self.failure, self.note = None, ""
            self._say(self.link.protocol_text(), "info")  # "" on rosbridge; a Foxglove link says so
            if self._remember is not None and self._remember == self.link.url and not self._remember_on_answer:
                self._keep_url()
        self.state_changed.emit(state)
