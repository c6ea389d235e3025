"""The add-widget panel driven like a person (taps, combo popups, the mouse wheel) against the embedded
robot, with the installed widget packages: roles, the Topic and Field choosers, scrolling, the preview's
size, and a clean panel after placing.

``RCON_SCREENSHOTS=DIR`` writes a PNG of the panel at each step (to look at it as a person would).
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from app_helpers import choose_kind, tap, tap_item, window_session
from qtpy import QtCore, QtWidgets
from qtpy.QtTest import QTest

from rcon_core.app.add_panel import AddPanel
from rcon_core.app.choosers import TARGET_ROLE
from rcon_core.app.draft import role_preference
from rcon_core.app.main_window import MainWindow
from rcon_core.app.new_topic import NEW_TOPIC
from rcon_core.app.theme import touch_px
from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import Role
from rcon_core.testing import qt_flushed

pytest.importorskip("rcon_widgets_std")
pytest.importorskip("rcon_widgets_sensors")

pytestmark = pytest.mark.usefixtures("qapp")


@pytest.fixture
def window(qtbot, tmp_path, sim_thread, plugins):
    yield from window_session(qtbot, tmp_path / "config", plugins, url=sim_thread.url,
                              types=TypeRegistry.standard(), wait_connected=True,
                              topics=("/speed_limit",), services=("/lights/set",))


# ------------------------------------------------------------------------------------- a person's hands
def pick(qtbot, combo: QtWidgets.QComboBox, text: str) -> None:
    """Open the combo's popup and tap the entry whose text starts with ``text``."""
    rows = [i for i in range(combo.count()) if combo.itemText(i).startswith(text)]
    assert rows, f"{text!r} not in {[combo.itemText(i) for i in range(combo.count())]}"
    tap(combo)
    view = combo.view()
    qtbot.waitUntil(view.isVisible, timeout=5_000)
    qtbot.wait(QtWidgets.QApplication.doubleClickInterval() + 50)  # a popup ignores a release at once
    tap_item(view, combo.model().index(rows[0], 0))
    qtbot.waitUntil(lambda: not view.isVisible(), timeout=5_000)
    assert combo.currentText().startswith(text)


def wheel(window: QtWidgets.QWidget, widget: QtWidgets.QWidget, notches: int = -1) -> None:
    """Turn the mouse wheel over the middle of ``widget`` (through the window system, as a real wheel)."""
    pos = widget.mapTo(window, widget.rect().center())
    QTest.wheelEvent(window.windowHandle(), QtCore.QPointF(pos), QtCore.QPoint(0, 120 * notches))
    QtWidgets.QApplication.processEvents()


def scroll_area(panel: AddPanel) -> QtWidgets.QScrollArea:
    """The settings page's scroll area (the one around the form)."""
    return panel.settings_page.findChild(QtWidgets.QScrollArea)


