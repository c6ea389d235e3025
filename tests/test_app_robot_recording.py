"""A recording file as a robot, added where an operator looks for robots: Canvas ▾ → Robots… → Recording
file… (the real dialog, in the real window, offscreen). The recording plays as one more robot beside the
live one (its own timeline bar, view-only: commands go nowhere), is saved with the workspace, and plays
again when the workspace is opened again; a file that is not a recording is refused in the dialog."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from app_helpers import TIMEOUT_MS, entry_point_plugins, open_window, tap
from qtpy import QtWidgets
from record_helpers import DEMO_BAG
from rogue_widget import CMD, RoguePlugin

from rcon_core.bridge import ConnectionState
from rcon_core.canvas import Binding, Geometry

pytestmark = pytest.mark.usefixtures("qapp")

ODOM_X = ("/odom", "nav_msgs/Odometry", "subscribe", ("pose.pose.position.x",))


@pytest.fixture
def plugins():
    pytest.importorskip("rcon_widgets_std")
    pm = entry_point_plugins()
    pm.register(RoguePlugin(view="rogue_widget_view:RogueView"), "rogue")
    return pm


def robots_dialog(win):
    """Canvas ▾ → Robots… as the operator opens it (the menu action)."""
    win.canvas_actions["robots"].trigger()
    dialog = win.fleet_ui.robots_dialog
    assert dialog.isVisible()
    return dialog


def pick_file(monkeypatch, path: Path) -> None:
    """The file dialog answers ``path`` (as if the operator picked it)."""
    monkeypatch.setattr(QtWidgets.QFileDialog, "getOpenFileName",
                        staticmethod(lambda *_a, **_k: (str(path), "")))


def place(win, kind, binding, x, title="", settings=None):
    return win.doc.add_widget(win.controller.canvas.id, kind, binding, Geometry(x, 24, 240, 160), settings or {},
                              title)


def model_of(qtbot, win, widget_id):
    qtbot.waitUntil(lambda: (h := win.host.hosted.get(widget_id)) is not None and h.model is not None,
                    timeout=TIMEOUT_MS)
    return win.host.hosted[widget_id].model


def test_a_recording_file_added_in_the_robots_dialog_plays_as_a_robot_and_is_saved(
        qtbot, tmp_path, plugins, sim_thread, monkeypatch):
    cfg = tmp_path / "cfg"
    win = open_window(qtbot, cfg, plugins, url=sim_thread.url, wait_connected=True)
    try:
        dialog = robots_dialog(win)
        pick_file(monkeypatch, DEMO_BAG)
        tap(dialog.findChild(QtWidgets.QPushButton, "addRecording"))
        assert dialog.table.rowCount() == 2
        assert dialog.table.item(1, 0).text() == "demo"  # named after the file
        assert dialog.table.item(1, 1).text() == str(DEMO_BAG)  # where it comes from, in the URL column
        ok = dialog.findChild(QtWidgets.QDialogButtonBox).button(QtWidgets.QDialogButtonBox.StandardButton.Ok)
        tap(ok)
        robots = win.doc.workspace.robots
        assert [r.recording for r in robots] == ["", str(DEMO_BAG)] and robots[1].url == ""
        rid = robots[1].id
        chips = win.fleet_ui.chips
        qtbot.waitUntil(lambda: chips.chips[rid].state is ConnectionState.CONNECTED, timeout=TIMEOUT_MS)
        bar = win.fleet_ui.recordings.bars[rid]  # its own timeline, under the connection bar
        qtbot.waitUntil(bar.isVisible, timeout=TIMEOUT_MS)
        assert "demo.bag" in bar.words.text() and "commands go nowhere" in bar.words.text()
        assert win.connection.state is ConnectionState.CONNECTED  # the live robot stays connected

        x = place(win, "std.label", Binding(*ODOM_X, robot=rid), 24, "x")
        qtbot.waitUntil(lambda: model_of(qtbot, win, x.id).state.count > 0, timeout=TIMEOUT_MS)
        rogue = place(win, "test.rogue", Binding("/cmd_vel", "geometry_msgs/Twist", "publish", robot=rid), 288)
        model = model_of(qtbot, win, rogue.id)
        qtbot.waitUntil(lambda: "recording" in (model.view_only or ""), timeout=TIMEOUT_MS)
        model.publish(CMD)  # sent anyway: refused, said
        qtbot.waitUntil(lambda: "recording" in (model.state.error or ""), timeout=TIMEOUT_MS)
        player = win.fleet_ui.recordings.players[rid]
        assert player.absorbed == {}  # nothing even reached the recording
        win.controller.saver.flush()
    finally:
        win.shutdown()

    saved = json.loads((cfg / "workspace.json").read_text())
    assert [r.get("recording", "") for r in saved["robots"]] == ["", str(DEMO_BAG)]
    # opened again: the recording plays as that robot again (no URL of a player of the last run is kept)
    again = open_window(qtbot, cfg, plugins, url=sim_thread.url, wait_connected=True)
    try:
        chips = again.fleet_ui.chips
        qtbot.waitUntil(lambda: chips.chips[rid].state is ConnectionState.CONNECTED, timeout=TIMEOUT_MS)
        qtbot.waitUntil(lambda: model_of(qtbot, again, x.id).state.count > 0, timeout=TIMEOUT_MS)
    finally:
        again.shutdown()


def test_a_file_that_is_not_a_recording_is_refused_in_the_dialog(qtbot, tmp_path, plugins, monkeypatch):
    win = open_window(qtbot, tmp_path / "cfg", plugins)
    try:
        dialog = robots_dialog(win)
        junk = tmp_path / "notes.mcap"
        junk.write_text("not a recording")
        pick_file(monkeypatch, junk)
        tap(dialog.findChild(QtWidgets.QPushButton, "addRecording"))
        assert dialog.table.rowCount() == 1  # nothing added
        assert "notes.mcap" in dialog.problem.text()
        dialog.reject()
        assert [r.recording for r in win.doc.workspace.robots] == [""]
    finally:
        win.shutdown()
