"""Dangerous commands on the standard Button and Switch, tapped in the real window against the sim:
"ask before sending" shows the exact service and request and sends nothing on Cancel; "hold to send"
sends after a 1 s hold (a bar fills) and nothing on a short press."""

from __future__ import annotations

import pytest
from app_helpers import (
    LEFT,
    NO_MOD,
    TIMEOUT_MS,
    all_sent,
    snap_with,
    tap,
    window_session,
)
from qtpy import QtCore, QtWidgets
from qtpy.QtTest import QTest

from rcon_core.canvas import Binding, Geometry

pytestmark = pytest.mark.usefixtures("qapp")
CALLS = ("call_service", "/lights/set")


@pytest.fixture
def window(qtbot, tmp_path, sim_url, plugins):
    yield from window_session(qtbot, tmp_path, plugins, url=sim_url, wait_connected=True)


def place(window, qtbot, kind, binding, x, title, settings):
    w = window.doc.add_widget(window.controller.canvas.id, kind, binding, Geometry(x, 24, 240, 160), settings, title)
    window.controller.set_locked(True)  # Operate mode: the views take the taps

    def ready():
        hosted = window.host.hosted.get(w.id)
        return (hosted is not None and hosted.view is not None and hosted.view.isVisible()
                and hosted.model.types_ready)  # a view put in a shown frame is shown on the next pass
    qtbot.waitUntil(ready, timeout=TIMEOUT_MS)
    return window.host.hosted[w.id].view


def confirm_box(qtbot, view) -> QtWidgets.QMessageBox:
    qtbot.waitUntil(lambda: view.guard.dialog is not None and view.guard.dialog.isVisible(), timeout=TIMEOUT_MS)
    return view.guard.dialog


def answer(qtbot, box, name: str) -> None:
    [button] = [b for b in box.buttons() if b.objectName() == name]
    tap(button)
    qtbot.waitUntil(lambda: not box.isVisible(), timeout=TIMEOUT_MS)


def test_ask_before_sending_shows_the_exact_call_and_cancel_sends_nothing(window, qtbot, sim_thread):
    sim = sim_thread
    sim.robot.lights = False
    view = place(window, qtbot, "std.button", Binding("/lights/set", "std_srvs/SetBool", "call"), 24, "Lights on",
                 {"payload": "data: true", "confirm": True})
    calls = sim.ops_received[CALLS]
    tap(view.button)
    box = confirm_box(qtbot, view)
    assert box.text() == "Call /lights/set (std_srvs/SetBool)?"
    assert box.informativeText() == "Request:\ndata: true"
    snap_with(window, box, "confirm-dialog")
    answer(qtbot, box, "sendConfirmCancel")
    all_sent(qtbot, window, sim)
    assert sim.ops_received[CALLS] == calls and sim.robot.lights is False

    tap(view.button)
    answer(qtbot, confirm_box(qtbot, view), "sendConfirmYes")
    qtbot.waitUntil(lambda: sim.robot.lights is True, timeout=TIMEOUT_MS)
    assert sim.ops_received[CALLS] == calls + 1


def test_hold_to_send_needs_a_full_second_and_a_short_press_sends_nothing(window, qtbot, sim_thread):
    sim = sim_thread
    sim.robot.lights = True
    view = place(window, qtbot, "std.button", Binding("/lights/set", "std_srvs/SetBool", "call"), 24, "Lights off",
                 {"payload": "data: false", "hold_to_send": True})
    calls = sim.ops_received[CALLS]
    button = view.button
    tap(button)  # a short press
    assert view.face.text == "✗ hold 1 s" and view.button.text() == "✗ hold 1 s"  # in full, never cut
    QTest.keyClick(button, QtCore.Qt.Key.Key_Space)  # the keyboard cannot hold
    all_sent(qtbot, window, sim)
    assert sim.ops_received[CALLS] == calls and sim.robot.lights is True and view.guard.refused == 1

    QTest.mousePress(button, LEFT, NO_MOD, button.rect().center())
    qtbot.waitUntil(lambda: 0 < view.guard.progress.value() < 100, timeout=TIMEOUT_MS)
    assert view.guard.progress.isVisible() and sim.ops_received[CALLS] == calls  # filling, nothing sent yet
    qtbot.waitUntil(lambda: view.guard.sent == 1, timeout=TIMEOUT_MS)
    QTest.mouseRelease(button, LEFT, NO_MOD, button.rect().center())
    qtbot.waitUntil(lambda: sim.robot.lights is False, timeout=TIMEOUT_MS)
    assert sim.ops_received[CALLS] == calls + 1 and not view.guard.progress.isVisible()


def test_a_switch_asks_with_the_state_it_will_set(window, qtbot, sim_thread):
    sim = sim_thread
    sim.robot.lights = False
    view = place(window, qtbot, "std.switch", Binding("/lights/set", "std_srvs/SetBool", "call", ("request.data",)),
                 24, "Lights", {"confirm": True, "hold_to_send": True, "state_topic": "/lights/state"})
    qtbot.waitUntil(lambda: getattr(view.model.state.value, "on", None) is False, timeout=TIMEOUT_MS)
    calls = sim.ops_received[CALLS]
    button = view.button
    QTest.mousePress(button, LEFT, NO_MOD, button.rect().center())
    box = confirm_box(qtbot, view)  # after the hold
    QTest.mouseRelease(button, LEFT, NO_MOD, button.rect().center())
    assert box.text() == "Call /lights/set (std_srvs/SetBool)?" and box.informativeText() == "Request:\ndata: true"
    assert not button.isChecked()
    answer(qtbot, box, "sendConfirmCancel")
    all_sent(qtbot, window, sim)
    assert sim.ops_received[CALLS] == calls and sim.robot.lights is False

    QTest.mousePress(button, LEFT, NO_MOD, button.rect().center())
    box = confirm_box(qtbot, view)
    QTest.mouseRelease(button, LEFT, NO_MOD, button.rect().center())
    answer(qtbot, box, "sendConfirmYes")
    qtbot.waitUntil(lambda: sim.robot.lights is True and button.isChecked(), timeout=TIMEOUT_MS)
    assert sim.ops_received[CALLS] == calls + 1
