"""The operator lock, driven like a person in the real window against the sim: a PIN set in the app (kept
hashed), Operate mode that only the PIN leaves (editing, canvases, the robot, quitting), and
``rcon --locked`` (full screen, locked from the start)."""

from __future__ import annotations

import contextlib
import json

import pytest
from app_helpers import entry_point_plugins, open_window, snap_with, tap
from qtpy.QtTest import QTest
from test_operator_pin import shows_pin

from rcon_core.app.config import AppConfig
from rcon_core.app.main import open_app, run_app
from rcon_core.app.operator_lock import PinDialog
from rcon_core.app.pin import check_pin, make_record
from rcon_core.bridge import ConnectionState
from rcon_core.cli.main import build_parser

pytestmark = pytest.mark.usefixtures("qapp")


def pin_dialog(window, qtbot) -> PinDialog:
    qtbot.waitUntil(lambda: window.operator_lock.dialog is not None and window.operator_lock.dialog.isVisible())
    return window.operator_lock.dialog


def type_pin(dialog: PinDialog, pin: str, *, pad: bool = False) -> None:
    for digit in pin:
        if pad:
            tap(dialog.keys[digit])
        else:
            QTest.keyClick(dialog.field, digit)


def cancel(dialog: PinDialog, qtbot) -> None:
    tap(dialog.cancel)
    qtbot.waitUntil(lambda: not dialog.isVisible())


@pytest.fixture
def window(qtbot, tmp_path, sim_url):
    win = open_window(qtbot, tmp_path, entry_point_plugins(), url=sim_url, wait_connected=True)
    win.controller.add_canvas("Second")  # two canvases: one can be deleted
    win.controller.switch(0)
    yield win
    win.close_now()
    win.shutdown()


def set_pin_and_lock(window, qtbot, pin: str) -> None:
    window.canvas_actions["lock"].trigger()  # Canvas ▾ → Lock Operate mode…: no PIN yet, choose one, twice
    dialog = pin_dialog(window, qtbot)
    assert dialog.repeat is not None
    type_pin(dialog, pin, pad=True)
    dialog.repeat.setFocus()
    QTest.keyClicks(dialog.repeat, pin)
    tap(dialog.ok)
    qtbot.waitUntil(lambda: window.operator_lock.engaged)


def test_the_pin_lock_blocks_editing_leaving_operate_deleting_the_robot_and_quitting(window, qtbot, tmp_path):
    set_pin_and_lock(window, qtbot, "2468")
    lock, ctl = window.operator_lock, window.controller
    assert ctl.canvas.locked and not window.edit_button.icon().isNull()
    stored = (tmp_path / "app.json").read_text()
    assert not shows_pin(json.loads(stored), "2468") and check_pin(json.loads(stored)["operator_pin"], "2468")

    # leaving Operate mode: the PIN first; Cancel keeps Operate
    tap(window.edit_button)
    dialog = pin_dialog(window, qtbot)
    assert "leave Operate mode" in dialog.findChild(type(dialog.message), "pinPrompt").text()
    snap_with(window, dialog, "lock-prompt")
    cancel(dialog, qtbot)
    assert ctl.canvas.locked and lock.engaged and window.lock_button.isChecked()

    # a wrong PIN changes nothing and says so
    tap(window.edit_button)
    dialog = pin_dialog(window, qtbot)
    type_pin(dialog, "1111")
    tap(dialog.ok)
    assert dialog.isVisible() and dialog.message.text() == "wrong PIN" and lock.engaged and ctl.canvas.locked
    cancel(dialog, qtbot)

    # editing the canvases: new canvas asks; deleting and renaming stay off in Operate mode
    canvases = len(ctl.workspace.canvases)
    window.canvas_actions["new"].trigger()
    cancel(pin_dialog(window, qtbot), qtbot)
    assert len(ctl.workspace.canvases) == canvases
    assert not window.canvas_actions["delete"].isEnabled() and not window.canvas_actions["rename"].isEnabled()
    window.canvas_actions["delete"].trigger()
    assert len(ctl.workspace.canvases) == canvases and lock.dialog is None

    # another canvas is shown in Operate mode too
    window.switch_canvas(1)
    qtbot.waitUntil(lambda: ctl.index == 1)
    assert ctl.canvas.locked
    window.switch_canvas(0)
    qtbot.waitUntil(lambda: ctl.index == 0)

    # adding a widget from the side panel: the notice's "Switch to Edit mode" asks for the PIN
    window.palette_panel.picked.emit(window.plugins.widgets()[0].kind)
    tap(window.notice.buttons["Switch to Edit mode"])
    cancel(pin_dialog(window, qtbot), qtbot)
    assert ctl.canvas.locked and not window.add_panel.isVisible()

    # the robot: the URL field is off, Disconnect asks
    assert not window.connection.url.isEnabled()
    tap(window.connection.connect_button)
    cancel(pin_dialog(window, qtbot), qtbot)
    assert window.connection.state is ConnectionState.CONNECTED and window.link.client is not None

    # quitting (Ctrl+Q, the window's close button): asks, Cancel keeps the window
    window.close()
    cancel(pin_dialog(window, qtbot), qtbot)
    assert window.isVisible()

    # the right PIN (typed on the pad) unlocks and the action goes on: Edit mode, then deleting works
    tap(window.edit_button)
    dialog = pin_dialog(window, qtbot)
    type_pin(dialog, "2468", pad=True)
    tap(dialog.ok)
    qtbot.waitUntil(lambda: not lock.engaged and not ctl.canvas.locked)
    assert window.edit_button.isChecked() and window.connection.url.isEnabled()
    window.canvas_actions["delete"].trigger()
    assert len(ctl.workspace.canvases) == canvases - 1


