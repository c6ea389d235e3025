"""The GPS map on the real window against the sim (issue 21.11): its trail breaks where the robot jumps (a
restart at its start position) and where the link is lost (the robot restarted on the same port), instead
of drawing a straight line across; and the add panel's preview of a map never advertises its goal topic on
the robot (a preview sends nothing)."""

from __future__ import annotations

import contextlib
import math

import pytest
from app_helpers import TIMEOUT_MS, choose_kind, entry_point_plugins, open_window, tap_topic
from qtpy import QtCore

from rcon_core.bridge import ConnectionState
from rcon_core.canvas import Binding, Canvas, Geometry, WidgetInstance, Workspace, new_id
from rcon_core.plugins import Role
from rcon_core.sim.server import SimServer

pytest.importorskip("rcon_widgets_map")
pytestmark = pytest.mark.usefixtures("qapp")


def map_layout() -> Workspace:
    canvas = Canvas(new_id("c"), "Map", locked=True)
    canvas.widgets.append(WidgetInstance(new_id("w"), "map.gps", Binding("/gps/fix", "sensor_msgs/NavSatFix",
                                                                         "subscribe"),
                                         Geometry(16, 16, 640, 480), {"trail_spacing_m": 0.0}, "Map"))
    return Workspace([canvas], canvas.id)


def main_track(hosted):
    value = hosted.model.state.value if hosted.model is not None else None
    return value.main if value is not None else None


def crosses(view, track, a, b) -> bool:
    """Whether a drawn trail line joins the fix ``a`` to the fix ``b`` directly."""
    pa, pb = (QtCore.QPointF(*view.viewport.to_screen(*p)) for p in (a, b))
    for line in view.trail_lines(track):
        for k in range(line.size() - 1):
            if {(line.at(k).x(), line.at(k).y()), (line.at(k + 1).x(), line.at(k + 1).y())} == \
                    {(pa.x(), pa.y()), (pb.x(), pb.y())}:
                return True
    return False


def test_the_trail_breaks_at_a_jump_and_at_a_lost_link(qtbot, tmp_path):
    with contextlib.ExitStack() as stack:
        robot = stack.enter_context(SimServer.in_thread(port=0, rate_scale=2.0))
        port = robot.port
        window = open_window(qtbot, tmp_path, entry_point_plugins(), url=robot.url, demo=map_layout,
                             wait_connected=True)
        try:
            [hosted] = window.host.hosted.values()
            qtbot.waitUntil(lambda: (t := main_track(hosted)) is not None and len(t.points) >= 3, timeout=TIMEOUT_MS)
            # a jump: the robot is 3 km away from one fix to the next (as after a restart at its start)
            before = main_track(hosted).points[-1]
            robot.run_sync(lambda: setattr(robot.robot, "x", robot.robot.x + 3000.0))
            qtbot.waitUntil(lambda: len(main_track(hosted).breaks) == 1
                            and len(main_track(hosted).segments()[-1]) >= 2, timeout=TIMEOUT_MS)
            track = main_track(hosted)
            after = track.segments()[-1][0]
            assert track.points[track.breaks[0] - 1] == before
            view = hosted.view
            view.set_follow(False)
            view.viewport.centre_on((before[0] + after[0]) / 2, (before[1] + after[1]) / 2)
            view.viewport.zoom_at(13)
            assert not crosses(view, track, before, after)
            assert len(view.trail_lines(track)) == 2
            # a lost link: the robot's rosbridge stops and comes back on the same port, the vessel where it was
            where = (robot.robot.x, robot.robot.y, robot.robot.yaw)
            last = main_track(hosted).points[-1]
            stack.close()
            qtbot.waitUntil(lambda: window.connection.state is not ConnectionState.CONNECTED, timeout=TIMEOUT_MS)
            again = stack.enter_context(SimServer.in_thread(port=port, rate_scale=2.0))
            again.run_sync(lambda: (setattr(again.robot, "x", where[0]), setattr(again.robot, "y", where[1]),
                                    setattr(again.robot, "yaw", where[2])))
            qtbot.waitUntil(lambda: window.connection.state is ConnectionState.CONNECTED, timeout=3 * TIMEOUT_MS)
            qtbot.waitUntil(lambda: len(main_track(hosted).breaks) == 2
                            and len(main_track(hosted).segments()[-1]) >= 2, timeout=TIMEOUT_MS)
            track = main_track(hosted)
            first_new = track.segments()[-1][0]
            assert track.points[track.breaks[1] - 1] == last
            metres = math.dist(last, first_new) * 111_000
            assert metres < 50  # no jump: the trail broke for the lost link alone
            assert not crosses(hosted.view, track, last, first_new)
        finally:
            window.shutdown()


def test_a_map_preview_never_advertises_its_goal_topic(qtbot, tmp_path):
    with SimServer.in_thread(port=0, rate_scale=2.0) as robot:
        window = open_window(qtbot, tmp_path, entry_point_plugins(), url=robot.url, wait_connected=True,
                             topics=("/gps/fix",))
        try:
            tap_topic(window, "/gps/fix")
            panel = choose_kind(window, Role.SUBSCRIBE, "map.gps")
            qtbot.waitUntil(lambda: panel.preview_frame is not None, timeout=TIMEOUT_MS)
            preview = window.host.hosted[panel.preview_frame.instance_id]
            # the preview shows the robot's fix...
            qtbot.waitUntil(lambda: preview.model is not None and preview.model.state.count > 0, timeout=TIMEOUT_MS)
            assert preview.model.goal_topic == "/goal/fix"
            # ...and never told the robot it would publish goals
            assert robot.ops_received[("advertise", "/goal/fix")] == 0
            panel.place_button.click()
            [placed] = [h for h in window.host.hosted.values() if h.widget.kind == "map.gps"]
            qtbot.waitUntil(lambda: robot.ops_received[("advertise", "/goal/fix")] == 1, timeout=TIMEOUT_MS)
        finally:
            window.shutdown()
