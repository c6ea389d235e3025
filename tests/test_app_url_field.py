"""The connection bar's URL field, driven by key presses and taps on the real window against the sim:
Enter connects to exactly what was typed (the history is a list to pick from, never completed inline),
and a URL too long for the field keeps its scheme and its port in sight (the middle is elided)."""

from __future__ import annotations

import json

import pytest
from app_helpers import TIMEOUT_MS, open_window, settle, tap, tap_item
from fit_check import problems
from qtpy import QtCore, QtWidgets
from qtpy.QtTest import QTest

from rcon_core.bridge import ConnectionState
from rcon_core.sim.server import SimServer

pytestmark = pytest.mark.usefixtures("qapp")


@pytest.fixture
def robot():
    with SimServer.in_thread(port=0) as server:
        yield server


def history(tmp_path, urls: list[str]) -> None:
    (tmp_path / "app.json").write_text(json.dumps({"version": 2, "url_history": urls}))


def type_into_field(window, text: str, enter: bool = True) -> None:
    """Tap the URL field, select what it holds and type ``text`` key by key (then Enter)."""
    line = window.connection.url.lineEdit()
    tap(line)
    line.selectAll()
    QTest.keyClicks(line, text)
    if enter:
        QTest.keyClick(line, QtCore.Qt.Key.Key_Return)


def test_enter_connects_to_exactly_what_was_typed_never_to_a_longer_url_from_the_history(
        qtbot, tmp_path, robot, plugins):
    typed = f"ws://127.0.0.1:{robot.port}"
    # the history holds a URL that starts with what is typed (the operator's other robot), newest first
    longer = f"ws://127.0.0.1:{robot.port}1"
    history(tmp_path, [longer, "ws://127.0.0.1:9090"])
    window = open_window(qtbot, tmp_path, plugins)
    try:
        type_into_field(window, typed)
        assert window.link.url == typed  # not the history's longer URL
        qtbot.waitUntil(lambda: window.connection.state is ConnectionState.CONNECTED, timeout=TIMEOUT_MS)
        assert window.connection.url.currentText() == typed
        # a shorter prefix neither: "ws://127.0.0.1:9" is not completed to the history's ":9090"
        window.connection.toggle()  # disconnect
        type_into_field(window, "ws://127.0.0.1:9", enter=False)
        line = window.connection.url.lineEdit()
        assert line.text() == "ws://127.0.0.1:9" and not line.hasSelectedText()
        QTest.keyClick(line, QtCore.Qt.Key.Key_Return)
        assert window.link.url == "ws://127.0.0.1:9"
    finally:
        window.shutdown()


def test_the_history_is_a_list_to_pick_from(qtbot, tmp_path, robot, plugins):
    url = f"ws://127.0.0.1:{robot.port}"
    history(tmp_path, ["ws://127.0.0.1:9", url])
    window = open_window(qtbot, tmp_path, plugins)
    try:
        combo = window.connection.url
        assert [combo.itemText(i) for i in range(combo.count())] == ["ws://127.0.0.1:9", url]
        tap(combo, QtCore.QPoint(combo.width() - 12, combo.height() // 2))  # the arrow opens the list
        view = combo.view()
        qtbot.waitUntil(view.isVisible, timeout=TIMEOUT_MS)
        for _ in range(5):  # a popup ignores a release that comes too soon after it opened (slow machine)
            QTest.qWait(QtWidgets.QApplication.doubleClickInterval() + 100)
            tap_item(view, combo.model().index(1, 0))
            if not view.isVisible():
                break
        qtbot.waitUntil(lambda: not view.isVisible(), timeout=TIMEOUT_MS)
        assert combo.currentText() == url
        tap(window.connection.connect_button)
        qtbot.waitUntil(lambda: window.connection.state is ConnectionState.CONNECTED, timeout=TIMEOUT_MS)
        assert window.link.url == url
    finally:
        window.shutdown()


def test_a_long_url_keeps_its_host_in_sight(qtbot, tmp_path, plugins):
    url = "wss://operations-vessel-kingfisher-07.harbour.example.org:9090"
    history(tmp_path, [url])
    window = open_window(qtbot, tmp_path, plugins, size=(1024, 600))
    try:
        settle()
        field = window.connection.url
        line = field.lineEdit()
        assert line.fontMetrics().horizontalAdvance(url) > line.width()  # too long for the field
        shown = line.shown_text()
        assert shown.startswith("…operations-vessel-kingfisher-07") and shown.endswith("…"), shown
        assert line.fontMetrics().horizontalAdvance(shown) <= line.text_rect().width()
        assert field.currentText() == url and line.toolTip() == url  # the field's value is the whole URL
        line.grab()  # painted: what the paint drew is what shown_text() says
        assert line.painted == shown
        # while editing, the whole text is there to edit
        tap(line)
        assert line.hasFocus() and line.text() == url
    finally:
        window.shutdown()


@pytest.fixture
def standard_look():
    yield
    from rcon_core.app import theme

    theme.apply(QtWidgets.QApplication.instance(), theme.DEFAULT_THEME, 100)


@pytest.mark.parametrize("text_size", [100, 150, 200])
def test_on_a_1024_px_window_the_field_shows_which_robot_at_every_text_size(qtbot, tmp_path, robot, plugins,
                                                                            text_size, standard_look):
    """Found walking the app on a 1024x600 tablet: the field showed "ws://1…1:45991" (and at 200 % text
    "w…5"): the scheme and the port, never the host, the part that tells which robot it is. The field now
    shows the host whole -- connected, and for the robots of its list -- at 100, 150 and 200 % text (the
    latency and the bandwidth readout give way first), the window still 1024 px wide."""
    from rcon_core.app.display_settings import set_display

    others = {"ws://192.168.1.10:9090": "192.168.1.10",
              "wss://kingfisher-07.harbour.example.org:9090": "kingfisher-07"}
    history(tmp_path, list(others))
    window = open_window(qtbot, tmp_path, plugins, size=(1024, 600), url=robot.url, wait_connected=True)
    try:
        set_display(window.config, None, text_size=text_size)
        field, line = window.connection.url, window.connection.url.lineEdit()

        def shows(host: str) -> None:
            settle()
            assert host in line.shown_text(), (host, line.shown_text(), field.width())

        for url, host in [(robot.url, "127.0.0.1"), *others.items()]:
            if url != robot.url:
                if window.link.client is not None:  # disconnected: the longest state word
                    window.connection.toggle()
                qtbot.waitUntil(lambda: window.connection.state is ConnectionState.CLOSED, timeout=TIMEOUT_MS)
                field.setCurrentText(url)  # another robot's URL, as picked from the list
            qtbot.waitUntil(lambda host=host: shows(host), timeout=TIMEOUT_MS)
            shown = line.shown_text()
            assert line.fontMetrics().horizontalAdvance(shown) <= line.text_rect().width(), shown
            line.grab()
            assert line.painted == shown and field.currentText() == url and line.toolTip() == url
            assert window.width() == 1024, (text_size, window.width())
            assert problems(window.connection) == []  # nothing on the bar cut (the latency: whole, or none)
            if url == robot.url:  # connected: the field shows the port too (the sim's, which tells sims apart)
                assert shown.endswith(f":{robot.port}") or text_size == 200, shown
                qtbot.waitUntil(lambda: window.connection.state_label.toolTip().startswith(
                    "round trip to the robot: "), timeout=TIMEOUT_MS)  # where the latency has no room too
    finally:
        window.shutdown()