def test_quitting_a_locked_window_needs_the_right_pin(window, qtbot):
    set_pin_and_lock(window, qtbot, "97531")
    window.close()
    dialog = pin_dialog(window, qtbot)
    type_pin(dialog, "97531")
    tap(dialog.ok)
    qtbot.waitUntil(lambda: not window.isVisible())


def test_too_many_wrong_pins_wait_before_the_next_try(window, qtbot):
    set_pin_and_lock(window, qtbot, "2468")
    lock = window.operator_lock
    now = [1000.0]
    lock.clock = lambda: now[0]
    answers = [lock.try_pin("0000") for _ in range(5)]
    assert answers[:4] == ["wrong PIN"] * 4 and "try again in 30 s" in answers[4]
    assert "try again" in lock.try_pin("2468") and lock.engaged  # even the right PIN waits
    now[0] += 31
    assert lock.try_pin("2468") is None and not lock.engaged


def rcon_args(*argv: str):
    return build_parser().parse_args(list(argv))


def test_rcon_locked_starts_full_screen_with_the_lock_on(qtbot, tmp_path, sim_url, monkeypatch):
    monkeypatch.setenv("RCON_CONFIG_DIR", str(tmp_path))
    AppConfig(tmp_path).set_pin_record(make_record("1357"))
    with contextlib.ExitStack() as stack:  # what `rcon --locked --url …` does before its event loop runs
        window = open_app(rcon_args("--locked", "--url", sim_url), stack)
        qtbot.addWidget(window)
        try:
            assert window.isFullScreen() and window.operator_lock.engaged and window.controller.canvas.locked
            qtbot.waitUntil(lambda: window.connection.state is ConnectionState.CONNECTED, timeout=10_000)
            window.close()  # refused while locked: the PIN dialog opens instead
            dialog = pin_dialog(window, qtbot)
            assert window.isVisible() and "quit" in dialog.findChild(type(dialog.message), "pinPrompt").text()
            cancel(dialog, qtbot)
        finally:
            window.close_now()
            window.shutdown()


def test_rcon_locked_without_a_pin_says_how_to_set_one(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("RCON_CONFIG_DIR", str(tmp_path))
    assert run_app(rcon_args("--locked", "--quit-after", "1")) == 2
    assert "--locked needs an operator PIN" in capsys.readouterr().err
