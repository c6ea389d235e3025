"""Sharing one canvas between tablets: Canvas ▾ Export canvas… / Import canvas… end to end.

One window (its own config dir) exports a canvas through the file dialog; a second window (another config
dir, as on a colleague's tablet) imports it: unique name, fresh ids where they clash, placeholders for a
missing plugin, the widgets running on the embedded robot, one undo step. Bad files change nothing.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from app_helpers import open_window as open_app_window
from app_helpers import tap
from qtpy import QtWidgets
from test_app_window import make_plugins, running

from rcon_core.app.canvas_controller import file_name_for, name_from_file
from rcon_core.app.main_window import MainWindow
from rcon_core.canvas import Binding, Geometry, WorkspaceStore

pytestmark = pytest.mark.usefixtures("qapp")

#: a widget kind no installed plugin provides, with settings only its plugin would understand
MISSING_KIND = "lab.gripper"
MISSING_SETTINGS = {"opening": 0.25, "limits": [0, 1], "nested": {"é": "ü", "n": None}}


def open_window(qtbot, config_dir: Path, url: str | None = None) -> MainWindow:
    """The probe plugin's window at the offscreen screen's size, connected to ``url`` if given."""
    window = open_app_window(qtbot, config_dir, make_plugins(), url=url, size=None, wait_connected=True)
    window.canvas_files.share_dir = config_dir.parent  # never the real home folder
    return window


def tap_notice(qtbot, window: MainWindow, label: str) -> None:
    """Tap the notice bar's button ``label`` once it shows (a button added to a shown bar appears on the
    next turn of the event loop)."""
    button = window.notice.buttons[label]
    qtbot.waitUntil(button.isVisible, timeout=5_000)
    tap(button)


def build_docking(window: MainWindow) -> None:
    """A demo-like canvas "Docking": two live probes and one widget whose plugin is missing, locked
    (operator mode), as a colleague would hand it over."""
    window.controller.add_canvas("Docking")
    doc, canvas = window.doc, window.controller.canvas
    doc.add_widget(canvas.id, "apptest.probe", Binding("/battery", "sensor_msgs/BatteryState", "subscribe",
                                                       ("percentage",)),
                   Geometry(32, 32, 192, 112), {"caption": "Charge", "digits": 1}, "Charge")
    doc.add_widget(canvas.id, "apptest.probe", Binding("/lights/state", "std_msgs/Bool", "subscribe", ("data",)),
                   Geometry(240, 32, 192, 112), {"caption": "Lights", "digits": 2}, "Lights")
    doc.add_widget(canvas.id, MISSING_KIND, Binding("/gripper", "lab_msgs/Gripper", "publish", ("opening",)),
                   Geometry(32, 160, 256, 96), MISSING_SETTINGS, "Gripper")
    window.controller.set_locked(True)


def pick(dialog: QtWidgets.QFileDialog, path: Path | None = None) -> None:
    """What the operator does in the file dialog: (type a name and) press Save/Open."""
    assert dialog.isVisible() and dialog.testOption(QtWidgets.QFileDialog.Option.DontUseNativeDialog)
    if path is not None:
        dialog.selectFile(str(path))
    dialog.accept()


def test_export_from_one_tablet_import_on_another_runs_on_the_robot_and_undoes(qtbot, tmp_path, sim_thread,
                                                                                sim_url):
    sender = open_window(qtbot, tmp_path / "tablet-a", sim_url)
    build_docking(sender)
    exported = sender.controller.canvas
    assert [a.text() for a in sender.menu_button.menu().actions()][-2:] == ["Export canvas…", "Import canvas…"]
    # export works in Operate mode (it changes nothing); the dialog proposes the canvas's name
    sender.canvas_actions["export"].trigger()
    dialog = sender.canvas_files.dialog
    assert dialog.objectName() == "exportDialog"
    assert dialog.acceptMode() == QtWidgets.QFileDialog.AcceptMode.AcceptSave
    assert [Path(f).name for f in dialog.selectedFiles()] == ["Docking.rcon-canvas.json"]
    files = dialog.findChild(QtWidgets.QTreeView, "treeView")  # rows a finger can pick
    qtbot.waitUntil(lambda: files.model().rowCount(files.rootIndex()) > 0, timeout=10_000)
    assert files.visualRect(files.model().index(0, 0, files.rootIndex())).height() >= 48
    pick(dialog)
    path = tmp_path / "Docking.rcon-canvas.json"
    assert path.is_file() and sender.controller.canvas.locked
    assert sender.notice.kind == "info" and str(path) in sender.banner.text()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # no temp file left behind
    data = json.loads(path.read_text(encoding="utf-8"))
    assert data["format"] == "rcon-canvas" and data["version"] == 2
    assert data["canvas"]["name"] == "Docking"
    assert [w["id"] for w in data["canvas"]["widgets"]] == [w.id for w in exported.widgets]
    assert data["canvas"]["widgets"][2]["settings"] == MISSING_SETTINGS
    sender.shutdown()  # the sender's widgets leave the robot
    for topic in ("/battery", "/lights/state"):
        qtbot.waitUntil(lambda t=topic: sim_thread.topic_subscriber_count(t) == 0, timeout=10_000)

    receiver = open_window(qtbot, tmp_path / "tablet-b", sim_url)
    try:
        doc = receiver.doc
        assert [c.name for c in doc.workspace.canvases] == ["Main"] and not doc.can_undo
        dialog = receiver.canvas_files.import_dialog()
        assert dialog is receiver.canvas_files.dialog and dialog.objectName() == "importDialog"
        assert dialog.fileMode() == QtWidgets.QFileDialog.FileMode.ExistingFile
        pick(dialog, path)
        canvas = receiver.controller.canvas  # switched to it
        assert canvas.name == "Docking" and receiver.tabs.tabText(receiver.tabs.currentIndex()) == "Docking"
        assert not canvas.locked and receiver.edit_button.isChecked()  # Edit mode: ↶ takes it back at once
        assert [(w.kind, w.title, w.binding, w.geometry) for w in canvas.widgets] == \
            [(w.kind, w.title, w.binding, w.geometry) for w in exported.widgets]
        assert [w.settings for w in canvas.widgets] == [w.settings for w in exported.widgets]
        assert [w.id for w in canvas.widgets] == [w.id for w in exported.widgets]  # nothing clashed here
        text = receiver.banner.text()
        assert receiver.notice.kind == "info" and "“Docking” imported" in text
        assert f"1 widget needs a package that is not installed ({MISSING_KIND})" in text
        # the widgets run on the robot; the missing one is a placeholder that never subscribes
        for topic in ("/battery", "/lights/state"):
            qtbot.waitUntil(lambda t=topic: sim_thread.topic_subscriber_count(t) == 1, timeout=10_000)
        charge = running(receiver, qtbot, canvas.widgets[0].id).view
        qtbot.waitUntil(lambda: charge.text().startswith("Charge: ") and charge.text() != "Charge: None",
                        timeout=10_000)
        placeholder = receiver.host.hosted[canvas.widgets[2].id].frame.view
        assert placeholder.objectName() == "placeholder" and MISSING_KIND in placeholder.text()
        assert sim_thread.topic_subscriber_count("/gripper") == 0
        # saved at once, the missing widget's settings unchanged
        saved = WorkspaceStore(receiver.layout_path).load()
        assert saved.canvas_named("Docking").widgets[2].settings == MISSING_SETTINGS

        # the same file again: a unique name and fresh widget ids (the first copy holds them now)
        receiver.switch_canvas(0)
        again = receiver.canvas_files.import_from(path)
        assert again is not None and again.name == "Docking (2)" and receiver.controller.canvas is again
        first_ids = {w.id for w in doc.workspace.canvas_named("Docking").widgets}
        assert not first_ids & {w.id for w in again.widgets} and len({w.id for w in again.widgets}) == 3
        assert [c.name for c in doc.workspace.canvases] == ["Main", "Docking", "Docking (2)"]
        qtbot.waitUntil(lambda: sim_thread.topic_subscriber_count("/battery") == 1, timeout=10_000)
        running(receiver, qtbot, again.widgets[0].id)

        # undo removes the imported canvas: its widgets leave the robot
        assert doc.undo_label == "add canvas Docking (2)"
        tap(receiver.canvas_buttons["undo"])
        assert [c.name for c in doc.workspace.canvases] == ["Main", "Docking"]
        assert receiver.tabs.count() == 2
        receiver.switch_canvas(0)
        receiver.undo()
        assert [c.name for c in doc.workspace.canvases] == ["Main"] and receiver.tabs.count() == 1
        for topic in ("/battery", "/lights/state"):
            qtbot.waitUntil(lambda t=topic: sim_thread.topic_subscriber_count(t) == 0, timeout=10_000)
        assert [c.name for c in WorkspaceStore(receiver.layout_path).load().canvases] == ["Main"]
    finally:
        receiver.shutdown()


BAD_FILES = {
    "corrupt": (b'{"format": "rcon-canvas", "version": 1, "canvas": {"na', "not valid JSON"),
    "newer": (json.dumps({"format": "rcon-canvas", "version": 99, "canvas": {"id": "c-1", "name": "X"}}).encode(),
              "written by a newer RCON (format version 99"),
    "workspace": (json.dumps({"format": "rcon-workspace", "version": 1, "canvases": []}).encode(),
                  "not an RCON canvas file (format is 'rcon-workspace'"),
    "no-format": (b"[1, 2, 3]", "not an RCON canvas file"),
    "bad-widget": (json.dumps({"format": "rcon-canvas", "version": 1, "canvas": {
        "id": "c-1", "name": "X", "widgets": [{"id": "w-1", "kind": "apptest.probe", "geometry": {"x": "left"}}]}}
    ).encode(), "geometry.x must be a number"),
    "no-name": (json.dumps({"format": "rcon-canvas", "version": 1, "canvas": {"id": "c-1", "name": "x" * 101}}
                           ).encode(), "a canvas name is at most 100 characters"),
}


def test_a_file_that_cannot_be_used_says_why_and_changes_nothing(qtbot, tmp_path):
    window = open_window(qtbot, tmp_path / "config")
    try:
        window.controller.add_canvas("Deck")
        window.switch_canvas(0)
        before = window.layout_path.read_bytes()
        names, undo_label = [c.name for c in window.doc.workspace.canvases], window.doc.undo_label
        cases = {name: (tmp_path / f"{name}.rcon-canvas.json", reason) for name, (_, reason) in BAD_FILES.items()}
        for name, (content, _) in BAD_FILES.items():
            cases[name][0].write_bytes(content)
        cases["missing"] = (tmp_path / "gone.rcon-canvas.json", "no such file")
        cases["folder"] = (tmp_path, "cannot read")
        for name, (path, reason) in cases.items():
            window.notice.dismiss()
            if name == "corrupt":  # through the dialog once, like an operator
                pick(window.canvas_files.import_dialog(), path)
            else:
                assert window.canvas_files.import_from(path) is None, name
            assert window.notice.isVisible() and window.notice.kind == "problem", name
            text = window.banner.text()
            assert text.startswith("⚠ The canvas could not be imported") and reason in text, (name, text)
            assert str(path) in text and text.endswith("Nothing was changed."), name
            assert [c.name for c in window.doc.workspace.canvases] == names, name
            assert window.doc.undo_label == undo_label and window.controller.index == 0, name
            assert window.layout_path.read_bytes() == before, name
    finally:
        window.shutdown()


def test_import_needs_edit_mode_export_does_not(qtbot, tmp_path):
    window = open_window(qtbot, tmp_path / "config")
    try:
        build_docking(window)  # leaves the canvas in Operate mode
        path = window.canvas_files.export_to(tmp_path / "deck.rcon-canvas.json")
        assert path is not None and path.is_file() and window.controller.canvas.locked
        window.canvas_files.dialog = None
        assert window.canvas_files.import_dialog() is None and window.canvas_files.dialog is None  # no dialog
        assert window.notice.kind == "info"
        assert "Switch to Edit mode to import a canvas" in window.banner.text()
        assert window.canvas_files.import_from(path) is None  # the same refusal when called directly
        assert len(window.doc.workspace.canvases) == 2
        tap_notice(qtbot, window, "Switch to Edit mode")  # unlocks, then imports what was picked
        assert not window.doc.workspace.canvas_named("Docking").locked
        assert [c.name for c in window.doc.workspace.canvases] == ["Main", "Docking", "Docking (2)"]
        # the menu's own path: switching to Edit mode opens the dialog
        window.controller.set_locked(True)
        window.canvas_actions["import"].trigger()
        assert window.canvas_files.dialog is None
        tap_notice(qtbot, window, "Switch to Edit mode")
        dialog = window.canvas_files.dialog
        assert dialog is not None and dialog.objectName() == "importDialog" and dialog.isVisible()
        dialog.reject()
        assert len(window.doc.workspace.canvases) == 3  # cancelled: nothing imported
        # a place that cannot be written: the notice says so, nothing else happens
        blocker = tmp_path / "a-file"
        blocker.write_text("x")
        assert window.canvas_files.export_to(blocker / "deck.rcon-canvas.json") is None
        assert window.notice.kind == "problem" and "could not be exported" in window.banner.text()
    finally:
        window.shutdown()


def test_names_of_files_and_canvases(qtbot, tmp_path):
    assert file_name_for("Docking") == "Docking.rcon-canvas.json"
    assert file_name_for('Dock/Undock: "A"?') == "Dock_Undock_ _A.rcon-canvas.json"
    assert file_name_for("..") == "canvas.rcon-canvas.json"
    assert name_from_file("/x/Docking.rcon-canvas.json") == "Docking"
    assert name_from_file("deck.JSON") == "deck"
    # a canvas without a name is named after its file
    path = tmp_path / "Harbour.rcon-canvas.json"
    path.write_text(json.dumps({"format": "rcon-canvas", "version": 1, "canvas": {"id": "", "name": "  "}}))
    window = open_window(qtbot, tmp_path / "config")
    try:
        canvas = window.canvas_files.import_from(path)
        assert canvas is not None and canvas.name == "Harbour" and canvas.id
        # geometry off the grid or off the canvas is put on it (what is saved is always on the grid)
        odd = tmp_path / "odd.rcon-canvas.json"
        odd.write_text(json.dumps({"format": "rcon-canvas", "version": 1, "canvas": {
            "id": "c-x", "name": "Odd", "widgets": [{"id": "w-x", "kind": "apptest.probe",
                                                     "geometry": {"x": -50, "y": 23, "w": 201, "h": 90}}]}}))
        odd_canvas = window.canvas_files.import_from(odd)
        assert odd_canvas is not None
        g = odd_canvas.widgets[0].geometry
        assert (g.x, g.y) == (0, 16) and g.w % 16 == 0 and g.h % 16 == 0
    finally:
        window.shutdown()
