"""The app's config folder (``app.json``: the PIN's hash, its lockout, view-only marks) against a full disk,
other users of the machine, restarts and a second RCON, in the real window where a person would see it.

Found by a probe: a PIN set on a full disk was silently not saved and ``rcon --locked`` then refused to
start (issue 21.1b); ``app.json`` was world-readable and the wrong-PIN lockout reset on restart (21.1c); two
app instances on one config folder erased each other's PIN, view-only marks and layout edits, and concurrent
saves raised FileNotFoundError 64 times in 1,000 (22.8)."""

from __future__ import annotations

import errno
import hashlib
import json
import os
import stat
import subprocess
import sys
import textwrap

import pytest
from app_helpers import TIMEOUT_MS, entry_point_plugins, full_disk, open_window
from qtpy.QtTest import QTest
from test_app_operator_lock import pin_dialog, type_pin

from rcon_core.app.config import AppConfig
from rcon_core.app.operator_lock import BACKOFF_S, MAX_TRIES
from rcon_core.app.pin import SCRYPT_N, check_pin, make_record
from rcon_core.canvas import Geometry, WorkspaceStore
from rcon_core.plugins import Binding

pytestmark = pytest.mark.usefixtures("qapp")
PIN = "246813"


def mode_of(path) -> int:
    return stat.S_IMODE(path.stat().st_mode)


def choose_pin(win, qtbot, pin: str) -> None:
    """Canvas ▾ → Lock Operate mode…: no PIN yet, so choose one (twice), as a person does."""
    win.canvas_actions["lock"].trigger()
    dialog = pin_dialog(win, qtbot)
    type_pin(dialog, pin, pad=True)
    dialog.repeat.setFocus()
    QTest.keyClicks(dialog.repeat, pin)
    dialog.ok.click()
    qtbot.waitUntil(lambda: win.operator_lock.engaged, timeout=TIMEOUT_MS)


def close(win) -> None:
    win.close_now()
    win.shutdown()


@pytest.fixture
def disk(monkeypatch):
    return full_disk(monkeypatch)


def test_a_pin_chosen_on_a_full_disk_locks_this_run_and_says_it_was_not_saved(qtbot, tmp_path, disk):
    win = open_window(qtbot, tmp_path, entry_point_plugins())
    try:
        disk.on = True
        choose_pin(win, qtbot, PIN)
        assert win.operator_lock.engaged and check_pin(win.config.pin_record, PIN)  # it locks this run
        notice = win.notice.label.text()
        assert "⚠ The operator PIN could not be saved" in notice and os.strerror(errno.ENOSPC) in notice
        assert "it locks this run only" in notice and "`rcon --locked` will not start" in notice
        disk.on = False
        assert AppConfig(tmp_path).pin_record is None  # as the notice said
    finally:
        close(win)


def test_app_json_is_readable_by_its_owner_only_and_an_old_wide_one_is_narrowed(tmp_path):
    old = tmp_path / "app.json"
    old.write_text(json.dumps({"version": 2, "url_history": ["ws://boat:9090"]}))
    old.chmod(0o644)
    config = AppConfig(tmp_path)
    assert mode_of(old) == 0o600 and config.url_history == ["ws://boat:9090"]
    config.set_pin_record(make_record(PIN))
    assert mode_of(old) == 0o600
    fresh = tmp_path / "fresh"
    AppConfig(fresh).set_view_only("ws://boat:9090", True)
    assert mode_of(fresh / "app.json") == 0o600


def test_the_wrong_pin_lockout_survives_a_restart(qtbot, tmp_path):
    win = open_window(qtbot, tmp_path, entry_point_plugins())
    choose_pin(win, qtbot, PIN)
    lock = win.operator_lock
    for _ in range(MAX_TRIES - 1):
        assert lock.try_pin("000000") == "wrong PIN"
    close(win)  # four wrong, then a restart: one more wrong PIN is the fifth
    win = open_window(qtbot, tmp_path, entry_point_plugins())
    try:
        lock = win.operator_lock
        assert lock.engage()
        assert lock.try_pin("000000") == f"wrong PIN; too many wrong PINs: try again in {int(BACKOFF_S)} s"
        close(win)
        win = open_window(qtbot, tmp_path, entry_point_plugins())  # and the wait is not over after a restart
        lock = win.operator_lock
        assert lock.engage()
        refused = lock.try_pin(PIN)
        assert refused is not None and refused.startswith("too many wrong PINs: try again in")
        assert 0 < int(refused.rsplit(" ", 2)[1]) <= BACKOFF_S and lock.engaged
    finally:
        close(win)


