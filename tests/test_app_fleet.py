"""Several robots in the real window, offscreen, against two and three sims on free ports: the robot chips,
the side panel's robot, widgets bound per robot (a mixed canvas marks them), one robot dropping (LINK DOWN
on its widgets only), re-targeting a canvas, a one-robot layout of format version 1, the map of every robot.

With ``RCON_FLEET_SHOTS=DIR`` the mixed canvas and the chips are saved as PNGs there (to look at them)."""

from __future__ import annotations

import asyncio
import json
import os
from pathlib import Path

import pytest
from app_helpers import TIMEOUT_MS, choose_kind, entry_point_plugins, open_window, tap, tap_topic
from qtpy import QtGui, QtWidgets

from rcon_core.bridge import ConnectionState
from rcon_core.canvas import Binding, Document, Geometry, Workspace, WorkspaceStore
from rcon_core.canvas.robots import Robot, robot_colour
from rcon_core.plugins import Role

pytestmark = pytest.mark.usefixtures("qapp")

BATTERY = ("/battery", "sensor_msgs/BatteryState", "subscribe", ("percentage",))
LABEL = {"decimals": 0, "units": "%", "scale": 100.0}


def shot(window: QtWidgets.QWidget, name: str) -> None:
    out = os.environ.get("RCON_FLEET_SHOTS")
    if out:
        QtWidgets.QApplication.processEvents()
        Path(out).mkdir(parents=True, exist_ok=True)
        window.grab().save(str(Path(out) / f"{name}.png"))


def fleet_layout(config_dir: Path, robots: list[Robot], widgets) -> Workspace:
    """A workspace file at the window's default place: ``widgets`` = (title, kind, binding, settings, rect)."""
    ws = Workspace.new("Fleet")
    ws.robots = robots
    doc = Document(ws)
    for title, kind, binding, settings, rect in widgets:
        w = doc.add_widget(doc.current.id, kind, binding, Geometry(*rect), settings)
        doc.reconfigure_widget(w.id, title=title)
    config_dir.mkdir(parents=True, exist_ok=True)
    WorkspaceStore(config_dir / "workspace.json").save(ws)
    return ws


def stop_sim(sim) -> None:
    asyncio.run_coroutine_threadsafe(sim.stop(), sim.loop).result(10)


def shown(window, wid: str) -> str:
    view = window.host.hosted[wid].view
    return view.value.text() if view is not None else ""


def frame_of(window, wid: str):
    return window.controller.surface.frames[wid]


@pytest.fixture
def two(sim_fleet_threads):
    pytest.importorskip("rcon_widgets_std")
    alpha, bravo = sim_fleet_threads(2)
    alpha.robot.battery_charge, bravo.robot.battery_charge = 4.0, 16.0  # 20 % and 80 %
    bravo.run_sync(lambda: bravo.advertise_internal("/bravo_only", "std_msgs/String", "/test"))
    return alpha, bravo


def open_fleet(qtbot, tmp_path, alpha, bravo, widgets):
    robots = [Robot("r-1", "Alpha"), Robot("r-2", "Bravo", url=bravo.url)]
    ws = fleet_layout(tmp_path / "config", robots, widgets)
    win = open_window(qtbot, tmp_path / "config", entry_point_plugins(), url=alpha.url, size=(1280, 800),
                      wait_connected=True)
    chips = win.fleet_ui.chips
    qtbot.waitUntil(lambda: chips.chips["r-2"].state is ConnectionState.CONNECTED, timeout=TIMEOUT_MS)
    return win, ws


