"""A topic that does not exist yet, made from the widget pathway: name typed, type searched and picked
(from the local registry and the robot's types), the widget placed and operated against the embedded
robot, which receives the messages on the new topic."""

from __future__ import annotations

import pytest
from app_helpers import entry_point_plugins, snap, tap, tap_item, window_session
from qtpy import QtCore
from qtpy.QtTest import QTest

from rcon_core.app.new_topic import compatible_types, topic_name_problem, type_label
from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import PluginManager, Role

pytest.importorskip("rcon_widgets_std")
pytestmark = pytest.mark.usefixtures("qapp")


@pytest.fixture(scope="module")
def plugins() -> PluginManager:
    return entry_point_plugins()


@pytest.fixture
def window(qtbot, tmp_path, sim_thread, plugins):
    yield from window_session(qtbot, tmp_path / "config", plugins, url=sim_thread.url, wait_connected=True,
                              types=TypeRegistry.standard(), topics=("/cmd_vel",))


def open_from_palette(window, kind: str):
    window.side.setCurrentWidget(window.palette_panel)
    tree = window.palette_panel.tree
    tap_item(tree, tree.indexFromItem(window.palette_panel.item(kind)))
    return window.add_panel


def test_a_chat_on_a_topic_the_robot_does_not_have(window, sim_thread, qtbot):
    assert not any(name == "/ops/chat" for name, _t in window.catalog["topics"])
    panel = open_from_palette(window, "std.textview")
    panel.role_combo.setCurrentIndex(panel.role_combo.findText(Role.PUBLISH.value))
    assert panel.draft.role is Role.PUBLISH
    last = panel.target_combo.count() - 1
    assert panel.target_combo.itemText(last) == "+ New topic…"
    box = panel.choose_new_topic()
    assert box.isVisible()
    # nothing typed yet: the problem says what the new topic lacks, once
    assert panel.problems()[0] == "type the new topic's name (e.g. /chat)"
    assert not panel.place_button.isEnabled()
    box.name_edit.setFocus()
    QTest.keyClicks(box.name_edit, "ops/2chat")
    assert "'2chat'" in panel.problems()[0] and not panel.place_button.isEnabled()
    box.name_edit.selectAll()
    QTest.keyClicks(box.name_edit, "ops/chat")
    assert panel.problems() == ["pick the new topic's type"]
    # the type search: only what a Text View can publish, by name
    assert set(box.type_names()) == {"std_msgs/String", "rosgraph_msgs/Log"}
    QTest.keyClicks(box.search, "string")
    assert box.type_names() == ["std_msgs/String"]
    snap(window, "new-topic-search")
    item = box.item_for("std_msgs/String")
    tap_item(box.type_list, box.type_list.indexFromItem(item))
    assert panel.problems() == [], panel.problems()
    assert panel.draft.binding.name == "/ops/chat" and panel.draft.binding.type == "std_msgs/String"
    snap(window, "new-topic-ready")
    tap(panel.place_button)
    [inst] = window.controller.canvas.widgets
    assert (inst.kind, inst.binding.name, inst.binding.role) == ("std.textview", "/ops/chat", Role.PUBLISH)
    window.lock_button.click()  # Operate mode
    hosted = window.host.hosted[inst.id]
    qtbot.waitUntil(lambda: hosted.view is not None and hosted.view.input is not None
                    and hosted.view.input.isVisible(), timeout=10_000)
    hosted.view.input.setFocus()
    QTest.keyClicks(hosted.view.input, "hello from the console")
    QTest.keyClick(hosted.view.input, QtCore.Qt.Key.Key_Return)
    got = sim_thread.wait_for_published_sync("/ops/chat", timeout=10)
    assert got == {"data": "hello from the console"}


def test_the_new_topic_survives_a_role_change_and_shows_too(window, qtbot):
    panel = open_from_palette(window, "std.label")  # a display: starts subscribing
    assert panel.draft.role is Role.SUBSCRIBE
    box = panel.choose_new_topic()
    QTest.keyClicks(box.name_edit, "/lab/level")
    QTest.keyClicks(box.search, "Float32")
    tap_item(box.type_list, box.type_list.indexFromItem(box.item_for("std_msgs/Float32")))
    assert panel.problems() == [] and panel.draft.binding.field_paths == ("data",)
    # a Label cannot publish; a Slider chosen afterwards offers publishing on a new topic too
    panel.cancel()
    panel = open_from_palette(window, "std.slider")
    box = panel.choose_new_topic()
    QTest.keyClicks(box.name_edit, "/lab/setpoint")
    QTest.keyClicks(box.search, "Float64")
    tap_item(box.type_list, box.type_list.indexFromItem(box.item_for("std_msgs/Float64")))
    assert panel.problems() == []
    panel.role_combo.setCurrentIndex(panel.role_combo.findText(Role.SUBSCRIBE.value))
    assert box.isVisible() and panel.draft.binding.name == "/lab/setpoint"
    assert panel.draft.role is Role.SUBSCRIBE and panel.problems() == []


def test_topic_names_and_type_labels():
    assert topic_name_problem("chat") is None and topic_name_problem("/a/b_2") is None
    assert topic_name_problem("") == "type the new topic's name (e.g. /chat)"
    assert "empty part" in topic_name_problem("/a//b")
    assert "ends with '/'" in topic_name_problem("/a/")
    assert "letters, digits" in topic_name_problem("/my topic")
    assert type_label("sensor_msgs/msg/BatteryState") == "BatteryState  ·  sensor_msgs"


def test_types_offered_come_from_the_registry_and_the_robot(plugins):
    types = TypeRegistry.standard()
    spec = plugins.widget("std.textview")
    assert compatible_types(spec, Role.PUBLISH, types, plugins) == ["rosgraph_msgs/Log", "std_msgs/String"]
    # a robot type the registry lacks, whose name the widget lists, is offered as the robot spells it
    empty = TypeRegistry.empty()
    assert compatible_types(spec, Role.SUBSCRIBE, empty, plugins, ["rcl_interfaces/msg/Log"]) == [
        "rcl_interfaces/msg/Log"]