def test_a_pin_record_from_an_older_app_still_opens_the_lock_and_is_stored_at_todays_cost(qtbot, tmp_path):
    salt = os.urandom(16)
    weak = {"kdf": "scrypt", "n": 2**14, "r": 8, "p": 1, "salt": salt.hex(),
            "hash": hashlib.scrypt(PIN.encode(), salt=salt, n=2**14, r=8, p=1, dklen=32).hex()}
    (tmp_path / "app.json").write_text(json.dumps({"version": 2, "operator_pin": weak}))
    win = open_window(qtbot, tmp_path, entry_point_plugins())
    try:
        assert win.operator_lock.engage()
        assert win.operator_lock.try_pin(PIN) is None and not win.operator_lock.engaged
        stored = json.loads((tmp_path / "app.json").read_text())["operator_pin"]
        assert stored["n"] == SCRYPT_N > weak["n"] and check_pin(stored, PIN)
    finally:
        close(win)


def test_a_second_window_on_one_config_folder_is_read_only_and_erases_nothing(qtbot, tmp_path, sim_url):
    first = open_window(qtbot, tmp_path, entry_point_plugins())
    first.config.set_pin_record(make_record(PIN))
    first.config.set_view_only(sim_url, True)
    placed = first.doc.add_widget(first.controller.canvas.id, "std.label",
                                  Binding("/battery", "sensor_msgs/BatteryState", "subscribe", ("percentage",)),
                                  Geometry(24, 24, 240, 160), {}, "Battery")
    first.controller.saver.flush()
    second = open_window(qtbot, tmp_path, entry_point_plugins())
    try:
        reason = f"another RCON (process {os.getpid()}) is using the config folder {tmp_path}"
        assert second.config.read_only_reason == reason
        notice = second.notice.label.text()
        assert notice.startswith(f"⚠ This window is read-only: {reason}.") and "RCON_CONFIG_DIR" in notice
        # the second window's edits: another PIN, the mark off, the widget gone -- none reaches the disk
        second.config.set_pin_record(make_record("111111"))
        second.config.set_view_only(sim_url, False)
        second.doc.remove_widget(placed.id)
        second.controller.saver.flush()
        close(second)
        again = AppConfig(tmp_path)
        assert check_pin(again.pin_record, PIN) and again.is_view_only(sim_url)
        assert [w.id for w in WorkspaceStore(tmp_path / "workspace.json").load().canvases[0].widgets] == [placed.id]
        # the first window is still the writer: its next change is saved
        first.config.remember_url(sim_url)
        assert AppConfig(tmp_path).url_history == [sim_url]
    finally:
        close(first)
    third = open_window(qtbot, tmp_path, entry_point_plugins())  # once the first closed, the folder is free
    try:
        assert third.config.read_only_reason is None
    finally:
        close(third)


def test_another_process_finds_the_folder_taken_and_says_by_whom(tmp_path):
    config = AppConfig(tmp_path)
    assert config.claim()
    try:
        code = textwrap.dedent(f"""
            from rcon_core.app.config import AppConfig
            c = AppConfig({str(tmp_path)!r})
            print(c.claim(), c.read_only_reason)
        """)
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60, check=True)
        assert out.stdout.strip() == (f"False another RCON (process {os.getpid()}) is using the config folder "
                                      f"{tmp_path}")
    finally:
        config.release()
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60, check=True)
    assert out.stdout.strip() == "True None"


SAVER = textwrap.dedent("""
    import sys
    from rcon_core.app.config import AppConfig
    folder, who, count = sys.argv[1], sys.argv[2], int(sys.argv[3])
    failures = 0
    for k in range(count):
        config = AppConfig(folder)  # as a fresh instance each time: it knows only its own change
        try:
            if not config.set_robot_settings(f"ws://{who}-{k}:9090", {"auth": True}):
                failures += 1
        except Exception as exc:
            failures += 1
            print(type(exc).__name__, exc, file=sys.stderr)
    print(failures)
""")


def test_concurrent_saves_from_two_processes_neither_fail_nor_lose_a_change(tmp_path):
    """The probe's 1,000 saves (two writers) raised FileNotFoundError 64 times; here none fails and every
    writer's every change is in the file at the end."""
    count = 250  # 500 saves in all, two writers at once (the probe made 1,000; the race shows in far fewer)
    procs = [subprocess.Popen([sys.executable, "-c", SAVER, str(tmp_path), who, str(count)],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) for who in ("a", "b")]
    results = [p.communicate(timeout=300) for p in procs]
    assert [(out.strip(), err) for out, err in results] == [("0", ""), ("0", "")]
    robots = json.loads((tmp_path / "app.json").read_text())["robots"]
    assert len(robots) == 2 * count
    assert all(f"ws://{who}-{k}:9090" in robots for who in "ab" for k in range(count))
