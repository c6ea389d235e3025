"""Actions in the app against the sim in ROS 2 mode: the Actions list, the Action widget placed from it,
a goal to ``/navigate_to_fix`` driven to the end (feedback with the distance remaining, a progress bar,
"Succeeded" in green), Cancel (the vessel stops, "Canceled"), a goal in flight when the canvas is switched
away (cancelled, and said so), a lost link (the fate is unknown, never a success), a bad entry named.
"""

from __future__ import annotations

import math

import pytest
from app_helpers import TIMEOUT_MS, choose_kind, entry_point_plugins, snap, tap, tap_item, window_session
from qtpy import QtCore, QtWidgets
from qtpy.QtTest import QTest

from rcon_core.canvas import Geometry
from rcon_core.plugins import Binding, PluginManager, Role
from rcon_core.sim import SimServer
from rcon_core.testing import TEST_RATE_SCALE

pytest.importorskip("rcon_widgets_std")
from rcon_widgets_std.action_view import PHASE_TEXT  # noqa: E402

pytestmark = pytest.mark.usefixtures("qapp")

NAV = "/navigate_to_fix"
NAV_TYPE = "rcon_sim/action/NavigateToFix"


@pytest.fixture(scope="module")
def plugins() -> PluginManager:
    return entry_point_plugins()


@pytest.fixture
def sim2():
    with SimServer.in_thread(host="127.0.0.1", port=0, rate_scale=TEST_RATE_SCALE, ros2=True) as server:
        yield server


@pytest.fixture
def window(qtbot, tmp_path, sim2, plugins):
    yield from window_session(qtbot, tmp_path / "config", plugins, url=sim2.url, wait_connected=True)


def fix_at(sim: SimServer, east: float, north: float) -> tuple[float, float]:
    """The latitude and longitude ``east``/``north`` metres from where the vessel is now."""
    lat, lon = sim.robot.lat_lon()
    r = 6_371_000.0
    return lat + math.degrees(north / r), lon + math.degrees(east / (r * math.cos(math.radians(lat))))


def place_action(window, qtbot, plugins):
    inst = window.doc.add_widget(window.controller.canvas.id, "std.action", Binding(NAV, NAV_TYPE, Role.ACTION),
                                 Geometry(16, 16, 352, 432), {}, "Navigate")
    if not window.controller.canvas.locked:
        window.lock_button.click()
    hosted = window.host.hosted[inst.id]
    qtbot.waitUntil(lambda: hosted.view is not None and "target.latitude" in hosted.view.editors
                    and hosted.view.send_button.isVisible(), timeout=TIMEOUT_MS)
    return inst, hosted.view


def type_into(edit: QtWidgets.QLineEdit, text: str) -> None:
    edit.setFocus()
    edit.selectAll()
    QTest.keyClicks(edit, text)


def send_goal(view, lat: float, lon: float) -> None:
    type_into(view.editors["target.latitude"], f"{lat:.7f}")
    type_into(view.editors["target.longitude"], f"{lon:.7f}")
    tap(view.send_button)


def fb(view) -> int:
    return getattr(view.model.state.value, "feedback_count", 0)


def phase(view) -> str:
    st = view.model.state.value
    return getattr(st, "phase", "")


def test_actions_list_and_the_add_pathway_place_an_action_widget(window, qtbot, plugins):
    qtbot.waitUntil(lambda: window.actions_list.item(NAV) is not None, timeout=TIMEOUT_MS)
    assert window.actions_list.item(NAV).data(0, 257) == NAV_TYPE  # the type, from /rosapi/action_type
    assert window.actions_list.item("/fibonacci") is not None
    window.side.setCurrentWidget(window.actions_list)
    snap(window, "actions-list")
    tree = window.actions_list.tree
    tap_item(tree, tree.indexFromItem(window.actions_list.item(NAV)))
    panel = window.add_panel
    assert panel.role_buttons[Role.ACTION].isVisible()
    assert not panel.role_buttons[Role.SUBSCRIBE].isVisible() and not panel.role_buttons[Role.CALL].isVisible()
    choose_kind(window, Role.ACTION, "std.action")
    assert panel.target_label.text() == "Action"
    tap(panel.place_button)
    placed = [i for i in window.controller.canvas.widgets if i.kind == "std.action"]
    assert len(placed) == 1 and placed[0].binding.name == NAV and placed[0].binding.role is Role.ACTION