def test_chips_pick_the_side_robot_and_a_new_widget_is_bound_to_it(qtbot, tmp_path, two):
    alpha, bravo = two
    widgets = [("Battery", "std.label", Binding(*BATTERY), LABEL, (16, 16, 240, 112)),
               ("Battery", "std.label", Binding(*BATTERY, robot="r-2"), LABEL, (272, 16, 240, 112))]
    win, ws = open_fleet(qtbot, tmp_path, alpha, bravo, widgets)
    try:
        a_id, b_id = (w.id for w in win.controller.canvas.widgets)
        chips = win.fleet_ui.chips
        assert chips.isVisible() and list(chips.chips) == ["r-1", "r-2"]
        qtbot.waitUntil(lambda: chips.chips["r-1"].state is ConnectionState.CONNECTED, timeout=TIMEOUT_MS)
        assert chips.chips["r-1"].text().startswith("Alpha  CONNECTED")
        qtbot.waitUntil(lambda: chips.chips["r-2"].text().endswith("ms"), timeout=TIMEOUT_MS)  # its round trip
        # a mixed canvas: each frame says its robot (name in the title, the robot's colour on its edge)
        qtbot.waitUntil(lambda: frame_of(win, b_id).title.full_title == "Bravo · Battery", timeout=TIMEOUT_MS)
        assert frame_of(win, a_id).title.full_title == "Alpha · Battery"
        assert robot_colour(ws.robots, "r-2") in frame_of(win, b_id).styleSheet()
        qtbot.waitUntil(lambda: shown(win, a_id).startswith("20") and shown(win, b_id).startswith("80"),
                        timeout=TIMEOUT_MS)  # each its own robot's battery
        shot(win, "mixed-canvas")
        shot(chips, "chips")
        # the side panel's topic rates count the listed robot's widgets only
        assert set(win.host.topic_counts("r-2")) == {"/battery"} and win.host.topic_counts("r-3") == {}

        # the side panel shows Alpha's topics; a tap on Bravo's chip shows Bravo's
        assert win.fleet_ui.side_robot == "r-1" and chips.chips["r-1"].isChecked()
        picker = win.fleet_ui.pickers[0]
        assert picker.isVisible() and picker.combo.currentText() == "Alpha"
        qtbot.waitUntil(lambda: win.topics.item("/battery") is not None, timeout=TIMEOUT_MS)
        assert win.topics.item("/bravo_only") is None
        tap(chips.chips["r-2"])
        assert win.fleet_ui.side_robot == "r-2" and chips.chips["r-2"].isChecked()
        assert not chips.chips["r-1"].isChecked() and picker.combo.currentText() == "Bravo"
        qtbot.waitUntil(lambda: win.topics.item("/bravo_only") is not None, timeout=TIMEOUT_MS)

        # adding a widget: the topic comes from Bravo, the widget is bound to Bravo
        tap_topic(win, "/battery")
        panel = choose_kind(win, Role.SUBSCRIBE, "std.label")
        tap(panel.place_button)
        added = win.controller.canvas.widgets[-1]
        assert added.binding.robot == "r-2" and added.binding.name == "/battery"
        # Bravo's 80 %: a Label on the battery's 0..1 fraction shows it in percent (issue 21.12)
        qtbot.waitUntil(lambda: shown(win, added.id) == "80 %", timeout=TIMEOUT_MS)

        # the picker in the side list picks back the first robot (a new widget then names no robot)
        picker.combo.activated.emit(picker.combo.findData("r-1"))
        assert win.fleet_ui.side_robot == "r-1" and chips.chips["r-1"].isChecked()
        qtbot.waitUntil(lambda: win.topics.item("/bravo_only") is None, timeout=TIMEOUT_MS)
        tap_topic(win, "/battery")
        panel = choose_kind(win, Role.SUBSCRIBE, "std.label")
        tap(panel.place_button)
        assert win.controller.canvas.widgets[-1].binding.robot == ""
    finally:
        win.shutdown()


