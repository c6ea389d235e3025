"""A robot marked View only, in the real window against the sim: its link refuses everything that would
change it, whatever path the operator (or a widget) takes, with one sentence naming the robot.

Each test is a person's finding in issue 21: the Params tab set ``max_speed`` 2.0 -> 5.0 on a view-only
robot in a locked app (21.1); on a full config disk ticking View only showed checked but the pad kept
sending (21.1a); "View only: … this robot" marked the other robot on a mixed canvas (21.10)."""

from __future__ import annotations

import errno
import os

import pytest
from app_helpers import (
    TIMEOUT_MS,
    all_sent,
    entry_point_plugins,
    full_disk,
    open_window,
    snap,
    tap,
    window_session,
)
from rogue_widget import CMD, RoguePlugin
from test_app_params import name_of, open_params, tap_param, type_into, value_on_robot

from rcon_core.app.config import AppConfig
from rcon_core.app.pin import make_record
from rcon_core.bridge import ConnectionState
from rcon_core.canvas import Binding, Geometry
from rcon_core.canvas.robots import Robot
from rcon_core.sim import SimServer
from rcon_core.testing import TEST_RATE_SCALE

pytestmark = pytest.mark.usefixtures("qapp")
PIN = "480159"


@pytest.fixture(params=[2, 1], ids=["ros2", "ros1"])
def robot(request):
    with SimServer.in_thread(host="127.0.0.1", port=0, rate_scale=TEST_RATE_SCALE, ros2=request.param == 2,
                             plugin_types=True) as sim:
        yield request.param, sim


def rogue_plugins():
    plugins = entry_point_plugins()
    plugins.register(RoguePlugin(view="rogue_widget_view:RogueView"), "rogue")
    return plugins


def view_only_menu(window):
    window.menu_button.menu().aboutToShow.emit()  # the menu is about to show: its words are brought up to date
    return window.canvas_actions["robot_view_only"]


def test_a_view_only_robot_refuses_a_parameter_write_on_its_link_even_in_a_locked_app(qtbot, tmp_path, robot):
    version, sim = robot
    config = AppConfig(tmp_path)
    config.set_pin_record(make_record(PIN))
    config.set_view_only(sim.url, True)
    win = open_window(qtbot, tmp_path, rogue_plugins(), url=sim.url, wait_connected=True)
    try:
        rogue = win.doc.add_widget(win.controller.canvas.id, "test.rogue",
                                   Binding("/cmd_vel", "geometry_msgs/Twist", "publish"), Geometry(24, 24, 240, 160),
                                   {}, "Rogue")
        qtbot.waitUntil(lambda: rogue.id in win.host.hosted and win.host.hosted[rogue.id].view is not None,
                        timeout=TIMEOUT_MS)
        assert win.operator_lock.engage()  # as `rcon --locked`
        assert win.link.client.guard.view_only  # the mark is on the link from its first frame
        panel = open_params(win, qtbot)
        name = name_of(version, "max_speed")
        before = value_on_robot(version, sim, "max_speed")
        calls = dict(sim.ops_received)
        tap_param(panel, name)
        sentence = f"Setting parameter {name} was not sent: robot “Robot” at {sim.url} is view-only."
        assert panel.edit_problem.text() == sentence  # said as soon as the editor opens
        type_into(panel.edit_value, "5.0")
        tap(panel.set_button)
        assert panel.edit_problem.text() == sentence and win.operator_lock.dialog is None  # nothing asked
        snap(win, "view-only-params")

        # below the panel: its own write, as made after the confirmation, is refused by the robot's link
        panel._write(name, 5.0)
        qtbot.waitUntil(lambda: panel.status.text().startswith("✗"), timeout=TIMEOUT_MS)
        assert panel.status.text() == f"✗ {sentence}"
        all_sent(qtbot, win, sim)
        assert value_on_robot(version, sim, "max_speed") == before
        sent = {k: n - calls.get(k, 0) for k, n in sim.ops_received.items() if n != calls.get(k, 0)}
        assert not [k for k in sent if k[1].endswith(("set_param", "set_parameters", "delete_param"))], sent

        # and a widget that sends on its own gets nothing through either, its error the port's sentence
        hosted = win.host.hosted[rogue.id]
        qtbot.waitUntil(lambda: "call" in hosted.model.attempts, timeout=TIMEOUT_MS)
        all_sent(qtbot, win, sim)
        assert sim.ops_received[("publish", "/cmd_vel")] == calls.get(("publish", "/cmd_vel"), 0)
        assert hosted.frame.badge.status == "VIEW ONLY"
        assert f"robot “Robot” at {sim.url} is view-only" in (hosted.model.state.error or "")
    finally:
        win.close_now()
        win.shutdown()


