"""The Parameters tab against the sim, ROS 2 (by node, ``<node>:<param>``) and ROS 1 (by namespace): listed
when the tab is shown, searched, a value edited with type checking (a bad text is named and nothing is
written), written only after the confirmation, read back; Refresh fetches again."""

from __future__ import annotations

import pytest
from app_helpers import TIMEOUT_MS, entry_point_plugins, snap, tap, tap_item, window_session
from qtpy import QtWidgets
from qtpy.QtTest import QTest

from rcon_core.plugins import PluginManager
from rcon_core.sim import SimServer
from rcon_core.testing import TEST_RATE_SCALE, flushed_sync, qt_flushed

pytestmark = pytest.mark.usefixtures("qapp")


@pytest.fixture(scope="module")
def plugins() -> PluginManager:
    return entry_point_plugins()


@pytest.fixture(params=[2, 1], ids=["ros2", "ros1"])
def robot(request):
    with SimServer.in_thread(host="127.0.0.1", port=0, rate_scale=TEST_RATE_SCALE, ros2=request.param == 2) as sim:
        if request.param == 1:
            sim.params_tree.set("/kingfisher/thruster_gains", [1.0, 0.5])
        yield request.param, sim


@pytest.fixture
def window(qtbot, tmp_path, robot, plugins):
    _version, sim = robot
    yield from window_session(qtbot, tmp_path / "config", plugins, url=sim.url, wait_connected=True)


def name_of(version: int, param: str) -> str:
    return f"/kingfisher:{param.replace('/', '.')}" if version == 2 else f"/kingfisher/{param}"


def value_on_robot(version: int, sim: SimServer, param: str):
    if version == 2:
        return sim.rosapi.node_params.get("/kingfisher", param.replace("/", "."))[1]
    return sim.params_tree.get(f"/kingfisher/{param}")


def open_params(window, qtbot):
    panel = window.params_panel
    window.side.setCurrentWidget(panel)  # shown: the list is fetched (on the bridge thread)
    try:
        qtbot.waitUntil(lambda: panel.item(name_of(2 if panel.ros2 else 1, "max_speed")) is not None
                        and not panel.busy, timeout=TIMEOUT_MS)
    except Exception:
        raise AssertionError(f"params not listed: {panel.status.text()!r}, values {list(panel.values)[:5]}") from None
    return panel


def wait_written(qtbot, panel) -> None:
    try:
        qtbot.waitUntil(lambda: panel.status.text().startswith("✓"), timeout=TIMEOUT_MS)
    except Exception as exc:
        raise AssertionError(f"not written: {panel.status.text()!r} {panel.edit_problem.text()!r}: {exc}") from None


def tap_param(panel, name: str) -> None:
    item = panel.item(name)
    tap_item(panel.tree, panel.tree.indexFromItem(item))


def type_into(edit: QtWidgets.QLineEdit, text: str) -> None:
    edit.setFocus()
    edit.selectAll()
    QTest.keyClicks(edit, text)


def test_browse_search_and_edit_with_confirmation(window, robot, qtbot):
    version, sim = robot
    panel = open_params(window, qtbot)
    assert panel.ros2 == (version == 2)
    heads = [panel.tree.topLevelItem(i).text(0) for i in range(panel.tree.topLevelItemCount())]
    assert "/kingfisher" in heads  # a node (ROS 2) or a namespace (ROS 1)
    max_speed = name_of(version, "max_speed")
    assert panel.item(max_speed).text(0) == "max_speed\n2.0" and panel.shown_value(max_speed) == "2.0"
    # search: only the gps origin stays in sight
    type_into(panel.filter, "origin_lat")
    lat = name_of(version, "gps/origin_lat")
    assert not panel.item(lat).isHidden() and panel.item(max_speed).isHidden()
    panel.filter.clear()
    assert not panel.item(max_speed).isHidden()
    if version == 2:
        snap(window, "params-panel")
    # a text of the wrong kind is refused on the spot, naming what was expected; nothing is written
    tap_param(panel, max_speed)
    assert panel.editor.isVisible() and panel.edit_name.text() == max_speed and "float" in panel.edit_kind.text()
    type_into(panel.edit_value, "fast")
    tap(panel.set_button)
    assert "expected a float" in panel.edit_problem.text()
    assert getattr(window, "confirm_dialog", None) is None or not window.confirm_dialog.isVisible()
    # a good value asks first; Cancel writes nothing
    type_into(panel.edit_value, "1.25")
    tap(panel.set_button)
    qtbot.waitUntil(lambda: window.confirm_dialog.isVisible(), timeout=TIMEOUT_MS)
    assert max_speed in window.confirm_dialog.text() and "1.25" in window.confirm_dialog.informativeText()
    tap(window.confirm_dialog.findChild(QtWidgets.QPushButton, "confirmCancel"))
    qt_flushed(qtbot)  # what the Cancel set going has started; then a marker after it reaches the robot
    flushed_sync(window.link.thread, window.link.client, sim, qtbot=qtbot)
    assert value_on_robot(version, sim, "max_speed") == 2.0
    # confirmed: written, read back, shown
    tap(panel.set_button)
    qtbot.waitUntil(lambda: window.confirm_dialog.isVisible(), timeout=TIMEOUT_MS)
    tap(window.confirm_dialog.findChild(QtWidgets.QPushButton, "confirmYes"))
    wait_written(qtbot, panel)
    assert value_on_robot(version, sim, "max_speed") == 1.25
    assert panel.shown_value(max_speed) == "1.25"
    if version == 2:
        snap(window, "params-set")