def test_goal_drives_to_the_fix_with_feedback_and_succeeds(window, sim2, qtbot, plugins):
    _inst, view = place_action(window, qtbot, plugins)
    lat, lon = fix_at(sim2, 8.0, 4.0)
    send_goal(view, lat, lon)
    qtbot.waitUntil(lambda: fb(view) >= 2, timeout=TIMEOUT_MS)
    assert "distance_remaining" in view.numbers.text()
    assert view.progress.isVisible() and "distance_remaining" in view.progress.format()
    assert view.cancel_button.isEnabled()
    assert view.status.text().startswith(PHASE_TEXT["active"][0])
    snap(window, "action-in-flight")
    qtbot.waitUntil(lambda: view.status.text().startswith("✓ Succeeded"), timeout=30_000)
    assert phase(view) == "succeeded" and view.status.colour == PHASE_TEXT["succeeded"][1]
    assert view.progress.value() == 1000 and "arrived" in view.result.text()
    assert not view.cancel_button.isEnabled()
    snap(window, "action-succeeded")
    here = sim2.robot.lat_lon()
    assert abs(here[0] - lat) < 3e-5 and abs(here[1] - lon) < 4e-5  # within a few metres of the fix


def test_cancel_stops_the_vessel_and_says_canceled(window, sim2, qtbot, plugins):
    _inst, view = place_action(window, qtbot, plugins)
    send_goal(view, *fix_at(sim2, 300.0, 0.0))
    qtbot.waitUntil(lambda: fb(view) >= 2, timeout=TIMEOUT_MS)
    tap(view.cancel_button)
    qtbot.waitUntil(lambda: view.status.text().startswith("⊘ Canceled"), timeout=TIMEOUT_MS)
    assert phase(view) == "canceled" and view.status.colour == PHASE_TEXT["canceled"][1]
    snap(window, "action-canceled")
    v = sim2.robot
    assert v.cmd_surge == 0.0  # the cancel stopped the drive at once
    qtbot.waitUntil(lambda: abs(v.surge) < 0.02, timeout=TIMEOUT_MS)  # and it coasts to a stop
    goal = sim2.navigate_action.goal
    qtbot.waitUntil(lambda: goal.task.done(), timeout=TIMEOUT_MS)  # the drive that commands the thrusters ended
    assert v.cmd_surge == 0.0 and abs(v.surge) < 0.02  # no command after the cancel


def test_the_goal_form_starts_empty_marks_what_is_required_and_sends_nothing_until_it_is_filled(
        window, sim2, qtbot, plugins):
    """issue 21.5: latitude/longitude started as real zeros; one tap of Send goal sent the boat to 0°N 0°E."""
    _inst, view = place_action(window, qtbot, plugins)
    lat_edit, lon_edit = view.editors["target.latitude"], view.editors["target.longitude"]
    assert lat_edit.text() == "" and lon_edit.text() == "" and view.editors["target.altitude"].text() == ""
    assert lat_edit.placeholderText() == "required" and view.editors["target.altitude"].placeholderText() == "0.0"
    labels = [view.form.labelForField(e).text() for e in (lat_edit, lon_edit)]
    assert labels == ["latitude *", "longitude *"]
    assert not view.send_button.isEnabled() and "latitude, longitude" in view.send_button.toolTip()
    snap(window, "action-goal-empty")
    QTest.mouseClick(view.send_button, QtCore.Qt.MouseButton.LeftButton)  # a tap on the disabled button
    lat, lon = fix_at(sim2, 8.0, 4.0)
    type_into(lat_edit, f"{lat:.7f}")
    assert not view.send_button.isEnabled() and "longitude" in view.send_button.toolTip()
    type_into(lon_edit, f"{lon:.7f}")
    assert view.send_button.isEnabled()
    assert sim2.ops_received[("send_action_goal", NAV)] == 0  # nothing went out before both were typed
    tap(view.send_button)
    qtbot.waitUntil(lambda: fb(view) >= 1, timeout=TIMEOUT_MS)
    assert sim2.ops_received[("send_action_goal", NAV)] == 1
    qtbot.waitUntil(view.cancel_button.isEnabled, timeout=TIMEOUT_MS)
    tap(view.cancel_button)


def test_a_bad_entry_is_named_and_nothing_is_sent(window, sim2, qtbot, plugins):
    _inst, view = place_action(window, qtbot, plugins)
    type_into(view.editors["target.latitude"], "north")
    type_into(view.editors["target.longitude"], "-79.4")
    tap(view.send_button)
    qtbot.waitUntil(lambda: "target.latitude" in view.status.text(), timeout=TIMEOUT_MS)
    assert view.status.colour == PHASE_TEXT["failed"][1] and phase(view) in ("", "idle")


def test_switching_canvas_cancels_the_goal_and_says_so(window, sim2, qtbot, plugins):
    inst, view = place_action(window, qtbot, plugins)
    send_goal(view, *fix_at(sim2, 300.0, 0.0))
    qtbot.waitUntil(lambda: fb(view) >= 1, timeout=TIMEOUT_MS)
    first = window.controller.canvas.id
    window.new_canvas()  # the new canvas is shown: the action widget's canvas is left
    qtbot.waitUntil(lambda: window.controller.canvas.id != first, timeout=TIMEOUT_MS)
    window.switch_canvas(0)
    hosted = window.host.hosted[inst.id]
    qtbot.waitUntil(lambda: hosted.view is not None and "canvas switched away" in hosted.view.status.text(),
                    timeout=TIMEOUT_MS)
    assert phase(hosted.view) == "canceled" and hosted.view.status.text().startswith("⊘ Canceled")


