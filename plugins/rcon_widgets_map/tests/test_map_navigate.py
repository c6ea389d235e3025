"""The map's "Navigate here": a long press on the map proposes the point, *Navigate here* sends a goal to the
sim's ``/navigate_to_fix`` (ROS 2 mode), the chip shows the distance remaining, *Stop* cancels it and the
vessel stops; a short tap still proposes a plain goal; where the point goes in a goal type."""

from __future__ import annotations

import pytest
from qtpy import QtCore
from qtpy.QtTest import QTest
from rcon_widgets_map.model import MapModel
from rcon_widgets_map.navigate import geo_goal_path
from rcon_widgets_map.settings import MapPluginSettings, MapSettings
from rcon_widgets_map.view import MapView

from rcon_core.bridge import BridgeClient
from rcon_core.bridge.threaded import BridgeThread
from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import Binding
from rcon_core.sim import SimServer
from rcon_core.testing import flushed_sync, qt_flushed

TYPES = TypeRegistry.standard()
Qt = QtCore.Qt
NAV = {"navigate_action": "/navigate_to_fix", "navigate_type": "rcon_sim/action/NavigateToFix"}


def test_the_point_goes_into_the_goals_geo_message():
    assert geo_goal_path(TYPES, "rcon_sim/action/NavigateToFix") == "target"
    with pytest.raises(ValueError, match="no latitude/longitude"):
        geo_goal_path(TYPES, "action_tutorials_interfaces/action/Fibonacci")
    with pytest.raises(ValueError, match="unknown action type"):
        geo_goal_path(TYPES, "lab/action/Nope")
    assert MapSettings(navigate_action="no good").problems()
    assert not MapSettings(**NAV).problems()


@pytest.fixture
def ros2_bridge():
    with SimServer.in_thread(host="127.0.0.1", port=0, rate_scale=2.0, ros2=True) as sim:
        bt = BridgeThread().start()
        client = BridgeClient(sim.url, reconnect=False)
        bt.run(client.connect()).result(10)
        yield sim, bt, client
        bt.run(client.close()).result(10)
        bt.stop()


def make_view(qtbot, model):
    view = MapView(model)
    qtbot.addWidget(view)
    view.resize(480, 400)
    view.show()
    qtbot.waitExposed(view)
    view.refresh(model.state)
    return view


def long_press(view, pos: QtCore.QPoint) -> None:
    QTest.mousePress(view, Qt.MouseButton.LeftButton, Qt.KeyboardModifier.NoModifier, pos)
    QTest.qWait(800)
    QTest.mouseRelease(view, Qt.MouseButton.LeftButton, Qt.KeyboardModifier.NoModifier, pos)


def test_long_press_navigate_here_drives_and_stop_cancels(qtbot, ros2_bridge):
    sim, bt, client = ros2_bridge
    model = MapModel(MapSettings(zoom=18, **NAV), Binding("/gps/fix", "sensor_msgs/NavSatFix", "subscribe"),
                     client.node("map-nav"), types=TYPES, plugin_settings=MapPluginSettings(), dispatch=bt.call)
    bt.call(model.start).result(5)
    qtbot.waitUntil(lambda: model.state.count > 0, timeout=10_000)
    view = make_view(qtbot, model)
    long_press(view, QtCore.QPoint(400, 200))  # well east of the vessel (in the middle)
    assert view.bubble.isVisible() and "Navigate here" in view.bubble.label.text()
    assert view.bubble.send.text() == "Navigate here" and view.pending is None  # not a plain goal
    lat, lon = view.nav.pending
    qt_flushed(qtbot)  # what the press set going has run, and a marker after it reached the robot
    flushed_sync(bt, client, sim, qtbot=qtbot)
    assert model.state.value.nav is None and sim.robot.cmd_surge == 0.0  # nothing sent before the tap
    qtbot.mouseClick(view.bubble.send, Qt.MouseButton.LeftButton)
    assert not view.bubble.isVisible()
    qtbot.waitUntil(lambda: (n := model.state.value.nav) is not None and n.remaining_m is not None, timeout=10_000)
    nav = model.state.value.nav
    assert nav.phase == "active" and (nav.lat, nav.lon) == pytest.approx((lat, lon))
    assert nav.remaining_m > 20
    view.refresh(model.state)
    assert view.nav.chip_text(nav)[0].startswith("→ navigating:") and "m to go" in view.nav.chip_text(nav)[0]
    qtbot.waitUntil(lambda: sim.robot.surge > 0.1, timeout=10_000)  # the vessel drives toward the point
    view.refresh(model.state)  # what the app does with each new state
    assert view.nav.stop_button.isVisible()
    qtbot.mouseClick(view.nav.stop_button, Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: model.state.value.nav.phase == "canceled", timeout=10_000)
    assert sim.robot.cmd_surge == 0.0
    view.refresh(model.state)
    assert view.nav.chip_text(model.state.value.nav)[0].startswith("⊘ navigation canceled")
    assert not view.nav.stop_button.isVisible()
    # a short tap is still a plain goal on the goal topic
    qtbot.mouseClick(view, Qt.MouseButton.LeftButton, pos=QtCore.QPoint(100, 300))
    assert view.pending is not None and view.nav.pending is None and view.bubble.send.text() == "Send goal"
    bt.call(model.stop).result(5)


def _nav_model(qtbot, client, bt):
    model = MapModel(MapSettings(zoom=18, **NAV), Binding("/gps/fix", "sensor_msgs/NavSatFix", "subscribe"),
                     client.node("map-nav"), types=TYPES, plugin_settings=MapPluginSettings(), dispatch=bt.call)
    bt.call(model.start).result(5)
    qtbot.waitUntil(lambda: model.state.count > 0, timeout=10_000)  # the vessel's first fix
    return model


def _far_point(sim):
    lat, lon = sim.robot.lat_lon()
    return lat, lon + 0.004  # about 320 m east


def test_stopping_the_map_cancels_the_navigation_and_says_so(qtbot, ros2_bridge):
    sim, bt, client = ros2_bridge
    model = _nav_model(qtbot, client, bt)
    assert model.navigate(*_far_point(sim))
    qtbot.waitUntil(lambda: (n := model.state.value.nav) is not None and n.remaining_m is not None, timeout=10_000)
    bt.call(model.stop).result(5)  # the canvas is left
    assert model.navigator.state.phase == "canceled" and "map stopped" in model.navigator.state.text
    qtbot.waitUntil(lambda: sim.robot.cmd_surge == 0.0, timeout=10_000)


def test_a_lost_link_leaves_the_navigation_unknown_never_arrived(qtbot):
    with SimServer.in_thread(host="127.0.0.1", port=0, rate_scale=2.0, ros2=True) as sim:
        bt = BridgeThread().start()
        client = BridgeClient(sim.url, reconnect=False)
        bt.run(client.connect()).result(10)
        model = _nav_model(qtbot, client, bt)
        assert model.navigate(*_far_point(sim))
        qtbot.waitUntil(lambda: (n := model.state.value.nav) is not None and n.remaining_m is not None,
                        timeout=10_000)
    # the robot went away with the goal running
    qtbot.waitUntil(lambda: model.state.value.nav.phase != "active", timeout=10_000)
    nav = model.state.value.nav
    assert nav.phase == "unknown" and "fate is unknown" in nav.text
    bt.call(model.stop).result(5)
    bt.run(client.close()).result(10)
    bt.stop()