def bring_into_sight(panel: AddPanel, widget: QtWidgets.QWidget) -> None:
    """Scroll the settings page so ``widget`` is in sight with room to scroll on (as a person would have
    scrolled there)."""
    QtWidgets.QApplication.processEvents()
    # the whole widget with 60 px to spare (ensureWidgetVisible looks at an editor's text cursor only)
    area = scroll_area(panel)
    centre = widget.mapTo(area.widget(), widget.rect().center())
    area.ensureVisible(centre.x(), centre.y(), 0, widget.height() // 2 + 60)
    QtWidgets.QApplication.processEvents()
    viewport = scroll_area(panel).viewport()
    top = widget.mapTo(viewport, QtCore.QPoint(0, 0)).y()
    assert 0 <= top and top + widget.height() <= viewport.height(), (top, viewport.height())
    center = widget.mapTo(panel.window(), widget.rect().center())
    assert panel.window().childAt(center) in (widget, *widget.findChildren(QtWidgets.QWidget))


def open_from_topic(window: MainWindow, topic: str, role: Role, kind: str) -> AddPanel:
    window.side.setCurrentWidget(window.topics)
    tap_item(window.topics.tree, window.topics.tree.indexFromItem(window.topics.item(topic)))
    panel = choose_kind(window, role, kind)
    assert panel.stack.currentWidget() is panel.settings_page
    return panel


def open_from_palette(window: MainWindow, kind: str) -> AddPanel:
    window.side.setCurrentWidget(window.palette_panel)
    item = window.palette_panel.item(kind)
    tap_item(window.palette_panel.tree, window.palette_panel.tree.indexFromItem(item))
    panel = window.add_panel
    assert panel.stack.currentWidget() is panel.settings_page
    return panel


def offered(panel: AddPanel) -> list[tuple[str, str]]:
    """(name, role) of each target in the Topic/Service chooser, in order (not its "+ New topic…" entry)."""
    combo = panel.target_combo
    return [(combo.itemData(i).name, combo.itemData(i, TARGET_ROLE)) for i in range(1, combo.count())
            if combo.itemData(i, NEW_TOPIC) is not True]


def field_entries(panel: AddPanel) -> list[str]:
    return [panel.field_combo.itemText(i) for i in range(panel.field_combo.count())]


def preview_role(window: MainWindow) -> Role | None:
    widget = window.preview.widget
    return widget.binding.role if widget is not None else None


def snap(panel: AddPanel, name: str) -> None:
    out = os.environ.get("RCON_SCREENSHOTS", "")
    if out and out != "1":
        QtWidgets.QApplication.processEvents()
        Path(out).mkdir(parents=True, exist_ok=True)
        panel.window().grab().save(str(Path(out) / f"{name}.png"))


# ------------------------------------------------------------------------------------- 1 roles
def test_changing_role_rebuilds_the_targets_and_the_preview(window, qtbot, plugins):
    panel = open_from_palette(window, "std.slider")
    spec = plugins.widget("std.slider")
    pick(qtbot, panel.role_combo, "subscribe")
    assert panel.draft.role is Role.SUBSCRIBE and panel.target_label.text() == "Topic"
    pick(qtbot, panel.target_combo, "/battery")
    assert panel.draft.binding.name == "/battery" and preview_role(window) is Role.SUBSCRIBE
    first_preview = panel.preview_frame

    pick(qtbot, panel.role_combo, "publish")
    assert panel.draft.role is Role.PUBLISH and panel.draft.binding.role is Role.PUBLISH
    assert panel.draft.binding.name == "/battery"  # still compatible: kept
    assert panel.preview_frame is not first_preview and preview_role(window) is Role.PUBLISH
    publish = [t.name for t in window.targets_for(spec, Role.PUBLISH)]
    assert publish and [name for name, _role in offered(panel)][:len(publish)] == publish  # publish-capable
    assert all(role == "publish" for _name, role in offered(panel)[:len(publish)])
    assert all(role != "publish" for _name, role in offered(panel)[len(publish):])  # other roles after

    pick(qtbot, panel.role_combo, "subscribe")
    subscribe = [t.name for t in window.targets_for(spec, Role.SUBSCRIBE)]
    assert [name for name, role in offered(panel) if role == "subscribe"] == subscribe
    assert preview_role(window) is Role.SUBSCRIBE


# ------------------------------------------------------------------------------------- 5 default role
def test_a_control_from_the_palette_starts_sending_and_a_display_starts_showing(window, qtbot, plugins, sim_thread):
    assert role_preference(plugins.widget("std.slider"))[0] is Role.PUBLISH
    assert role_preference(plugins.widget("std.label")) == [Role.SUBSCRIBE]
    assert role_preference(plugins.widget("std.textview"))[0] is Role.SUBSCRIBE
    panel = open_from_palette(window, "std.textview")
    assert panel.draft.role is Role.SUBSCRIBE
    panel.cancel()

    panel = open_from_palette(window, "std.slider")
    snap(panel, "slider-1-opened")
    assert panel.role_combo.currentText() == "publish"
    pick(qtbot, panel.target_combo, "/speed_limit")
    snap(panel, "slider-2-speed-limit")
    assert panel.draft.binding.name == "/speed_limit" and panel.draft.role is Role.PUBLISH
    assert not panel.problems()
    tap(panel.place_button)
    [inst] = window.controller.canvas.widgets
    assert inst.binding.role is Role.PUBLISH and inst.binding.field_paths == ("data",)
    window.lock_button.click()
    hosted = window.host.hosted[inst.id]
    qtbot.waitUntil(lambda: hosted.view is not None and hosted.model is not None, timeout=10_000)
    hosted.model.publish_value(0.75)
    assert sim_thread.wait_for_published_sync("/speed_limit", lambda m: m["data"] == 0.75, timeout=10)


def test_choosing_a_target_only_another_role_fits_switches_to_that_role(window, qtbot):
    panel = open_from_palette(window, "std.switch")
    assert panel.draft.role is Role.PUBLISH and panel.target_label.text() == "Topic"
    assert ("/lights/set", "call") in offered(panel)  # offered, marked with the role it needs
    pick(qtbot, panel.target_combo, "/lights/set")
    assert panel.draft.role is Role.CALL and panel.role_combo.currentText() == "call"
    assert panel.target_label.text() == "Service"
    assert panel.draft.binding.name == "/lights/set" and panel.draft.binding.field_paths == ("request.data",)
    assert preview_role(window) is Role.CALL
    assert panel.target_combo.currentText().startswith("/lights/set") and "· to" not in panel.target_combo.currentText()


# ------------------------------------------------------------------------------------- 3 the field
def test_field_chooser_binds_another_field_from_a_topic(window, qtbot, sim_thread):
    panel = open_from_topic(window, "/battery", Role.SUBSCRIBE, "std.label")
    snap(panel, "label-1-settings")
    assert panel.field_combo.isVisible()
    entries = field_entries(panel)
    assert entries[0] == "percentage · float32" and "voltage · float32" in entries
    assert panel.field_combo.height() >= panel.target_combo.height()  # as touch-sized as its neighbours
    tap(panel.field_combo)
    popup = panel.field_combo.view()
    qtbot.waitUntil(popup.isVisible, timeout=5_000)
    assert popup.visualRect(panel.field_combo.model().index(1, 0)).height() >= touch_px()  # entries too
    QTest.keyClick(popup, QtCore.Qt.Key.Key_Escape)
    qtbot.waitUntil(lambda: not popup.isVisible(), timeout=5_000)
    assert panel.draft.binding.field_paths == ("percentage",)
    pick(qtbot, panel.field_combo, "voltage")
    snap(panel, "label-2-voltage")
    assert panel.draft.binding.field_paths == ("voltage",)
    assert window.preview.widget.binding.field_paths == ("voltage",)  # the preview was rebuilt on it
    tap(panel.place_button)
    [inst] = window.controller.canvas.widgets
    assert inst.binding.field_paths == ("voltage",)
    hosted = window.host.hosted[inst.id]
    qtbot.waitUntil(lambda: hosted.model is not None and hosted.model.state.count > 0, timeout=10_000)
    value = hosted.model.state.value.raw
    assert isinstance(value, float) and value > 5.0  # volts, not a 0..1 fraction
    assert value == pytest.approx(sim_thread.robot.voltage, abs=0.5)


def test_field_chooser_refills_from_the_topic_chosen_in_pathway_3(window, qtbot):
    panel = open_from_palette(window, "std.label")
    assert not panel.field_combo.isVisible()  # no topic yet: nothing to choose from
    pick(qtbot, panel.target_combo, "/battery")
    assert panel.field_combo.isVisible() and field_entries(panel)[0].startswith("percentage")
    pick(qtbot, panel.field_combo, "temperature")
    assert panel.draft.binding.field_paths == ("temperature",)
    pick(qtbot, panel.target_combo, "/depth")
    entries = field_entries(panel)
    assert entries and not any(e.startswith("percentage") for e in entries)
    assert panel.draft.binding.field_paths == (panel.field_combo.currentData(),) == ("range",)
    pick(qtbot, panel.target_combo, "/speed_limit")  # one field only: nothing to choose
    assert not panel.field_combo.isVisible() and panel.draft.binding.field_paths == ("data",)


def test_field_chooser_hidden_for_a_single_field_or_the_whole_message(window, qtbot):
    panel = open_from_topic(window, "/cmd_vel", Role.PUBLISH, "sensors.teleop")
    assert not panel.field_combo.isVisible() and panel.draft.binding.field_paths == ()
    panel.cancel()
    window.side.setCurrentWidget(window.services)
    tap_item(window.services.tree, window.services.tree.indexFromItem(window.services.item("/lights/set")))
    tap(window.add_panel.role_buttons[Role.CALL])
    tap_item(window.add_panel.candidates, window.add_panel.candidates.model().index(0, 0))
    assert not window.add_panel.field_combo.isVisible()


# ------------------------------------------------------------------------------------- 2 the wheel
def test_the_wheel_scrolls_the_form_instead_of_changing_values(window, qtbot):
    window.resize(1280, 700)
    panel = open_from_topic(window, "/battery", Role.SUBSCRIBE, "std.label")
    decimals = panel.form.editor("decimals")
    bar = scroll_area(panel).verticalScrollBar()
    qtbot.waitUntil(lambda: bar.maximum() > 0, timeout=5_000)
    bring_into_sight(panel, decimals)
    assert bar.value() < bar.maximum()
    before, scrolled = decimals.value(), bar.value()
    wheel(window, decimals, -1)
    assert decimals.value() == before == 2
    assert bar.value() > scrolled  # the form scrolled instead
    for editor in (decimals, panel.field_combo, panel.target_combo, panel.role_combo):
        assert editor.focusPolicy() == QtCore.Qt.FocusPolicy.StrongFocus  # a wheel does not focus it
    field_before = panel.field_combo.currentIndex()
    bar.setValue(0)
    bring_into_sight(panel, panel.field_combo)
    wheel(window, panel.field_combo, -1)
    assert panel.field_combo.currentIndex() == field_before
    # tapped first, it is the operator's: the wheel changes it
    bring_into_sight(panel, decimals)
    tap(decimals)
    assert decimals.hasFocus()
    wheel(window, decimals, -1)
    assert decimals.value() == 1


def test_the_wheel_over_a_compound_childs_settings_scrolls_too(window, qtbot):
    window.resize(1280, 700)
    panel = open_from_topic(window, "/cmd_vel", Role.PUBLISH, "std.compound")
    editor = panel.form.children_editors["children"]
    tap(editor.add_button)
    qtbot.waitUntil(lambda: editor.current_page == "fields", timeout=10_000)
    tap(editor.field_buttons["linear.x"])
    tap(editor.kind_buttons["std.slider"])
    form = editor.child_form
    spin = form.editor("maximum")
    bar = scroll_area(panel).verticalScrollBar()
    qtbot.waitUntil(lambda: bar.maximum() > 0, timeout=5_000)
    bring_into_sight(panel, spin)
    assert bar.value() < bar.maximum()
    before, scrolled = spin.value(), bar.value()
    wheel(window, spin, -1)
    assert spin.value() == before
    assert bar.value() > scrolled


# ------------------------------------------------------------------------------------- 4 scroll position
def test_a_new_settings_page_opens_at_its_top(window, qtbot):
    window.resize(1280, 700)
    panel = open_from_topic(window, "/battery", Role.SUBSCRIBE, "std.label")
    bar = scroll_area(panel).verticalScrollBar()
    qtbot.waitUntil(lambda: bar.maximum() > 0, timeout=5_000)
    for _ in range(6):
        wheel(window, scroll_area(panel).viewport(), -1)
    assert bar.value() > 0
    tap(_visible_button(panel, "cancelButton"))
    panel = open_from_palette(window, "std.slider")
    QtWidgets.QApplication.processEvents()
    assert bar.value() == 0
    viewport = scroll_area(panel).viewport()
    top = panel.target_combo.mapTo(viewport, QtCore.QPoint(0, 0)).y()
    assert 0 <= top and top + panel.target_combo.height() <= viewport.height()  # Topic chooser in sight

    for _ in range(6):  # a Compound scrolls its children into sight only when the operator opens a page
        wheel(window, viewport, -1)
    _visible_button(panel, "cancelButton").click()
    panel = open_from_topic(window, "/cmd_vel", Role.PUBLISH, "std.compound")
    qt_flushed(qtbot)
    assert bar.value() == 0


def _visible_button(panel: AddPanel, name: str) -> QtWidgets.QPushButton:
    [found] = [b for b in panel.findChildren(QtWidgets.QPushButton, name) if b.isVisible()]
    return found


# ------------------------------------------------------------------------------------- 6 layout
def test_headings_keep_names_whole_and_the_preview_fits_the_panel(window, qtbot):
    window.side.setCurrentWidget(window.services)
    tap_item(window.services.tree, window.services.tree.indexFromItem(window.services.item("/lights/set")))
    panel = window.add_panel
    tap(panel.role_buttons[Role.CALL])
    snap(panel, "call-lights-set")
    assert panel.widgets_title.text() == "Widgets that can call"
    name = panel.widgets_name
    assert name.text() == "/lights/set" and name.toolTip() == "/lights/set"
    assert name.height() < 2 * name.fontMetrics().height()  # one line, not broken at the slash
    name.set_name("/kingfisher/set_logger_level/with/a/very/long/name/that/cannot/fit")
    QtWidgets.QApplication.processEvents()
    assert "…" in name.text() and name.fontMetrics().horizontalAdvance(name.text()) <= name.contentsRect().width()
    assert name.toolTip().endswith("cannot/fit")
    panel.cancel()

    panel = open_from_topic(window, "/cmd_vel", Role.PUBLISH, "sensors.teleop")
    qtbot.waitUntil(lambda: panel.preview_frame is not None and panel.preview_frame.badge.isVisible(), timeout=10_000)
    snap(panel, "teleop-preview")
    frame = panel.preview_frame
    left = frame.mapTo(panel, QtCore.QPoint(0, 0)).x()
    assert left >= 0 and left + frame.width() <= panel.width()  # scaled to the panel, not cut
    # pinned above the settings (in sight while they are changed), and the settings keep most of the room
    assert frame.mapTo(panel, QtCore.QPoint(0, frame.height())).y() <= scroll_area(panel).mapTo(
        panel, QtCore.QPoint(0, 0)).y()
    assert frame.height() <= panel.height() // 3 + 1
    badge = frame.badge.geometry()
    assert "PREVIEW ONLY" in frame.badge.status
    assert frame.rect().contains(badge)
    assert frame.height() >= 0.8 * frame.width()  # square-ish like the 320 x 320 widget
    # the preview's model knows it is a preview (offline on purpose), so the pad says so, not "link down"
    model = window.host.hosted[frame.instance_id].model
    assert model.dry_run is True


# ------------------------------------------------------------------------------------- 7 after placing
def test_after_placing_the_panel_is_clean_for_the_next_add(window, qtbot):
    panel = open_from_topic(window, "/battery", Role.SUBSCRIBE, "std.label")
    pick(qtbot, panel.field_combo, "voltage")
    QTest.keyClicks(panel.title_edit, " V")
    tap(panel.place_button)
    assert not panel.isVisible()
    assert panel.draft is None and panel.form is None and panel.preview_frame is None
    assert window.preview.widget is None  # the preview stopped running
    qtbot.waitUntil(lambda: not panel.findChildren(QtWidgets.QWidget, "settingsForm"), timeout=5_000)
    assert panel.preview_slot.frame is None and not panel.findChildren(QtWidgets.QFrame, "widgetFrame")
    assert panel.target_combo.count() == panel.field_combo.count() == panel.role_combo.count() == 0
    assert panel.title_edit.text() == "" and panel.candidates.count() == 0

    panel = open_from_palette(window, "std.label")
    snap(panel, "label-palette-after-place")
    assert panel.title_edit.text() == "Label" and panel.target_combo.currentData() is None
    assert panel.draft.target is None and not panel.field_combo.isVisible()
    assert len(panel.findChildren(QtWidgets.QWidget, "settingsForm")) == 1
    assert "no topic chosen" in panel.problems()
