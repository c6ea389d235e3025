"""The app over a secure link (issue 16, "the link"): a robot's connection settings from the lock button
(CA file, rosauth secret), the secret in the credential store (a test keyring, never the real one) or,
where there is none, in memory only; without the CA, with the wrong secret or an expired certificate the
bar says why within 2 s and stops trying.  Drives the real window offscreen against the sim over wss://.

``RCON_SCREENSHOTS=DIR`` writes a PNG of the window in each failure state."""

from __future__ import annotations

from pathlib import Path

import pytest
from app_helpers import open_window, snap, tap, window_session
from qtpy import QtCore, QtWidgets
from qtpy.QtTest import QTest

from rcon_core.app.link import LinkSettings
from rcon_core.app.secret_store import SERVICE
from rcon_core.bridge import ConnectionState
from rcon_core.plugins import PluginManager
from rcon_core.sim import SimServer
from rcon_core.testing import qt_flushed

keyring = pytest.importorskip("keyring")
pytest.importorskip("cryptography")
from keyring.backend import KeyringBackend  # noqa: E402
from keyring.backends import fail  # noqa: E402
from tls_certs import make_pki  # noqa: E402

pytestmark = pytest.mark.usefixtures("qapp")

SECRET = "app-robot-secret"
SAY_WHY_MS = 2_000


class MemoryKeyring(KeyringBackend):
    """A credential store that lives in this test only."""

    priority = 1  # type: ignore[assignment]

    def __init__(self) -> None:
        super().__init__()
        self.passwords: dict[tuple[str, str], str] = {}

    def get_password(self, service: str, username: str) -> str | None:
        return self.passwords.get((service, username))

    def set_password(self, service: str, username: str, password: str) -> None:
        self.passwords[(service, username)] = password

    def delete_password(self, service: str, username: str) -> None:
        self.passwords.pop((service, username), None)


@pytest.fixture
def store():
    previous = keyring.get_keyring()
    backend = MemoryKeyring()
    keyring.set_keyring(backend)
    yield backend
    keyring.set_keyring(previous)


@pytest.fixture
def no_store():
    previous = keyring.get_keyring()
    keyring.set_keyring(fail.Keyring())
    yield
    keyring.set_keyring(previous)


@pytest.fixture(scope="module")
def pki(tmp_path_factory):
    return make_pki(tmp_path_factory.mktemp("pki"))


@pytest.fixture
def robot(pki):
    with SimServer.in_thread(port=0, rate_scale=2.0, auth_secret=SECRET, ssl=pki.server.server_context()) as server:
        yield server


@pytest.fixture
def window(qtbot, tmp_path):
    yield from window_session(qtbot, tmp_path, PluginManager(environ={}), size=(1280, 800))


def type_into(line: QtWidgets.QLineEdit, text: str) -> None:
    QTest.mouseClick(line, QtCore.Qt.MouseButton.LeftButton)
    line.selectAll()
    QTest.keyClicks(line, text)


def type_url(window, url: str) -> None:
    type_into(window.connection.url.lineEdit(), url)
    QTest.keyClick(window.connection.url.lineEdit(), QtCore.Qt.Key.Key_Return)
    qt_flushed()  # the bar's one-Return-per-press guard resets (a person's next key press comes later)


def fill_settings(qtbot, window, url: str, *, ca: Path | None, secret: str | None):
    """Type the URL, tap the lock, fill the dialog like an operator, tap Save and connect."""
    type_into(window.connection.url.lineEdit(), url)
    tap(window.connection.settings_button)
    dialog = window.connection.dialog
    qtbot.waitUntil(dialog.isVisible)
    if ca is not None:
        type_into(dialog.paths["ca_file"].edit, str(ca))
    if secret is not None:
        if not dialog.use_auth.isChecked():
            tap(dialog.use_auth)
        type_into(dialog.secret, secret)
    tap(dialog.save_button)
    return dialog