def test_lost_link_shows_the_fate_unknown_never_success(qtbot, tmp_path, plugins):
    with SimServer.in_thread(host="127.0.0.1", port=0, rate_scale=TEST_RATE_SCALE, ros2=True) as sim:
        gen = window_session(qtbot, tmp_path / "config", plugins, url=sim.url, wait_connected=True)
        window = next(gen)
        _inst, view = place_action(window, qtbot, plugins)
        send_goal(view, *fix_at(sim, 300.0, 0.0))
        qtbot.waitUntil(lambda: fb(view) >= 1, timeout=TIMEOUT_MS)
    # the robot is gone with the goal running
    qtbot.waitUntil(lambda: view.status.text().startswith("? Unknown"), timeout=TIMEOUT_MS)
    assert phase(view) == "unknown" and "fate is unknown" in view.status.text()
    assert "Succeeded" not in view.status.text()
    window.shutdown()


def test_an_action_listed_without_its_type_asks_for_it_then_places_the_widget(qtbot, tmp_path, plugins):
    with SimServer.in_thread(host="127.0.0.1", port=0, rate_scale=TEST_RATE_SCALE, ros2=True) as sim:
        del sim.services["/rosapi/action_type"]  # a rosapi 2.1.0: it cannot tell an action's type
        for window in window_session(qtbot, tmp_path / "config", plugins, url=sim.url, wait_connected=True):
            qtbot.waitUntil(lambda actions=window.actions_list: actions.item(NAV) is not None, timeout=TIMEOUT_MS)
            assert window.actions_list.item(NAV).data(0, 257) == ""
            assert window.actions_list.item(NAV).text(0).endswith("type unknown")
            window.side.setCurrentWidget(window.actions_list)
            tree = window.actions_list.tree
            tap_item(tree, tree.indexFromItem(window.actions_list.item(NAV)))
            panel = window.add_panel
            assert panel.role_type.text() == "type unknown" and panel.action_type_box.isVisible()
            assert not panel.role_buttons[Role.ACTION].isEnabled()  # nothing fits a type nobody knows
            panel.action_type_box.choose(NAV_TYPE)
            assert panel.role_type.text() == NAV_TYPE and panel.role_buttons[Role.ACTION].isEnabled()
            choose_kind(window, Role.ACTION, "std.action")
            tap(panel.place_button)
            placed = [i for i in window.controller.canvas.widgets if i.kind == "std.action"]
            assert len(placed) == 1 and placed[0].binding.type == NAV_TYPE


def test_no_type_at_all_offers_no_widget_and_says_so(window, qtbot):
    panel = window.add_panel
    panel.start_from_action("/mystery", "")
    assert panel.action_type_box.isVisible() and not panel.role_buttons[Role.ACTION].isEnabled()
    panel.choose_role(Role.ACTION)  # what the disabled button would do: nothing fits, said, no exception
    assert panel.candidates.count() == 0 and panel.no_candidates.isVisible()
    assert "No installed widget can action" in panel.no_candidates.text()


def test_a_ros1_robot_lists_no_actions_and_says_why(qtbot, tmp_path, sim_thread, plugins):
    for window in window_session(qtbot, tmp_path / "config", plugins, url=sim_thread.url, wait_connected=True,
                                 topics=("/cmd_vel",)):
        window.side.setCurrentWidget(window.actions_list)
        assert window.catalog["actions"] == [] and window.actions_list.tree.topLevelItemCount() == 0
        assert window.actions_list.empty.isVisible() and "ROS 2" in window.actions_list.empty.text()


def test_a_bad_new_goal_while_one_runs_is_named_and_the_run_goes_on(window, sim2, qtbot, plugins):
    _inst, view = place_action(window, qtbot, plugins)
    send_goal(view, *fix_at(sim2, 300.0, 0.0))
    qtbot.waitUntil(lambda: fb(view) >= 1, timeout=TIMEOUT_MS)
    type_into(view.editors["target.longitude"], "west")
    tap(view.send_button)  # "Send new goal"
    qtbot.waitUntil(lambda: "target.longitude" in view.result.text(), timeout=TIMEOUT_MS)
    assert view.result.colour == PHASE_TEXT["failed"][1] and phase(view) == "active"
    assert view.status.text().startswith(PHASE_TEXT["active"][0])
    seen = fb(view)
    qtbot.waitUntil(lambda: fb(view) >= seen + 3, timeout=TIMEOUT_MS)  # feedback goes on arriving...
    assert "target.longitude" in view.result.text()  # ...and the refusal stays said
    tap(view.cancel_button)
    qtbot.waitUntil(lambda: view.status.text().startswith("⊘ Canceled"), timeout=TIMEOUT_MS)
