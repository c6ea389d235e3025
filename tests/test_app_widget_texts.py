"""What the operator reads on and around widgets, against the embedded robot in the real window: nothing
painted over anything else, nothing clipped, type names never cut mid-word, and the words themselves."""

from __future__ import annotations

import pytest
from app_helpers import snap, tap, window_session
from qtpy import QtCore, QtWidgets
from qtpy.QtTest import QTest

from rcon_core.app.catalog_panel import TYPE_ROLE
from rcon_core.canvas import Geometry
from rcon_core.plugins import Binding, Role

pytest.importorskip("rcon_widgets_std")
pytestmark = pytest.mark.usefixtures("qapp")


@pytest.fixture
def window(qtbot, tmp_path, sim_thread, plugins):
    yield from window_session(qtbot, tmp_path / "config", plugins, url=sim_thread.url, wait_connected=True,
                              topics=("/cmd_vel", "/speed_limit", "/battery"))


def place(window, qtbot, plugins, kind: str, binding: Binding, size=None, settings=None, title="w"):
    spec = plugins.widget(kind)
    inst = window.doc.add_widget(window.controller.canvas.id, kind, binding,
                                 Geometry(16, 16, *(size or spec.default_size)), settings or {}, title)
    hosted = window.host.hosted[inst.id]
    qtbot.waitUntil(lambda: hosted.view is not None and hosted.view.isVisible(), timeout=10_000)
    return inst, hosted


def below(view: QtWidgets.QWidget, upper: QtWidgets.QWidget, lower: QtWidgets.QWidget) -> bool:
    """``lower`` starts under ``upper``'s bottom edge (both in ``view``'s coordinates)."""
    top_of_lower = lower.mapTo(view, QtCore.QPoint(0, 0)).y()
    bottom_of_upper = upper.mapTo(view, QtCore.QPoint(0, upper.height())).y()
    return top_of_lower >= bottom_of_upper


# ----------------------------------------------------------------------------------------- item 11
def test_a_text_field_never_paints_its_status_over_the_input(window, qtbot, plugins, sim_thread):
    binding = Binding("/speed_limit", "std_msgs/Float64", Role.PUBLISH, ("data",))
    inst, hosted = place(window, qtbot, plugins, "std.textfield", binding, title="limit")
    window.lock_button.click()
    view = hosted.view
    qtbot.waitUntil(lambda: view.button.isVisible(), timeout=5_000)
    view.edit.setFocus()
    QTest.keyClicks(view.edit, "0.8")
    tap(view.button)
    sim_thread.wait_for_published_sync("/speed_limit", lambda m: m["data"] == 0.8, timeout=10)
    qtbot.waitUntil(lambda: view.status.text() == "sent: 0.8", timeout=5_000)
    # at its default size both show, one under the other
    assert view.status.isVisible() and below(view, view.edit, view.status)
    snap(window, "textfield-default-size")
    # squeezed shorter than both need: the status line gives way (it becomes the input's tooltip)
    window.controller.set_locked(False)
    window.doc.set_geometry(inst.id, Geometry(16, 16, 240, 80))
    qtbot.waitUntil(lambda: not view.status.isVisible(), timeout=5_000)
    assert view.edit.toolTip() == "sent: 0.8"


def test_compound_child_row_buttons_are_whole(window, qtbot):
    from test_app_compound_editor import add_child, button, open_compound_on_cmd_vel

    panel, editor = open_compound_on_cmd_vel(window)
    add_child(qtbot, editor, "linear.x", "std.slider")
    tap(button(editor, "childDone"))
    add_child(qtbot, editor, "angular.z", "std.stepper")
    tap(button(editor, "childDone"))
    QtWidgets.QApplication.processEvents()
    for name in ("childUp_1", "childDown_0", "childEdit_0", "childRemove_1"):
        b = button(editor, name)
        hint = b.sizeHint()  # the theme's touch size plus the border it draws around it
        assert b.width() >= hint.width() and b.height() >= hint.height(), (name, b.size(), hint)
    assert button(editor, "addChildButton").text() == "+ Add child"  # a glyph every font has
    panel.settings_scroll.ensureWidgetVisible(editor.add_button)
    snap(window, "compound-child-rows")


def test_topic_types_keep_their_own_name_when_the_column_is_narrow(window, qtbot):
    tree = window.topics.tree
    delegate = window.topics.delegate
    item = window.topics.item("/battery")
    index = tree.indexFromItem(item)
    assert index.data(TYPE_ROLE).endswith("BatteryState")
    for width in (tree.columnWidth(0), 150, 110):
        option = QtWidgets.QStyleOptionViewItem()
        option.initFrom(tree.viewport())
        option.rect = QtCore.QRect(0, 0, width, tree.visualRect(index).height())
        option.widget = tree
        name_line, type_line = delegate.lines(index, option).split("\u2028")
        # the package gave way (to "…", or wholly when even that does not fit), never the type's name
        assert type_line.endswith("/BatteryState" if width >= 150 else "BatteryState"), (width, type_line)
        assert tree.fontMetrics().horizontalAdvance(type_line) <= width
        if tree.fontMetrics().horizontalAdvance("sensor_msgs/BatteryState") <= width:
            assert type_line == "sensor_msgs/BatteryState"  # a column wide enough cuts nothing
        else:
            assert "…" in type_line or width == 110
    assert type_line == "BatteryState" and name_line == "/battery"
    snap(window, "topic-types")


