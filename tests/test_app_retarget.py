"""Issue 21.6, in the real window against two sims: "Duplicate for robot" to a robot in a namespace.

With ``rcon sim --name boat2`` the copy stayed bound to ``/cmd_vel`` and ``/gps/fix``, which boat2 does not
have: the map said NO DATA and the pad animated while nothing moved. Now the names are mapped through the
target's namespace (``/boat2/cmd_vel``), each is checked against the robot's topics and services, and the
operator is shown the mapping and whatever the robot lacks before the copy is made; a pad bound to a topic
nobody subscribes to says so.
"""

from __future__ import annotations

import pytest
from app_helpers import TIMEOUT_MS, entry_point_plugins, open_window, snap_with, tap
from qtpy import QtCore, QtWidgets
from qtpy.QtTest import QTest

from rcon_core.bridge import ConnectionState
from rcon_core.canvas import Binding, Document, Geometry, Workspace, WorkspaceStore
from rcon_core.canvas.robots import Robot
from rcon_core.plugins import Role
from rcon_core.sim import SimServer
from rcon_core.testing import TEST_RATE_SCALE

pytest.importorskip("rcon_widgets_std")
pytest.importorskip("rcon_widgets_sensors")
pytestmark = pytest.mark.usefixtures("qapp")


@pytest.fixture
def sims():
    with SimServer.in_thread(host="127.0.0.1", port=0, rate_scale=TEST_RATE_SCALE) as alpha, \
            SimServer.in_thread(host="127.0.0.1", port=0, rate_scale=TEST_RATE_SCALE, name="boat2") as boat2:
        alpha.run_sync(lambda: alpha.advertise_internal("/alpha_only", "std_msgs/String", "/test"))
        yield alpha, boat2


WIDGETS = [
    ("Drive", "sensors.teleop", Binding("/cmd_vel", "geometry_msgs/Twist", Role.PUBLISH), {}, (16, 16, 272, 320)),
    ("Latitude", "std.label", Binding("/gps/fix", "sensor_msgs/NavSatFix", Role.SUBSCRIBE, ("latitude",)),
     {"decimals": 6}, (304, 16, 256, 112)),
    ("Lights", "std.switch", Binding("/lights/set", "std_srvs/SetBool", Role.CALL, ("request.data",)),
     {"state_topic": "/lights/state"}, (304, 144, 208, 144)),
    ("Lab", "std.label", Binding("/alpha_only", "std_msgs/String", Role.SUBSCRIBE, ("data",)), {},
     (576, 16, 256, 112)),
]


def open_two(qtbot, tmp_path, alpha, boat2):
    ws = Workspace.new("Drive")
    ws.robots = [Robot("r-1", "Alpha"), Robot("r-2", "boat2", url=boat2.url)]
    doc = Document(ws)
    for title, kind, binding, settings, rect in WIDGETS:
        w = doc.add_widget(doc.current.id, kind, binding, Geometry(*rect), settings)
        doc.reconfigure_widget(w.id, title=title)
    (tmp_path / "config").mkdir(parents=True, exist_ok=True)
    WorkspaceStore(tmp_path / "config" / "workspace.json").save(ws)
    win = open_window(qtbot, tmp_path / "config", entry_point_plugins(), url=alpha.url, wait_connected=True)
    qtbot.waitUntil(lambda: win.fleet_ui.chips.chips["r-2"].state is ConnectionState.CONNECTED, timeout=TIMEOUT_MS)
    qtbot.waitUntil(lambda: "r-2" in win.fleet_ui.catalogs, timeout=TIMEOUT_MS)  # boat2's topics are known
    return win