def test_bool_string_and_list_values_are_checked_by_kind(window, robot, qtbot):
    version, sim = robot
    panel = open_params(window, qtbot)
    frame = name_of(version, "frame_id")
    tap_param(panel, frame)
    assert "string" in panel.edit_kind.text()
    type_into(panel.edit_value, "base link 2")  # a string needs no quotes
    tap(panel.set_button)
    qtbot.waitUntil(lambda: window.confirm_dialog.isVisible(), timeout=TIMEOUT_MS)
    tap(window.confirm_dialog.findChild(QtWidgets.QPushButton, "confirmYes"))
    wait_written(qtbot, panel)
    assert value_on_robot(version, sim, "frame_id") == "base link 2"
    if version == 1:
        gains = name_of(version, "thruster_gains")
        tap_param(panel, gains)
        assert "list" in panel.edit_kind.text() and panel.edit_value.text() == "[1.0, 0.5]"
        type_into(panel.edit_value, "[1, yes]")
        tap(panel.set_button)
        assert "list of float" in panel.edit_problem.text()


def test_refresh_fetches_changes_made_elsewhere(window, robot, qtbot):
    version, sim = robot
    panel = open_params(window, qtbot)
    if version == 2:
        sim.rosapi.node_params.set("/kingfisher", "max_yaw_rate", 0.5)
    else:
        sim.params_tree.set("/kingfisher/max_yaw_rate", 0.5)
    name = name_of(version, "max_yaw_rate")
    assert panel.shown_value(name) != "0.5"  # nothing polls behind the operator's back
    tap(panel.refresh_button)
    qtbot.waitUntil(lambda: not panel.busy and panel.shown_value(name) == "0.5", timeout=TIMEOUT_MS)


@pytest.fixture
def ros2_window(qtbot, tmp_path, plugins):
    """ROS 2 only: a ROS 1 parameter server takes any name, nothing there refuses a value."""
    with SimServer.in_thread(host="127.0.0.1", port=0, rate_scale=TEST_RATE_SCALE, ros2=True) as sim:
        for win in window_session(qtbot, tmp_path / "config", plugins, url=sim.url, wait_connected=True):
            yield win, sim


def test_a_value_the_node_refuses_is_said_refused_not_set(ros2_window, qtbot):
    window, sim = ros2_window
    version = 2
    panel = open_params(window, qtbot)
    name = name_of(version, "max_yaw_rate")
    sim.rosapi.node_params.delete("/kingfisher", "max_yaw_rate")  # undeclared behind the operator's back
    tap_param(panel, name)
    type_into(panel.edit_value, "0.9")
    tap(panel.set_button)
    qtbot.waitUntil(lambda: window.confirm_dialog.isVisible(), timeout=TIMEOUT_MS)
    tap(window.confirm_dialog.findChild(QtWidgets.QPushButton, "confirmYes"))
    qtbot.waitUntil(lambda: panel.status.text().startswith("✗"), timeout=TIMEOUT_MS)
    assert "refused" in panel.status.text() and "not declared" in panel.edit_problem.text()
    assert panel.shown_value(name) == "1.2"  # the list still shows what it last read, not the refused value
