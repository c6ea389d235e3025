"""While the operator lock is on, everything that changes the robot outside Operate-mode widgets asks for the
PIN first, driven like a person in the real window against the sim (issue 21.2: a locked app asked only
"Set it?" before writing a parameter; 21.1d: the Security dialog was not gated, and unticking rosauth in
it deleted the stored secret)."""

from __future__ import annotations

import pytest
from app_helpers import TIMEOUT_MS, entry_point_plugins, open_window, tap, tap_item
from qtpy import QtWidgets
from test_app_operator_lock import cancel, pin_dialog, type_pin
from test_app_params import name_of, open_params, tap_param, type_into, value_on_robot, wait_written

from rcon_core.app.pin import make_record

keyring = pytest.importorskip("keyring")
from test_app_secure_link import MemoryKeyring  # noqa: E402

pytestmark = pytest.mark.usefixtures("qapp")
PIN = "735911"


@pytest.fixture
def locked(qtbot, tmp_path, sim_thread):
    win = open_window(qtbot, tmp_path, entry_point_plugins(), url=sim_thread.url, wait_connected=True,
                      services=("/lights/set",))
    win.config.set_pin_record(make_record(PIN))
    assert win.operator_lock.engage()
    yield win
    win.close_now()
    win.shutdown()


def prompt(dialog) -> str:
    return dialog.findChild(QtWidgets.QLabel, "pinPrompt").text()


def test_a_parameter_write_needs_the_pin_while_locked(locked, qtbot, sim_thread):
    win, sim = locked, sim_thread
    panel = open_params(win, qtbot)
    name = name_of(1, "max_speed")
    tap_param(panel, name)
    type_into(panel.edit_value, "5.0")
    tap(panel.set_button)
    dialog = pin_dialog(win, qtbot)  # the PIN before the question, not only "Set it?"
    assert f"set {name}" in prompt(dialog)
    assert getattr(win, "confirm_dialog", None) is None
    cancel(dialog, qtbot)
    assert value_on_robot(1, sim, "max_speed") == 2.0 and getattr(win, "confirm_dialog", None) is None

    tap(panel.set_button)
    dialog = pin_dialog(win, qtbot)
    type_pin(dialog, PIN, pad=True)
    tap(dialog.ok)
    qtbot.waitUntil(lambda: win.confirm_dialog is not None and win.confirm_dialog.isVisible(), timeout=TIMEOUT_MS)
    tap(win.confirm_dialog.findChild(QtWidgets.QPushButton, "confirmYes"))
    wait_written(qtbot, panel)
    assert value_on_robot(1, sim, "max_speed") == 5.0


def test_calling_a_service_from_the_side_panel_needs_the_pin_while_locked(locked, qtbot):
    win = locked
    win.side.setCurrentWidget(win.services)
    tree = win.services.tree
    tap_item(tree, tree.indexFromItem(win.services.item("/lights/set")))
    assert not win.add_panel.isVisible()  # Operate mode: the notice offers Edit mode, which is locked
    tap(win.notice.buttons["Switch to Edit mode"])
    dialog = pin_dialog(win, qtbot)
    assert "add widgets" in prompt(dialog)
    cancel(dialog, qtbot)
    assert not win.add_panel.isVisible() and win.controller.canvas.locked


def test_the_robots_dialog_needs_the_pin_while_locked(locked, qtbot):
    win = locked
    win.canvas_actions["robots"].trigger()
    dialog = pin_dialog(win, qtbot)
    assert "edit the robots" in prompt(dialog)
    cancel(dialog, qtbot)
    assert getattr(win.fleet_ui, "robots_dialog", None) is None


@pytest.fixture
def store():
    previous = keyring.get_keyring()
    backend = MemoryKeyring()
    keyring.set_keyring(backend)
    yield backend
    keyring.set_keyring(previous)


def test_the_security_dialog_needs_the_pin_while_locked_and_keeps_the_secret(locked, qtbot, store, sim_url):
    win = locked
    bar = win.connection
    win.config.set_robot_settings(sim_url, {"auth": True})
    bar.secrets.set(sim_url, "robot-secret")
    tap(bar.settings_button)
    dialog = pin_dialog(win, qtbot)
    assert "connection settings" in prompt(dialog)
    assert bar.dialog is None  # not opened: its rosauth box cannot be unticked
    cancel(dialog, qtbot)
    assert bar.dialog is None and store.get_password("rcon", sim_url) == "robot-secret"

    tap(bar.settings_button)
    dialog = pin_dialog(win, qtbot)
    type_pin(dialog, PIN, pad=True)
    tap(dialog.ok)
    qtbot.waitUntil(lambda: bar.dialog is not None and bar.dialog.isVisible(), timeout=TIMEOUT_MS)
    bar.dialog.reject()


def test_a_connect_that_needs_a_secret_asks_for_the_pin_before_the_security_dialog(locked, qtbot, store, sim_url):
    win = locked
    bar = win.connection
    win.config.set_robot_settings(sim_url, {"auth": True})  # no secret known: the dialog would ask for it
    bar.connect_clicked()  # as the window's own connect at start (`rcon --locked`) does
    dialog = pin_dialog(win, qtbot)
    assert "connection settings" in prompt(dialog) and bar.dialog is None
    cancel(dialog, qtbot)
    assert bar.dialog is None and win.operator_lock.engaged