# ------------------------------------------------------------------------------------ the words
def open_from_palette(window, kind: str):
    from app_helpers import tap_item

    window.side.setCurrentWidget(window.palette_panel)
    tree = window.palette_panel.tree
    tap_item(tree, tree.indexFromItem(window.palette_panel.item(kind)))
    return window.add_panel


def test_not_configured_says_a_missing_topic_once_and_decimals_in_words(window, qtbot):
    panel = open_from_palette(window, "std.textfield")
    assert panel.problems() == ["no topic chosen"]  # not again as "no topic type set"
    qtbot.waitUntil(lambda: "no topic chosen" in panel.preview_frame.problems.text(), timeout=5_000)
    assert "type set" not in panel.preview_frame.problems.text()
    decimals = panel.form.editor("decimals")
    assert decimals.value() == -1 and decimals.text() == "as received"  # never "-1"
    panel.settings_scroll.ensureWidgetVisible(decimals)
    snap(window, "textfield-settings")
    panel.cancel()
    panel = open_from_palette(window, "std.label")
    label_decimals = panel.form.editor("decimals")
    label_decimals.setValue(-1)
    assert label_decimals.text() == "as received"


def test_a_service_widget_is_titled_without_slashes(window, qtbot):
    from app_helpers import choose_kind

    window.side.setCurrentWidget(window.services)
    qtbot.waitUntil(lambda: window.services.item("/reset_pose") is not None, timeout=10_000)
    tree = window.services.tree
    index = tree.indexFromItem(window.services.item("/reset_pose"))
    tree.scrollTo(index)
    tap(tree.viewport(), tree.visualRect(index).center())
    panel = choose_kind(window, Role.CALL, "std.button")
    assert panel.title_edit.text() == "reset pose"  # like a topic's title ("battery"), not "/reset_pose"


def test_the_lights_switch_reads_as_a_state_and_says_what_a_tap_does(window, qtbot, plugins, sim_thread):
    binding = Binding("/lights/set", "std_srvs/SetBool", Role.CALL, ("request.data",))
    _inst, hosted = place(window, qtbot, plugins, "std.switch", binding,
                          settings={"state_topic": "/lights/state", "state_field": "data"}, title="Lights")
    window.lock_button.click()
    view = hosted.view
    qtbot.waitUntil(lambda: view.button.text() == "○ Off", timeout=10_000)  # a lamp not lit: a state
    assert view.reply.text() == "tap for On"
    snap(window, "switch-off")
    tap(view.button)
    qtbot.waitUntil(lambda: sim_thread.robot.lights is True, timeout=10_000)
    qtbot.waitUntil(lambda: view.button.text() == "● On", timeout=10_000)


def test_a_text_view_on_a_string_topic_has_no_level_picker(window, qtbot, plugins):
    _i, chat = place(window, qtbot, plugins, "std.textview",
                     Binding("/ops/chat", "std_msgs/String", Role.SUBSCRIBE), title="chat")
    assert not chat.view.level.isVisible() and chat.view.filter.isVisible()
    window.doc.set_geometry(_i.id, Geometry(16, 300, 420, 260))
    _j, log = place(window, qtbot, plugins, "std.textview",
                    Binding("/rosout", "rosgraph_msgs/Log", Role.SUBSCRIBE), title="log")
    assert log.view.level.isVisible()


def test_a_number_child_offers_the_slider_first_and_a_used_field_not_again(window, qtbot):
    from test_app_compound_editor import add_child, button, open_compound_on_cmd_vel

    panel, editor = open_compound_on_cmd_vel(window)
    add_child(qtbot, editor, "linear.x", "std.slider")
    kinds = list(editor.kind_buttons)
    assert kinds.index("std.slider") < kinds.index("std.textfield"), kinds  # made for numbers first
    assert kinds.index("std.stepper") < kinds.index("std.textfield"), kinds
    tap(button(editor, "childDone"))
    tap(editor.add_button)
    qtbot.waitUntil(lambda: editor.current_page == "fields", timeout=10_000)
    offered = set(editor.field_buttons)
    assert "linear.x" not in offered  # set by child 1 already
    assert "linear" not in offered and "" not in offered  # they hold linear.x too
    assert {"linear.y", "angular", "angular.z"} <= offered