@pytest.fixture
def disk(monkeypatch):
    return full_disk(monkeypatch)


def test_on_a_full_disk_view_only_still_stops_the_commands_and_says_it_was_not_saved(qtbot, tmp_path, sim_thread,
                                                                                     disk):
    sim = sim_thread
    win = next(window_session(qtbot, tmp_path, rogue_plugins(), url=sim.url, wait_connected=True))
    try:
        rogue = win.doc.add_widget(win.controller.canvas.id, "test.rogue",
                                   Binding("/cmd_vel", "geometry_msgs/Twist", "publish"), Geometry(24, 24, 240, 160),
                                   {}, "Pad")
        qtbot.waitUntil(lambda: win.host.hosted[rogue.id].view is not None, timeout=TIMEOUT_MS)
        win.controller.saver.flush()
        disk.on = True
        action = view_only_menu(win)
        assert action.text() == "View only: nothing is sent to “Robot”"
        action.trigger()
        assert action.isChecked() and win.link.client.guard.view_only  # applied, in memory
        notice = win.notice.label.text()
        assert "view-only mark of" in notice and "could not be saved" in notice
        assert os.strerror(errno.ENOSPC) in notice and "applies until RCON quits" in notice
        before = sim.ops_received[("publish", "/cmd_vel")]
        hosted = win.host.hosted[rogue.id]
        qtbot.waitUntil(lambda: win.host.hosted[rogue.id].model is not hosted.model or hosted.model.view_only,
                        timeout=TIMEOUT_MS)
        for _ in range(25):  # the pad goes on sending, as the operator saw it do
            win.host.hosted[rogue.id].model.publish(CMD)
        all_sent(qtbot, win, sim)
        assert sim.ops_received[("publish", "/cmd_vel")] == before
        snap(win, "view-only-full-disk")
        disk.on = False
        assert not AppConfig(tmp_path).is_view_only(sim.url)  # indeed not on disk
    finally:
        win.shutdown()


def test_the_view_only_action_names_the_side_panels_robot_and_marks_that_one(qtbot, tmp_path, sim_fleet_threads):
    from test_app_fleet import fleet_layout

    alpha, bravo = sim_fleet_threads(2)
    fleet_layout(tmp_path, [Robot("r-1", "Alpha"), Robot("r-2", "Bravo", url=bravo.url)], [])
    win = open_window(qtbot, tmp_path, entry_point_plugins(), url=alpha.url, wait_connected=True)
    try:
        chips = win.fleet_ui.chips
        qtbot.waitUntil(lambda: chips.chips["r-2"].state is ConnectionState.CONNECTED, timeout=TIMEOUT_MS)
        assert view_only_menu(win).text() == "View only: nothing is sent to “Alpha”"
        tap(chips.chips["r-2"])  # the side panel shows Bravo
        action = view_only_menu(win)
        assert action.text() == "View only: nothing is sent to “Bravo”" and not action.isChecked()
        action.trigger()
        assert win.config.is_view_only(bravo.url) and not win.config.is_view_only(alpha.url)
        bravo_client = win.fleet_ui.links.link("r-2").client
        assert bravo_client.guard.view_only and not win.link.client.guard.view_only
        assert bravo_client.guard.reason == f"robot “Bravo” at {bravo.url} is view-only"
        qtbot.waitUntil(lambda: "Bravo · view only" in chips.chips["r-2"].text(), timeout=TIMEOUT_MS)
        assert "view only" not in chips.chips["r-1"].text()
    finally:
        win.shutdown()


def test_a_robot_marked_view_only_in_the_robots_dialog_is_refused_on_its_link(qtbot, tmp_path, sim_thread):
    sim = sim_thread
    win = open_window(qtbot, tmp_path, entry_point_plugins(), url=sim.url, wait_connected=True)
    try:
        robot = win.doc.workspace.robots[0]
        dialog = win.fleet_ui.open_robots_dialog()
        dialog.set_row(0, view_only=True)  # the robot's own box, as ticking it would
        dialog.accept()
        assert win.doc.workspace.robots[0].view_only
        guard = win.link.client.guard
        assert guard.reason == f"robot “{robot.label}” at {sim.url} is view-only"
        win.doc.set_robots([Robot(robot.id, robot.name, url=robot.url)])  # unticked (undoable, no PIN here)
        assert not guard.view_only
    finally:
        win.shutdown()
