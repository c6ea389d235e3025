"""The connection bar says DEGRADED while the link to the robot is stalled (issue 11, item 5), then
CONNECTED again when it recovers; the link is the sim behind a loopback proxy that stops forwarding."""

from __future__ import annotations

import asyncio

import pytest
from app_helpers import entry_point_plugins, window_session

from rcon_core.bridge import ConnectionState
from rcon_core.loopback import StallProxy

pytestmark = pytest.mark.usefixtures("qapp")


@pytest.fixture
def proxy(sim_thread):
    proxy = StallProxy("127.0.0.1", sim_thread.port)
    asyncio.run_coroutine_threadsafe(proxy.start(), sim_thread.loop).result(10)
    yield proxy
    asyncio.run_coroutine_threadsafe(proxy.stop(), sim_thread.loop).result(10)


@pytest.fixture
def window(qtbot, tmp_path, proxy):
    yield from window_session(qtbot, tmp_path / "config", entry_point_plugins(), url=proxy.url,
                              wait_connected=True)


def test_a_stalled_link_shows_degraded_then_connected_again(window, qtbot, proxy, sim_thread):
    bar = window.connection
    assert bar.state_label.text() == "CONNECTED"
    sim_thread.run_sync(proxy.stall)
    qtbot.waitUntil(lambda: bar.state is ConnectionState.DEGRADED, timeout=3_000)
    assert bar.state_label.text() == "DEGRADED" and bar.state_label.property("state") == "degraded"
    assert bar.connect_button.text() == "Disconnect"
    sim_thread.run_sync(proxy.resume)
    qtbot.waitUntil(lambda: bar.state is ConnectionState.CONNECTED, timeout=5_000)
    assert bar.state_label.text() == "CONNECTED"