def test_one_robot_dropping_shows_link_down_only_on_its_widgets(qtbot, tmp_path, two):
    alpha, bravo = two
    widgets = [("Battery", "std.label", Binding(*BATTERY), LABEL, (16, 16, 240, 112)),
               ("Battery", "std.label", Binding(*BATTERY, robot="r-2"), LABEL, (272, 16, 240, 112))]
    win, _ws = open_fleet(qtbot, tmp_path, alpha, bravo, widgets)
    try:
        a_id, b_id = (w.id for w in win.controller.canvas.widgets)
        qtbot.waitUntil(lambda: shown(win, a_id) not in ("", "–") and shown(win, b_id) not in ("", "–"),
                        timeout=TIMEOUT_MS)
        stop_sim(bravo)  # Bravo's link drops
        chip = win.fleet_ui.chips.chips["r-2"]
        qtbot.waitUntil(lambda: chip.state in (ConnectionState.RECONNECTING, ConnectionState.CLOSED), timeout=TIMEOUT_MS)
        b_badge = frame_of(win, b_id).badge
        qtbot.waitUntil(lambda: b_badge.isVisible() and b_badge.status == "LINK DOWN", timeout=TIMEOUT_MS)
        assert "RECONNECTING" in chip.text() or "DISCONNECTED" in chip.text()
        qtbot.waitUntil(lambda: "connection refused" in chip.toolTip(), timeout=TIMEOUT_MS)  # why, in words
        # Alpha's widget stays live: no badge, its value keeps coming
        model = win.host.hosted[a_id].model
        count = model.state.count
        qtbot.waitUntil(lambda: model.state.count > count + 2, timeout=TIMEOUT_MS)
        assert not frame_of(win, a_id).badge.isVisible()
        assert win.connection.state is ConnectionState.CONNECTED and win.fleet_ui.chips.chips["r-1"].state is ConnectionState.CONNECTED
        assert shown(win, b_id) not in ("", "–")  # Bravo's last value is kept
        shot(win, "bravo-down")
    finally:
        win.shutdown()


def test_a_canvas_is_re_targeted_to_another_robot_in_one_undo_step(qtbot, tmp_path, two):
    alpha, bravo = two
    widgets = [("Battery", "std.label", Binding(*BATTERY), LABEL, (16, 16, 240, 112)),
               ("Speed", "std.slider", Binding("/speed_limit", "std_msgs/Float64", "publish", ("data",)),
                {"minimum": 0.0, "maximum": 2.0}, (16, 144, 320, 112))]
    win, _ws = open_fleet(qtbot, tmp_path, alpha, bravo, widgets)
    try:
        original = win.controller.canvas
        assert not win.fleet_ui.chips.chips["r-2"].isChecked()
        # Bravo's catalogue holds both names: else the copy waits for the operator's answer (a name missing)
        qtbot.waitUntil(lambda: {"/battery", "/speed_limit"} <= {
            n for n, _t in (win.fleet_ui.catalogs.get("r-2") or {}).get("topics", [])}, timeout=TIMEOUT_MS)
        action = win.fleet_ui.retarget_menu.findChild(QtGui.QAction, "retarget-r-2")
        action.trigger()  # Canvas ▾ → Duplicate for robot → Bravo
        copy = win.controller.canvas
        assert copy is not original and copy.name == "Fleet · Bravo" and win.tabs.count() == 2
        assert [w.binding.robot for w in copy.widgets] == ["r-2", "r-2"]
        assert [w.binding.robot for w in original.widgets] == ["", ""]
        label = copy.widgets[0].id
        qtbot.waitUntil(lambda: shown(win, label).startswith("80"), timeout=TIMEOUT_MS)  # Bravo's battery
        # a canvas of one robot (even not the first) is not marked
        assert frame_of(win, label).title.full_title == "Battery"
        tap(win.canvas_buttons["undo"])  # one step takes the copy away
        assert [c.name for c in win.controller.workspace.canvases] == ["Fleet"]
        assert win.controller.canvas is original
        before = win.connection.message.text()
        win.fleet_ui.retarget_current("r-9")  # no such robot: refused on the notice bar, nothing changes
        assert win.notice.kind == "problem" and "r-9" in win.banner.text(), win.banner.text()
        assert win.connection.message.text() == before
        assert [c.name for c in win.controller.workspace.canvases] == ["Fleet"]
    finally:
        win.shutdown()


