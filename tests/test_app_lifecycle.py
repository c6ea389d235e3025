"""The app's life across starts: the demo layout, unreadable layout files, quitting, the URL history.

Driven like a person: taps, key presses, real signals to a real ``rcon --demo`` process.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys

import pytest
from app_helpers import open_window as open_app_window
from app_helpers import tap, tap_item
from qtpy import QtCore
from qtpy.QtTest import QTest
from test_app_window import make_plugins

from rcon_core.app.config import AppConfig
from rcon_core.app.main_window import MainWindow
from rcon_core.bridge import ConnectionState
from rcon_core.canvas import Binding, Canvas, Geometry, WidgetInstance, Workspace, new_id
from rcon_core.testing import qt_flushed, until_sync

pytestmark = pytest.mark.usefixtures("qapp")

#: a layout from an early development build: no canvas ids, "rect" instead of geometry, same version
EARLY_BUILD = json.dumps({"format": "rcon-workspace", "version": 1, "canvases": [
    {"name": "Main", "widgets": [{"kind": "apptest.probe", "rect": [16, 16, 160, 80]}]}]}).encode()


def demo_layout() -> Workspace:
    """A stand-in for the demo layout (the real one needs the widget packages): one locked canvas."""
    canvas = Canvas(new_id("c"), "Demo", locked=True)
    canvas.widgets.append(WidgetInstance(new_id("w"), "apptest.probe",
                                         Binding("/battery", "sensor_msgs/BatteryState", "subscribe",
                                                 ("percentage",)),
                                         Geometry(32, 32, 192, 112), {"caption": "Charge"}, "Charge"))
    return Workspace([canvas], canvas.id)


def open_window(qtbot, config_dir, layout=None, demo=None) -> MainWindow:
    """The probe plugin's window, 1280x800 (a tablet; the offscreen screen is 800x800), on ``layout``."""
    return open_app_window(qtbot, config_dir, make_plugins(), layout=layout, demo=demo)


def menu_action(window: MainWindow, name: str) -> None:
    window.canvas_actions[name].trigger()


def answer(window: MainWindow, qtbot, yes: bool) -> None:
    box = window.confirm_dialog
    qtbot.waitUntil(box.isVisible)
    name = "confirmYes" if yes else "confirmCancel"
    [button] = [b for b in box.buttons() if b.objectName() == name]
    assert button.height() >= 48  # a touch target
    tap(button)
    qtbot.waitUntil(lambda: not box.isVisible())


