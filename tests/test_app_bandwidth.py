"""The connection bar's bandwidth readout: the total on the bar, the details by topic on a tap."""

from __future__ import annotations

import pytest
from app_helpers import TIMEOUT_MS, window_session
from qtpy import QtCore
from qtpy.QtTest import QTest

from rcon_core.plugins import PluginManager
from rcon_core.sim import SimServer

pytestmark = pytest.mark.usefixtures("qapp")


@pytest.fixture
def robot():
    with SimServer.in_thread(port=0) as server:
        yield server


@pytest.fixture
def window(qtbot, tmp_path, robot):
    yield from window_session(qtbot, tmp_path, PluginManager(environ={}), size=(1280, 800), url=robot.url,
                              wait_connected=True)


def test_bytes_in_by_topic_in_the_bar_and_its_details(qtbot, window):
    bar = window.connection
    button = bar.bandwidth
    width = button.width()
    client = window.link.client
    window.link.thread.call(lambda: client.node("bw").subscribe("/camera/rear/image_raw/compressed",
                                                                lambda m: None, compression="cbor")).result(5)
    qtbot.waitUntil(lambda: button.total > 20_000, timeout=TIMEOUT_MS)
    assert button.text() == button.reading and button.reading.startswith("↓ ") and button.reading.endswith("B/s")
    assert "/camera/rear/image_raw/compressed" in button.details and button.toolTip() == button.details
    assert button.width() == width  # a reading never changes what the bar needs
    QTest.mouseClick(button, QtCore.Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: button.popup is not None and button.popup.isVisible(), timeout=3000)
    lines = button.popup.text().splitlines()
    assert lines[0] == "Bytes per second in, by topic:" and lines[1].startswith("in all: ")
    assert lines[2].split()[-1] == "/camera/rear/image_raw/compressed"  # the biggest first
    assert button.popup.width() >= button.popup.sizeHint().width()  # nothing cut
    button.popup.close()
    window.connection.toggle()  # disconnect
    qtbot.waitUntil(lambda: button.text() == "↓ —", timeout=TIMEOUT_MS)


def test_a_narrow_window_squeezes_the_readout_not_the_window(qtbot, tmp_path, robot):
    made = window_session(qtbot, tmp_path, PluginManager(environ={}), size=(800, 600), url=robot.url,
                          wait_connected=True)
    window = next(made)
    try:
        button = window.connection.bandwidth
        qtbot.waitUntil(lambda: button.reading.endswith("B/s"), timeout=TIMEOUT_MS)
        assert window.width() == 800 and button.width() < button.sizeHint().width()
        assert button.text() in ("↓", "") and button.toolTip().startswith("Bytes per second in")
    finally:
        next(made, None)
