"""The connection bar says why a robot cannot be reached, keeps retrying with a countdown, clears the
previous robot's lists, rejects a URL that cannot work before connecting, keeps only URLs that once
connected in the history, and no message ever widens the window or pushes the UI down (issue 12, items 2
and 3).

``RCON_SCREENSHOTS=DIR`` writes a PNG of the window in each state."""

from __future__ import annotations

import pytest
from app_helpers import snap, window_session
from qtpy import QtCore, QtWidgets
from qtpy.QtTest import QTest

from rcon_core.app.config import AppConfig
from rcon_core.bridge import ConnectionState
from rcon_core.plugins import PluginManager
from rcon_core.sim import SimServer
from rcon_core.testing import qt_flushed

pytestmark = pytest.mark.usefixtures("qapp")

SAY_WHY_MS = 2_000  # the bound: the reason is on screen within 2 s of the first failed attempt


def type_url(window, text: str) -> None:
    line = window.connection.url.lineEdit()
    QTest.mouseClick(line, QtCore.Qt.MouseButton.LeftButton)
    line.selectAll()
    QTest.keyClicks(line, text)
    QTest.keyClick(line, QtCore.Qt.Key.Key_Return)
    qt_flushed()  # a person's next key press comes later: the bar's one-Return-per-press guard resets


@pytest.fixture
def robot():
    with SimServer.in_thread(port=0, rate_scale=2.0) as server:
        yield server


@pytest.fixture
def window(qtbot, tmp_path):
    yield from window_session(qtbot, tmp_path, PluginManager(environ={}), size=(1280, 800))


def test_unreachable_robot_is_said_with_a_countdown_and_its_lists_are_cleared(qtbot, window, robot, tmp_path):
    type_url(window, robot.url.removeprefix("ws://"))
    qtbot.waitUntil(lambda: window.topics.item("/cmd_vel") is not None, timeout=10_000)
    type_url(window, "ws://127.0.0.1:1")
    bar = window.connection
    qtbot.waitUntil(lambda: bar.message.text().startswith("connection refused · retrying"), timeout=SAY_WHY_MS)
    assert bar.state_label.text() == "CONNECTING"
    assert bar.message.toolTip() == bar.message.text()
    # the previous robot's topics are gone: they are not this robot's
    assert window.topics.item("/cmd_vel") is None and window.topics.tree.topLevelItemCount() == 0
    snap(window, "refused")
    # it keeps retrying, counting down to each attempt
    attempts = set()
    qtbot.waitUntil(lambda: attempts.add(bar.failure.retry_at) or len(attempts) >= 3, timeout=10_000)
    assert bar.link.client is not None and bar.connect_button.text() == "Disconnect"
    # only the URL that connected is in the history
    assert AppConfig(tmp_path).url_history == [robot.url]
    items = [bar.url.itemText(i) for i in range(bar.url.count())]
    assert "ws://127.0.0.1:1" not in items


def test_no_such_host_and_not_a_websocket_server(qtbot, window):
    bar = window.connection
    type_url(window, "no-such-robot.invalid:9090")
    qtbot.waitUntil(lambda: bar.message.text().startswith("no such host · retrying"), timeout=SAY_WHY_MS)
    snap(window, "no-such-host")

    import socket
    import threading

    listener = socket.socket()
    listener.bind(("127.0.0.1", 0))
    listener.listen(4)
    stop = threading.Event()

    def answer_http() -> None:  # a web server, not a rosbridge: 404 to everything
        listener.settimeout(0.2)
        while not stop.is_set():
            try:
                conn, _ = listener.accept()
            except OSError:
                continue
            with conn:
                conn.recv(4096)
                conn.sendall(b"HTTP/1.1 404 Not Found\r\nContent-Length: 0\r\nConnection: close\r\n\r\n")

    thread = threading.Thread(target=answer_http, daemon=True)
    thread.start()
    try:
        type_url(window, f"ws://127.0.0.1:{listener.getsockname()[1]}")
        qtbot.waitUntil(lambda: bar.message.text().startswith("not a WebSocket server (HTTP 404)"),
                        timeout=SAY_WHY_MS)
        snap(window, "not-websocket")
    finally:
        window.connection.toggle()  # disconnect before the server goes
        stop.set()
        thread.join(5)
        listener.close()
    assert bar.message.text() == "" and bar.state_label.text() == "DISCONNECTED"


def test_a_url_that_cannot_work_is_rejected_before_connecting(qtbot, window, tmp_path):
    bar = window.connection
    type_url(window, "not a url!!")
    assert bar.link.client is None
    assert bar.message.text() == "'not a url!!' is not a host name or an IP address"
    assert AppConfig(tmp_path).url_history == []
    snap(window, "bad-url")


def test_no_message_widens_the_window_and_the_message_is_true(qtbot, window, robot):
    bar = window.connection
    width = window.width()
    least = window.minimumSizeHint().width()
    assert least <= 1024  # a 1024 px tablet fits it
    bar_least = {"closed": bar.minimumSizeHint().width()}
    height = bar.height()
    type_url(window, "ws://127.0.0.1:1")  # only connecting, never connected
    qtbot.waitUntil(lambda: bar.message.text().startswith("connection refused"), timeout=SAY_WHY_MS)
    bar_least["connecting"] = bar.minimumSizeHint().width()
    type_url(window, "http://robot:9090")
    assert bar.message.text().startswith("'http://robot:9090': the URL must start with ws:// or wss:// · still "
                                         "trying ws://127.0.0.1:1: connection refused · retrying")
    assert "still connected" not in bar.message.text()
    type_url(window, robot.url)
    qtbot.waitUntil(lambda: bar.state is ConnectionState.CONNECTED, timeout=10_000)
    bar_least["connected"] = bar.minimumSizeHint().width()
    # the state word, the Connect/Disconnect label and the latency never change what the bar needs
    assert len(set(bar_least.values())) == 1, bar_least
    type_url(window, "http://robot:9090")
    message = bar.message.text()
    assert message == f"'http://robot:9090': the URL must start with ws:// or wss:// · still connected to {robot.url}"
    QtWidgets.QApplication.processEvents()
    snap(window, "long-message")
    # the whole message is in the tooltip, what fits is on screen, and the window kept its width
    assert bar.message.toolTip() == message
    bar.message.setText("a very long reason " * 60)
    QtWidgets.QApplication.processEvents()
    # a second line where the bar has the height for one, then "…"; nothing moves down
    assert bar.message.shown().endswith("…") and len(bar.message.shown()) < len(bar.message.text())
    assert bar.message.shown().count("\n") <= 1 and bar.height() == height
    assert window.width() == width and window.minimumSizeHint().width() == least
    assert bar.message.geometry().right() <= bar.width()
    assert window.lock_button.mapTo(window, window.lock_button.rect().topRight()).x() <= window.width()
    # a long URL in the history does not widen it either
    bar.url.addItem("ws://" + "a" * 300 + ".example:9090")
    QtWidgets.QApplication.processEvents()
    assert window.width() == width and window.minimumSizeHint().width() == least
