"""What the operator reads on and around widgets, against the embedded robot in the real window: nothing
painted over anything else, nothing clipped, type names never cut mid-word, and the words themselves."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from app_helpers import entry_point_plugins, tap, window_session
from qtpy import QtCore, QtWidgets
from qtpy.QtTest import QTest

from rcon_core.app.catalog_panel import TYPE_ROLE
from rcon_core.canvas import Geometry
from rcon_core.plugins import Binding, PluginManager, Role

pytest.importorskip("rcon_widgets_std")
pytestmark = pytest.mark.usefixtures("qapp")

SHOTS = Path(os.environ.get("RCON_UX_SHOTS", "/tmp/ux-a"))


@pytest.fixture(scope="module")
def plugins() -> PluginManager:
    return entry_point_plugins()


@pytest.fixture
def window(qtbot, tmp_path, sim_thread, plugins):
    yield from window_session(qtbot, tmp_path / "config", plugins, url=sim_thread.url, wait_connected=True,
                              topics=("/cmd_vel", "/speed_limit", "/battery"))


def shoot(window, name: str) -> None:
    SHOTS.mkdir(parents=True, exist_ok=True)
    QtWidgets.QApplication.processEvents()
    window.grab().save(str(SHOTS / name))


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
    shoot(window, "textfield-default-size.png")
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
    shoot(window, "compound-child-rows.png")


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
        assert "…" in type_line or width == 110
    assert type_line == "BatteryState" and name_line == "/battery"
    shoot(window, "topic-types.png")