def test_robots_are_added_in_the_robots_dialog_and_connect(qtbot, tmp_path, two):
    alpha, bravo = two
    fleet_layout(tmp_path / "config", [Robot("r-1", "Alpha")],
                 [("Battery", "std.label", Binding(*BATTERY), LABEL, (16, 16, 240, 112))])
    win = open_window(qtbot, tmp_path / "config", entry_point_plugins(), url=alpha.url, wait_connected=True)
    try:
        ui = win.fleet_ui
        assert not ui.chips.isVisible()
        win.canvas_actions["robots"].trigger()  # Canvas ▾ → Robots…
        dialog = ui.robots_dialog
        assert dialog.isVisible() and dialog.table.rowCount() == 1
        tap(dialog.findChild(QtWidgets.QPushButton, "addRobot"))
        assert dialog.table.rowCount() == 2
        dialog.set_row(1, name="Bravo", url="127.0.0.1:not-a-port")
        ok = dialog.findChild(QtWidgets.QDialogButtonBox).button(QtWidgets.QDialogButtonBox.StandardButton.Ok)
        tap(ok)  # a URL it cannot use: refused with the reason, nothing changed
        assert dialog.isVisible() and "port" in dialog.problem.text()
        assert len(win.controller.workspace.robots) == 1
        dialog.table.setCurrentCell(0, 0)
        tap(dialog.findChild(QtWidgets.QPushButton, "removeRobot"))  # the first robot stays
        assert dialog.table.rowCount() == 2 and "first robot" in dialog.problem.text()
        dialog.set_row(1, url=alpha.url)  # a slip: Alpha's URL
        tap(ok)
        robots = win.controller.workspace.robots
        assert [(r.name, r.url) for r in robots] == [("Alpha", ""), ("Bravo", alpha.url)]
        rid = robots[1].id
        qtbot.waitUntil(lambda: ui.chips.isVisible() and rid in ui.chips.chips, timeout=TIMEOUT_MS)
        qtbot.waitUntil(lambda: ui.chips.chips[rid].state is ConnectionState.CONNECTED, timeout=TIMEOUT_MS)
        assert ui.links.link(rid).url == alpha.url and "view only" not in ui.chips.chips[rid].text()
        win.canvas_actions["robots"].trigger()  # Bravo is only watched: its chip says so
        ui.robots_dialog.set_row(1, view_only=True)
        ui.robots_dialog.accept()
        qtbot.waitUntil(lambda: ui.chips.chips[rid].text().startswith("Bravo · view only"), timeout=TIMEOUT_MS)
        assert win.controller.workspace.robots[1].view_only
        tap(win.canvas_buttons["undo"])
        qtbot.waitUntil(lambda: "view only" not in ui.chips.chips[rid].text(), timeout=TIMEOUT_MS)
        win.canvas_actions["robots"].trigger()  # corrected: Bravo connects again, to its own URL
        ui.robots_dialog.set_row(1, url=bravo.url)
        ui.robots_dialog.accept()
        qtbot.waitUntil(lambda: ui.links.link(rid).url == bravo.url, timeout=TIMEOUT_MS)
        qtbot.waitUntil(lambda: ui.chips.chips[rid].state is ConnectionState.CONNECTED, timeout=TIMEOUT_MS)
        qtbot.waitUntil(lambda: len(bravo.connections) == 1, timeout=TIMEOUT_MS)
        tap(win.canvas_buttons["undo"])  # back to Alpha's URL
        qtbot.waitUntil(lambda: len(bravo.connections) == 0, timeout=TIMEOUT_MS)
        tap(win.canvas_buttons["redo"])
        qtbot.waitUntil(lambda: len(bravo.connections) == 1, timeout=TIMEOUT_MS)
        tap(win.canvas_buttons["undo"])
        tap(win.canvas_buttons["undo"])  # one step more: Bravo is gone again, its link closed
        assert [r.name for r in win.controller.workspace.robots] == ["Alpha"]
        qtbot.waitUntil(lambda: not ui.chips.isVisible(), timeout=TIMEOUT_MS)
        assert rid not in ui.links.ids
        qtbot.waitUntil(lambda: len(bravo.connections) == 0, timeout=TIMEOUT_MS)  # the link was closed
    finally:
        win.shutdown()