def test_duplicate_for_a_namespaced_robot_maps_the_names_and_lists_what_it_lacks(qtbot, tmp_path, sims):
    alpha, boat2 = sims
    win = open_two(qtbot, tmp_path, alpha, boat2)
    try:
        original = win.controller.canvas
        box = win.fleet_ui.retarget_current("r-2")  # Canvas ▾ → Duplicate for robot → boat2
        qtbot.waitUntil(box.isVisible, timeout=TIMEOUT_MS)
        detail = box.informativeText()
        for line in ("/cmd_vel → /boat2/cmd_vel", "/gps/fix → /boat2/gps/fix", "/lights/set → /boat2/lights/set",
                     "/lights/state → /boat2/lights/state"):
            assert line in detail, detail
        assert "namespace /boat2" in detail and "Not on boat2" in detail and "/alpha_only" in detail
        assert [c.name for c in win.controller.workspace.canvases] == ["Drive"]  # nothing made before the answer
        snap_with(win, box, "retarget-namespace")
        tap(box.findChild(QtWidgets.QPushButton, "confirmYes"))
        qtbot.waitUntil(lambda: win.controller.canvas is not original, timeout=TIMEOUT_MS)
        copy = win.controller.canvas
        by_title = {w.title: w for w in copy.widgets}
        assert {t: (w.binding.name, w.binding.robot) for t, w in by_title.items()} == {
            "Drive": ("/boat2/cmd_vel", "r-2"), "Latitude": ("/boat2/gps/fix", "r-2"),
            "Lights": ("/boat2/lights/set", "r-2"), "Lab": ("/alpha_only", "r-2")}
        assert by_title["Lights"].settings["state_topic"] == "/boat2/lights/state"
        assert [w.binding.name for w in original.widgets] == ["/cmd_vel", "/gps/fix", "/lights/set", "/alpha_only"]
        # the copy's label shows boat2's fix; its pad drives boat2
        label = win.host.hosted[by_title["Latitude"].id]
        qtbot.waitUntil(lambda: label.model is not None and label.model.state.count >= 1, timeout=TIMEOUT_MS)
        win.controller.set_locked(True)
        pad_hosted = win.host.hosted[by_title["Drive"].id]
        qtbot.waitUntil(lambda: pad_hosted.view is not None and pad_hosted.view.isVisible(), timeout=TIMEOUT_MS)
        pad = pad_hosted.view
        qtbot.waitUntil(lambda: "idle" in pad.status_text() or "touch to drive" in pad.status_text(),
                        timeout=TIMEOUT_MS)
        centre, radius = pad.pad()
        c = centre.toPoint()
        QTest.mousePress(pad, QtCore.Qt.MouseButton.LeftButton, pos=c)
        QTest.mouseMove(pad, c - QtCore.QPoint(0, int(radius * 0.9)))
        boat2.wait_for_published_sync("/boat2/cmd_vel", lambda m: m["linear"]["x"] > 0.3, timeout=10)
        qtbot.waitUntil(lambda: boat2.robot.cmd_surge > 0.3, timeout=TIMEOUT_MS)  # it moves
        QTest.mouseRelease(pad, QtCore.Qt.MouseButton.LeftButton, pos=c)
        qtbot.waitUntil(lambda: boat2.robot.cmd_surge == 0.0, timeout=TIMEOUT_MS)
        assert win.fleet_ui.retarget_plan.missing == ("/alpha_only",)
    finally:
        win.shutdown()


def test_a_pad_bound_to_a_topic_nobody_subscribes_to_says_so(qtbot, tmp_path, sims):
    alpha, boat2 = sims
    win = open_two(qtbot, tmp_path, alpha, boat2)
    try:
        canvas = win.controller.canvas
        pad_inst = win.doc.add_widget(canvas.id, "sensors.teleop",
                                      Binding("/cmd_vel", "geometry_msgs/Twist", Role.PUBLISH, robot="r-2"),
                                      Geometry(576, 160, 272, 320), {}, "Drive boat2 (wrong name)")
        win.controller.set_locked(True)
        hosted = win.host.hosted[pad_inst.id]
        qtbot.waitUntil(lambda: hosted.view is not None and hosted.view.isVisible(), timeout=TIMEOUT_MS)
        qtbot.waitUntil(lambda: "nobody subscribes to /cmd_vel" in hosted.view.status_text(), timeout=TIMEOUT_MS)
        assert hosted.view.status_text() == "⚠ nobody subscribes to /cmd_vel: nothing moves"
        # the first robot's own /cmd_vel has a listener: its pad says nothing of the kind
        [own] = [w for w in canvas.widgets if w.title == "Drive"]
        view = win.host.hosted[own.id].view
        qtbot.waitUntil(lambda: view is not None and "touch to drive" in view.status_text(), timeout=TIMEOUT_MS)
    finally:
        win.shutdown()
