"""Disconnect keeps the canvas's widgets with their last values, marked LINK DOWN (then STALE), as a lost link
does; Connect again brings live values back. Driven with taps against the sim."""

from __future__ import annotations

import pytest
from app_helpers import choose_kind, entry_point_plugins, tap, tap_topic, window_session

from rcon_core.app.main_window import MainWindow
from rcon_core.bridge import ConnectionState
from rcon_core.plugins import Role

pytestmark = pytest.mark.usefixtures("qapp")


@pytest.fixture
def window(qtbot, tmp_path, sim_thread):
    pytest.importorskip("rcon_widgets_std")
    yield from window_session(qtbot, tmp_path / "config", entry_point_plugins(), url=sim_thread.url,
                              size=(1280, 800), topics=("/battery",))


def place_battery_label(window: MainWindow) -> str:
    tap_topic(window, "/battery")
    tap(choose_kind(window, Role.SUBSCRIBE, "std.label").place_button)
    return window.controller.canvas.widgets[-1].id


def shown(window: MainWindow, wid: str) -> str:
    view = window.host.hosted[wid].view
    return view.value.text() if view is not None else ""


def test_disconnect_keeps_the_last_values_marked_link_down_and_connect_brings_them_back(window, qtbot):
    wid = place_battery_label(window)
    qtbot.waitUntil(lambda: shown(window, wid) not in ("", "–"), timeout=10_000)
    frame = window.controller.surface.frames[wid]
    assert not frame.badge.isVisible()
    live = window.host.hosted[wid]
    model, view = live.model, live.view

    tap(window.connection.connect_button)  # "Disconnect"
    qtbot.waitUntil(lambda: window.connection.state is ConnectionState.CLOSED, timeout=5_000)
    qtbot.waitUntil(lambda: frame.badge.isVisible() and frame.badge.status == "LINK DOWN", timeout=5_000)
    # everything the Disconnect asked of the bridge thread has run (one queue, in order), and whatever it
    # sent back is applied: a rebuild, were there one, is in place now
    window.link.thread.call(lambda: None).result(5)
    window._pump()
    kept = window.host.hosted[wid].model
    assert kept is model and window.host.hosted[wid].view is view  # kept, not rebuilt
    last = shown(window, wid)
    assert last not in ("", "–"), last  # still the last value, not "–" (no data yet)
    assert window.connection.connect_button.text() == "Connect"

    # another canvas while disconnected runs offline; back on this one, its widget shows LINK DOWN
    window.controller.add_canvas("Other")
    window.switch_canvas(0)
    qtbot.waitUntil(lambda: window.host.hosted[wid].model is not kept and window.host.hosted[wid].view is not None,
                    timeout=10_000)
    qtbot.waitUntil(lambda: frame.badge.isVisible() and frame.badge.status == "LINK DOWN", timeout=5_000)

    tap(window.connection.connect_button)  # Connect again: live values
    qtbot.waitUntil(lambda: window.connection.state is ConnectionState.CONNECTED, timeout=10_000)
    qtbot.waitUntil(lambda: not frame.badge.isVisible(), timeout=10_000)
    qtbot.waitUntil(lambda: shown(window, wid) not in ("", "–"), timeout=10_000)
    # rebuilt on the new link, and taking the robot's values
    qtbot.waitUntil(lambda: window.host.hosted[wid].model is not kept, timeout=10_000)
    qtbot.waitUntil(lambda: window.host.hosted[wid].model.state.value is not None, timeout=10_000)