# a one-robot layout of format version 1 (as earlier builds wrote it)
VERSION_1 = {"format": "rcon-workspace", "version": 1, "current": "c-old", "canvases": [
    {"id": "c-old", "name": "Deck", "locked": False, "widgets": [
        {"id": "w-batt", "kind": "std.label", "title": "Battery",
         "binding": {"name": "/battery", "type": "sensor_msgs/BatteryState", "role": "subscribe",
                     "field_paths": ["percentage"]},
         "geometry": {"x": 16.0, "y": 16.0, "w": 240.0, "h": 112.0}, "settings": LABEL}]}],
    "plugin_settings": {}}


def test_a_one_robot_layout_of_version_1_opens_as_the_first_robot(qtbot, tmp_path, sim_thread):
    pytest.importorskip("rcon_widgets_std")
    config = tmp_path / "config"
    config.mkdir()
    path = config / "workspace.json"
    path.write_text(json.dumps(VERSION_1))
    win = open_window(qtbot, config, entry_point_plugins(), url=sim_thread.url, wait_connected=True)
    try:
        ws = win.controller.workspace
        assert [(r.id, r.name, r.url) for r in ws.robots] == [("r-1", "Robot", "")]
        assert not win.fleet_ui.chips.isVisible() and not win.fleet_ui.pickers[0].isVisible()
        assert not win.fleet_ui.retarget_menu.isEnabled()  # one robot: nothing to re-target to
        qtbot.waitUntil(lambda: shown(win, "w-batt") not in ("", "–"), timeout=TIMEOUT_MS)
        assert frame_of(win, "w-batt").title.full_title == "Battery"  # one robot: no mark
        win.controller.saver.flush()
        data = json.loads(path.read_text())
        assert data["version"] == 2 and data["robots"][0]["id"] == "r-1"
        assert data["canvases"][0]["widgets"][0]["binding"]["robot"] == ""
    finally:
        win.shutdown()


def test_three_robots_one_map_shows_every_fix(qtbot, tmp_path, sim_fleet_threads):
    pytest.importorskip("rcon_widgets_map")
    sims = sim_fleet_threads(3)
    for i, sim in enumerate(sims):
        sim.robot.x, sim.robot.y = 120.0 * i, 60.0 * i
    robots = [Robot("r-1", "Alpha"), Robot("r-2", "Bravo", url=sims[1].url),
              Robot("r-3", "Charlie", url=sims[2].url)]
    fix = Binding("/gps/fix", "sensor_msgs/NavSatFix", "subscribe")
    widgets = [("GPS", "map.gps", fix, {"every_robot": True, "goal_topic": "", "zoom": 16.0}, (16, 16, 560, 420)),
               ("Battery", "std.label", Binding(*BATTERY, robot="r-3"), LABEL, (592, 16, 240, 112))]
    fleet_layout(tmp_path / "config", robots, widgets)
    win = open_window(qtbot, tmp_path / "config", entry_point_plugins(), url=sims[0].url, wait_connected=True)
    try:
        chips = win.fleet_ui.chips.chips
        qtbot.waitUntil(lambda: all(c.state is ConnectionState.CONNECTED for c in chips.values()), timeout=TIMEOUT_MS)
        map_id = win.controller.canvas.widgets[0].id

        def labels():
            model = win.host.hosted[map_id].model
            value = model.state.value if model is not None else None
            return [t.label for t in value.tracks if t.has_position] if value is not None else []

        qtbot.waitUntil(lambda: labels() == ["Alpha", "Bravo", "Charlie"], timeout=TIMEOUT_MS)
        shot(win, "fleet-map")
    finally:
        win.shutdown()