# ------------------------------------------------------------------------------------------ the demo
def test_the_demo_layout_is_built_once_edits_persist_and_reset_asks_first(qtbot, tmp_path):
    path = tmp_path / "demo-workspace.json"
    built: list[int] = []

    def demo() -> Workspace:
        built.append(1)
        return demo_layout()

    first = open_window(qtbot, tmp_path, path, demo)
    assert built == [1] and path.exists()  # first start: built and saved at once
    [canvas] = first.controller.workspace.canvases
    tap(first.edit_button)  # unlock, then move the widget
    [frame] = first.controller.surface.frames.values()
    shield = frame.shield
    start = QtCore.QPoint(frame.width() // 2, frame.height() // 2)
    QTest.mousePress(shield, QtCore.Qt.MouseButton.LeftButton, QtCore.Qt.KeyboardModifier.NoModifier, start)
    for i in range(1, 6):
        QTest.mouseMove(shield, start + QtCore.QPoint(40 * i, 30 * i))
    QTest.mouseRelease(shield, QtCore.Qt.MouseButton.LeftButton, QtCore.Qt.KeyboardModifier.NoModifier,
                       start + QtCore.QPoint(200, 150))
    moved = canvas.widgets[0].geometry
    assert (moved.x, moved.y) != (32, 32)
    first.close()

    again = open_window(qtbot, tmp_path, path, demo)
    try:
        assert built == [1]  # not rebuilt: the edit is still there
        g = again.controller.canvas.widgets[0].geometry
        assert (g.x, g.y) == (moved.x, moved.y) and not again.controller.canvas.locked
        # the canvas menu resets it, after asking
        menu_action(again, "reset_demo")
        answer(again, qtbot, yes=False)
        assert built == [1]
        menu_action(again, "reset_demo")
        answer(again, qtbot, yes=True)
        assert built == [1, 1]
        g = again.controller.canvas.widgets[0].geometry
        assert (g.x, g.y) == (32, 32) and again.controller.canvas.locked
    finally:
        again.close()
    saved = json.loads(path.read_text())
    assert saved["canvases"][0]["widgets"][0]["geometry"]["x"] == 32
    # no reset action outside the demo
    plain = open_window(qtbot, tmp_path / "plain")
    try:
        assert "reset_demo" not in plain.canvas_actions
    finally:
        plain.close()


def test_an_unreadable_demo_layout_is_moved_aside_once_and_rebuilt(qtbot, tmp_path):
    path = tmp_path / "demo-workspace.json"
    path.write_bytes(EARLY_BUILD)
    window = open_window(qtbot, tmp_path, path, demo_layout)
    try:
        assert window.notice.isVisible() and window.notice.kind == "info"  # told, not blocked
        assert "fresh demo layout" in window.banner.text()
        assert [c.name for c in window.controller.workspace.canvases] == ["Demo"]
        [kept] = tmp_path.glob("demo-workspace.json.unreadable-*")
        assert kept.read_bytes() == EARLY_BUILD
        assert json.loads(path.read_text())["canvases"][0]["name"] == "Demo"  # saved normally
        tap(window.notice.dismiss_button)
        assert not window.notice.isVisible()
    finally:
        window.close()
    again = open_window(qtbot, tmp_path, path, demo_layout)
    try:
        assert not again.notice.isVisible()
        assert len(list(tmp_path.glob("demo-workspace.json.unreadable-*"))) == 1
    finally:
        again.close()


# ------------------------------------------------------------------------- an unreadable layout file
def test_an_unreadable_layout_offers_a_new_layout_and_keeps_one_copy(qtbot, tmp_path):
    path = tmp_path / "site.json"
    path.write_bytes(EARLY_BUILD)
    for _start in range(2):  # each start reports it, but only one copy is kept
        window = open_window(qtbot, tmp_path, path)
        assert window.notice.isVisible() and window.notice.kind == "problem"
        assert "will not be overwritten" in window.banner.text()
        window.close()
        assert path.read_bytes() == EARLY_BUILD
    [copy] = tmp_path.glob("site.json.unreadable-*")
    window = open_window(qtbot, tmp_path, path)
    try:
        tap(window.notice.buttons["Start a new layout"])
        assert not path.exists() or json.loads(path.read_text())["format"] == "rcon-workspace"
        assert list(tmp_path.glob("site.json.unreadable-*")) == [copy] and copy.read_bytes() == EARLY_BUILD
        assert window.notice.kind == "info" and str(copy) in window.banner.text()
        window.controller.add_canvas("Scratch")  # saved from now on
        assert [c["name"] for c in json.loads(path.read_text())["canvases"]] == ["Main", "Scratch"]
    finally:
        window.close()
    again = open_window(qtbot, tmp_path, path)
    try:
        assert not again.notice.isVisible()
        assert [c.name for c in again.controller.workspace.canvases] == ["Main", "Scratch"]
    finally:
        again.close()


# ----------------------------------------------------------------------------- adding in Operate mode
def test_picking_a_widget_in_operate_mode_says_why_and_offers_edit_mode(qtbot, tmp_path):
    window = open_window(qtbot, tmp_path)
    try:
        tap(window.lock_button)
        assert window.controller.canvas.locked
        window.side.setCurrentWidget(window.palette_panel)
        tree = window.palette_panel.tree
        tap_item(tree, tree.indexFromItem(window.palette_panel.item("apptest.probe")))
        qtbot.waitUntil(window.notice.isVisible)  # never a silent no-op: the notice says why
        qt_flushed(qtbot)
        assert not window.add_panel.isVisible()
        assert "Switch to Edit mode to add widgets" in window.banner.text()
        tap(window.notice.buttons["Switch to Edit mode"])
        assert not window.controller.canvas.locked and window.edit_button.isChecked()
        qtbot.waitUntil(window.add_panel.isVisible)
        qt_flushed(qtbot)  # the panel stays open (it used to close itself at once)
        assert window.add_panel.isVisible() and not window.notice.isVisible()
        assert window.add_panel.stack.currentWidget() is window.add_panel.settings_page
    finally:
        window.close()


# ------------------------------------------------------------------------------------------ quitting
def test_ctrl_q_closes_the_window_and_saves(qtbot, tmp_path):
    window = open_window(qtbot, tmp_path)
    window.controller.add_canvas("Kept")
    window.activateWindow()
    QTest.qWaitForWindowActive(window)
    (tmp_path / "workspace.json").unlink()
    QTest.keyClick(window, QtCore.Qt.Key.Key_Q, QtCore.Qt.KeyboardModifier.ControlModifier)
    qtbot.waitUntil(lambda: not window.isVisible())
    saved = json.loads((tmp_path / "workspace.json").read_text())
    assert [c["name"] for c in saved["canvases"]] == ["Main", "Kept"]


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_rcon_demo_exits_cleanly_on_a_signal_and_saves(tmp_path, sig):
    pytest.importorskip("rcon_widgets_std", reason="the demo layout wants the widget packages")
    env = dict(os.environ, RCON_CONFIG_DIR=str(tmp_path), QT_QPA_PLATFORM="offscreen")
    proc = subprocess.Popen([sys.executable, "-m", "rcon_core.cli.main", "--demo"], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    layout = tmp_path / "demo-workspace.json"
    try:

        def started() -> bool:  # the layout is written when the window is built: the signal handler is in place
            assert proc.poll() is None, proc.stdout.read().decode()
            return layout.exists()

        until_sync(started, 60, what="rcon --demo to start")
        layout.unlink()  # the shutdown must write it again
        proc.send_signal(sig)
        rc = proc.wait(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    output = proc.stdout.read().decode()
    assert rc == 0, output
    assert json.loads(layout.read_text())["format"] == "rcon-workspace"
    # the embedded robot's URL (its port is gone now) is not in the history for plain `rcon`
    app = tmp_path / "app.json"
    history = json.loads(app.read_text()).get("url_history", []) if app.exists() else []
    assert not [u for u in history if u.startswith("ws://127.0.0.1:")], history


# --------------------------------------------------------------------------------------- URL history
def test_a_history_left_by_earlier_demo_runs_never_auto_connects_to_a_dead_port(tmp_path):
    (tmp_path / "app.json").write_text(json.dumps({"url_history": [
        "ws://127.0.0.1:41873", "ws://127.0.0.1:39211", "ws://boat.local:9090", "ws://127.0.0.1:9090"]}))
    config = AppConfig(tmp_path)
    assert config.last_url == "ws://boat.local:9090"
    assert config.url_history == ["ws://boat.local:9090", "ws://127.0.0.1:9090"]
    # what the operator connects to from now on is kept, whatever its port
    config.remember_url("ws://127.0.0.1:45000")
    assert AppConfig(tmp_path).last_url == "ws://127.0.0.1:45000"


# ----------------------------------------------------------------------------------------- the URL
def type_url(window: MainWindow, text: str) -> None:
    line = window.connection.url.lineEdit()
    line.setFocus()
    line.selectAll()
    QTest.keyClicks(line, text)
    QTest.keyClick(line, QtCore.Qt.Key.Key_Return)


def test_a_url_without_scheme_is_ws_and_a_rejected_one_never_hides_the_active_url(qtbot, tmp_path):
    from rcon_core.sim.server import SimServer

    with SimServer.in_thread(port=0) as robot:
        window = open_window(qtbot, tmp_path)
        try:
            type_url(window, f"127.0.0.1:{robot.port}")  # no scheme: ws:// is meant
            assert window.link.url == f"ws://127.0.0.1:{robot.port}"
            qtbot.waitUntil(lambda: window.connection.state is ConnectionState.CONNECTED, timeout=10_000)
            assert window.connection.url.currentText() == f"ws://127.0.0.1:{robot.port}"
            button = window.connection.connect_button
            assert button.text() == "Disconnect"
            fm = button.fontMetrics()
            assert button.width() >= fm.horizontalAdvance("Disconnect") + 20  # the label is not cut
            type_url(window, "http://robot:9090")  # rejected: the field goes back to the URL in use
            assert window.link.url == f"ws://127.0.0.1:{robot.port}" and window.link.client is not None
            assert window.connection.url.currentText() == f"ws://127.0.0.1:{robot.port}"
            message = window.connection.message.text()
            assert "ws://" in message and f"still connected to ws://127.0.0.1:{robot.port}" in message
        finally:
            window.close()


# ---------------------------------------------------------------------------------------- the palette
def test_the_palette_groups_by_category_and_searches_what_a_widget_does(qtbot):
    pytest.importorskip("rcon_widgets_sensors", reason="needs the widget packages")
    from rcon_core.app.main import load_plugins
    from rcon_core.app.palette_panel import KIND_ROLE, PalettePanel

    plugins = load_plugins()
    panel = PalettePanel()
    qtbot.addWidget(panel)
    panel.set_specs(plugins.widgets())
    panel.show()
    groups = list(panel.groups)
    assert "Controls" in groups and not any(g.startswith("rcon-widgets") for g in groups)
    teleop = panel.item("sensors.teleop")
    assert teleop.parent().text(0) == plugins.widget("sensors.teleop").category
    assert "rcon-widgets-sensors" in teleop.toolTip(0) and "rcon-widgets-sensors" in teleop.text(0)

    def shown() -> set[str]:  # the kinds a user sees in the tree (the groups' visible children)
        return {item.data(0, KIND_ROLE) for group in panel.groups.values() if not group.isHidden()
                for item in (group.child(i) for i in range(group.childCount())) if not item.isHidden()}

    QTest.keyClicks(panel.filter, "drive")  # in the teleop's description, not in its title
    assert "sensors.teleop" in shown()
    hidden_groups = [g for g, item in panel.groups.items() if item.isHidden()]
    assert hidden_groups and all(not any(panel.item(k).parent() is panel.groups[g] for k in shown())
                                 for g in hidden_groups)
    panel.filter.clear()
    QTest.keyClicks(panel.filter, "NavSatFix")  # an accepted type
    assert "map.gps" in shown()
    panel.filter.clear()
    QTest.keyClicks(panel.filter, "no such widget at all")
    assert not shown() and panel.no_match.isVisible()
    assert all(item.isHidden() for item in panel.groups.values())
