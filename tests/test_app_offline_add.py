"""A widget placed while the app has no robot gets its data once the robot connects (through the real
window, offscreen, against the sim): the first robot through the connection bar, a fleet workspace's
second robot through its own link, and a canvas shown (switched to) while offline.

The widgets are placed with ``doc.add_widget``, as the add panel does: the runtime on the bridge thread
hears the new widget on its offline port, and must move it to the robot's link when the link comes."""

from __future__ import annotations

from pathlib import Path

import pytest
from app_helpers import TIMEOUT_MS, entry_point_plugins, open_window

from rcon_core.bridge import ConnectionState
from rcon_core.canvas import Binding, Geometry, Workspace, WorkspaceStore
from rcon_core.canvas.robots import Robot

pytestmark = pytest.mark.usefixtures("qapp")

BATTERY = ("/battery", "sensor_msgs/BatteryState", "subscribe", ("percentage",))
LABEL = {"decimals": 0, "units": "%", "scale": 100.0}


@pytest.fixture(autouse=True)
def _std():
    pytest.importorskip("rcon_widgets_std")


def place_label(win, robot: str = "", canvas_id: str | None = None) -> str:
    """A Label on /battery placed as the add panel places it (``doc.add_widget``); its id."""
    w = win.doc.add_widget(canvas_id or win.controller.canvas.id, "std.label", Binding(*BATTERY, robot=robot),
                           Geometry(16, 16, 240, 112), LABEL)
    return w.id


def count_of(win, widget_id: str) -> int:
    hosted = win.host.hosted.get(widget_id)
    model = hosted.model if hosted is not None else None
    return model.state.count if model is not None else 0


def wait_model(qtbot, win, widget_id: str) -> None:
    qtbot.waitUntil(lambda: win.host.hosted[widget_id].model is not None, timeout=TIMEOUT_MS)


def test_a_label_placed_offline_gets_data_once_the_robot_connects(qtbot, tmp_path, sim_thread):
    win = open_window(qtbot, tmp_path / "cfg", entry_point_plugins())
    try:
        assert win.connection.state is not ConnectionState.CONNECTED
        wid = place_label(win)
        wait_model(qtbot, win, wid)
        assert count_of(win, wid) == 0
        win.connect_to(sim_thread.url)
        qtbot.waitUntil(lambda: win.connection.state is ConnectionState.CONNECTED, timeout=TIMEOUT_MS)
        qtbot.waitUntil(lambda: count_of(win, wid) > 0, timeout=TIMEOUT_MS)
        # the model now running is on the robot's link, not the offline port: not link-down
        assert not win.host.hosted[wid].model.state.link_down
    finally:
        win.shutdown()


def test_a_label_placed_on_a_canvas_switched_to_offline_gets_data(qtbot, tmp_path, sim_thread):
    win = open_window(qtbot, tmp_path / "cfg", entry_point_plugins())
    try:
        first = win.controller.index
        win.new_canvas()  # shown at once: the runtime switched to it while offline
        assert win.controller.index != first
        wid = place_label(win)
        wait_model(qtbot, win, wid)
        win.switch_canvas(first)  # away and back while still offline
        win.switch_canvas(win.controller.workspace.canvases.index(win.doc.workspace.find_widget(wid)[0]))
        wait_model(qtbot, win, wid)
        other = place_label(win)  # and one more, placed after the switch back
        wait_model(qtbot, win, other)
        win.connect_to(sim_thread.url)
        qtbot.waitUntil(lambda: count_of(win, wid) > 0 and count_of(win, other) > 0, timeout=TIMEOUT_MS)
    finally:
        win.shutdown()


def test_a_label_placed_for_an_offline_fleet_robot_gets_data_when_that_robot_connects(
        qtbot, tmp_path, sim_fleet_threads):
    alpha, bravo = sim_fleet_threads(2)
    bravo.robot.battery_charge = 16.0  # 80 %: this label shows Bravo's battery, not Alpha's
    cfg: Path = tmp_path / "cfg"
    ws = Workspace.new("Fleet")
    ws.robots = [Robot("r-1", "Alpha"), Robot("r-2", "Bravo")]  # neither has a URL: both offline
    cfg.mkdir(parents=True)
    WorkspaceStore(cfg / "workspace.json").save(ws)
    win = open_window(qtbot, cfg, entry_point_plugins(), url=alpha.url, wait_connected=True)
    try:
        chips = win.fleet_ui.chips
        assert chips.chips["r-2"].state is not ConnectionState.CONNECTED
        wid = place_label(win, robot="r-2")
        wait_model(qtbot, win, wid)
        assert count_of(win, wid) == 0
        win.fleet_ui.connect_robot("r-2", bravo.url)
        qtbot.waitUntil(lambda: chips.chips["r-2"].state is ConnectionState.CONNECTED, timeout=TIMEOUT_MS)
        qtbot.waitUntil(lambda: count_of(win, wid) > 0, timeout=TIMEOUT_MS)
        view = win.host.hosted[wid].view
        qtbot.waitUntil(lambda: view.value.text() == "80 %", timeout=TIMEOUT_MS)
    finally:
        win.shutdown()