def test_the_side_robot_decides_the_actions_and_parameters_listed(qtbot, tmp_path):
    """A ROS 1 boat and a ROS 2 boat: the Actions list and the Parameters tab follow the picked chip."""
    pytest.importorskip("rcon_widgets_std")
    from rcon_core.sim import SimServer
    from rcon_core.testing import TEST_RATE_SCALE

    with SimServer.in_thread(port=0, rate_scale=TEST_RATE_SCALE) as alpha, \
            SimServer.in_thread(port=0, rate_scale=TEST_RATE_SCALE, ros2=True) as bravo:
        robots = [Robot("r-1", "Alpha"), Robot("r-2", "Bravo", url=bravo.url)]
        fleet_layout(tmp_path / "config", robots, [])
        win = open_window(qtbot, tmp_path / "config", entry_point_plugins(), url=alpha.url, wait_connected=True)
        try:
            ui = win.fleet_ui
            qtbot.waitUntil(lambda: ui.chips.chips["r-2"].state is ConnectionState.CONNECTED, timeout=TIMEOUT_MS)
            qtbot.waitUntil(lambda: win.topics.item("/battery") is not None, timeout=TIMEOUT_MS)
            assert win.actions_list.item("/fibonacci") is None  # Alpha (ROS 1) has no actions
            assert win.params_panel.link is win.link
            tap(ui.chips.chips["r-2"])
            qtbot.waitUntil(lambda: win.actions_list.item("/fibonacci") is not None, timeout=TIMEOUT_MS)
            assert ui.pickers[2].combo.currentText() == "Bravo"  # the Actions list's picker too
            panel = win.params_panel
            assert panel.link is ui.links.link("r-2")
            win.side.setCurrentWidget(panel)  # shown: Bravo's parameters are fetched, by node (ROS 2)
            qtbot.waitUntil(lambda: panel.item("/kingfisher:max_speed") is not None and not panel.busy,
                            timeout=TIMEOUT_MS)
            tap(ui.chips.chips["r-1"])
            qtbot.waitUntil(lambda: win.actions_list.item("/fibonacci") is None, timeout=TIMEOUT_MS)
            assert panel.link is win.link
            qtbot.waitUntil(lambda: panel.item("/kingfisher/max_speed") is not None and not panel.busy,
                            timeout=TIMEOUT_MS)  # Alpha's, by namespace (ROS 1)
        finally:
            win.shutdown()


def test_rcon_layout_opens_a_link_to_every_robot_at_its_url(qtbot, tmp_path, sim_fleet_threads, monkeypatch):
    """`rcon --layout FILE` with two robots that have URLs: the first connects through the connection bar
    (its URL, not the history's), the second on its own link; neither URL needs typing."""
    import contextlib

    from rcon_core.app.main import open_app
    from rcon_core.cli.main import build_parser

    alpha, bravo = sim_fleet_threads(2)
    monkeypatch.setenv("RCON_CONFIG_DIR", str(tmp_path / "config"))
    layout = tmp_path / "boats.json"
    ws = Workspace.new("Boats")
    ws.robots = [Robot("r-1", "Alpha", url=alpha.url), Robot("r-2", "Bravo", url=bravo.url)]
    WorkspaceStore(layout).save(ws)
    with contextlib.ExitStack() as stack:
        window = open_app(build_parser().parse_args(["--layout", str(layout)]), stack)
        qtbot.addWidget(window)
        try:
            chips = window.fleet_ui.chips.chips
            qtbot.waitUntil(lambda: all(c.state is ConnectionState.CONNECTED for c in chips.values()), timeout=TIMEOUT_MS)
            assert window.link.url == alpha.url and window.connection.url.currentText() == alpha.url
            assert window.fleet_ui.links.link("r-2").url == bravo.url
            assert len(alpha.connections) == 1 and len(bravo.connections) == 1
        finally:
            window.shutdown()