def test_connects_with_the_ca_file_and_a_secret_kept_in_the_credential_store(qtbot, window, robot, pki, store,
                                                                            tmp_path):
    dialog = fill_settings(qtbot, window, robot.url, ca=pki.ca, secret=SECRET)
    assert dialog.where.text() == "kept in the system's credential store"
    bar = window.connection
    qtbot.waitUntil(lambda: bar.state is ConnectionState.CONNECTED, timeout=10_000)
    qtbot.waitUntil(lambda: window.topics.item("/cmd_vel") is not None, timeout=10_000)
    # the robot saw the authenticated client; the secret is in the store, never in the app's files
    assert store.passwords == {(SERVICE, robot.url): SECRET}
    for f in tmp_path.rglob("*"):
        if f.is_file():
            assert SECRET not in f.read_text(errors="replace"), f
    saved = bar.config.robot_settings(robot.url)
    assert saved == {"ca_file": str(pki.ca), "client_cert": "", "client_key": "", "auth": True}
    # next start: the settings and the secret come back without asking
    bar.toggle()
    qtbot.waitUntil(lambda: bar.state is ConnectionState.CLOSED)
    fresh = type(bar.secrets)()
    assert fresh.get(robot.url) == SECRET
    tap(bar.connect_button)
    qtbot.waitUntil(lambda: bar.state is ConnectionState.CONNECTED, timeout=10_000)
    assert bar.dialog is dialog  # no new dialog was needed


def test_without_a_credential_store_the_secret_is_asked_each_start(qtbot, window, robot, pki, no_store, tmp_path):
    dialog = fill_settings(qtbot, window, robot.url, ca=pki.ca, secret=SECRET)
    assert dialog.where.text().startswith("no credential store on this system")
    bar = window.connection
    qtbot.waitUntil(lambda: bar.state is ConnectionState.CONNECTED, timeout=10_000)
    for f in tmp_path.rglob("*"):
        if f.is_file():
            assert SECRET not in f.read_text(errors="replace"), f
    window.shutdown()
    # a new start (a new window on the same config): it knows auth is used, not the secret, so it asks
    again = open_window(qtbot, tmp_path, PluginManager(environ={}), size=(1280, 800))
    try:
        type_url(again, robot.url)
        asking = again.connection.dialog
        assert asking is not None and asking.isVisible() and again.connection.link.client is None
        assert asking.problem.text() == "This robot checks a secret: enter it to connect."
        assert again.connection.message.text().startswith("this robot checks a secret")
        type_into(asking.secret, SECRET)
        tap(asking.save_button)
        qtbot.waitUntil(lambda: again.connection.state is ConnectionState.CONNECTED, timeout=10_000)
    finally:
        again.shutdown()


@pytest.mark.parametrize("case, sentence", [
    ("no CA", "certificate not trusted (self-signed? pass the CA file)"),
    ("wrong secret", "robot refused authentication"),
    ("expired", "certificate expired (check its dates and the clocks)"),
])
def test_fails_fast_with_the_reason_in_the_bar(qtbot, window, pki, store, case, sentence):
    pair = pki.expired if case == "expired" else pki.server
    with SimServer.in_thread(port=0, rate_scale=2.0, auth_secret=SECRET, ssl=pair.server_context()) as robot:
        fill_settings(qtbot, window, robot.url, ca=None if case == "no CA" else pki.ca,
                      secret="wrong" if case == "wrong secret" else SECRET)
        bar = window.connection
        qtbot.waitUntil(lambda: bar.message.text() == sentence, timeout=SAY_WHY_MS)
        # fatal: the link is ended, not retried; the operator changes a setting and taps Connect
        assert bar.link.client is None and bar.state is ConnectionState.CLOSED
        assert bar.state_label.text() == "DISCONNECTED" and bar.connect_button.text() == "Connect"
        assert bar.message.toolTip() == sentence
        QtWidgets.QApplication.processEvents()
        snap(window, f"fatal-{case.replace(' ', '-')}")
        QTest.qWait(300)
        assert bar.message.text() == sentence and bar.link.client is None  # still said, still not retrying
        assert bar.config.url_history == []


def test_a_bad_file_is_named_in_the_dialog(qtbot, window, robot, store, tmp_path):
    dialog = fill_settings(qtbot, window, robot.url, ca=tmp_path / "missing.pem", secret=SECRET)
    assert dialog.isVisible() and dialog.problem.text() == f"CA file {tmp_path / 'missing.pem'}: no such file"
    assert window.connection.link.client is None and store.passwords == {}


def test_command_line_settings_apply(qtbot, window, robot, pki, store):
    """``rcon --ca-file ... `` with ``RCON_AUTH_SECRET``: the overrides reach the link."""
    window.connection.overrides = LinkSettings(ca_file=str(pki.ca), secret=SECRET)
    type_url(window, robot.url)
    qtbot.waitUntil(lambda: window.connection.state is ConnectionState.CONNECTED, timeout=10_000)
    assert window.connection.dialog is None
