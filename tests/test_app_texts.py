"""Texts a person must be able to read: frame titles cut with "…" (never mid-letter, never under the status
badge), the add panel's hint wrapped, text settings wide enough for a message."""

from __future__ import annotations

import pytest
from app_helpers import choose_kind, entry_point_plugins, tap, tap_item, window_session
from qtpy import QtCore, QtGui, QtWidgets

from rcon_core.app.theme import stylesheet
from rcon_core.app.widget_frame import WidgetFrame

pytestmark = pytest.mark.usefixtures("qapp")


def _text_columns(frame: WidgetFrame) -> tuple[int, int]:
    """The first and last pixel column (frame coordinates) where the title's white text is painted, left
    of the badge when one shows."""
    image = frame.grab().toImage()
    title = frame.title.geometry()
    stop = frame.badge.x() if frame.badge.isVisible() else title.right()
    cols = [x for x in range(title.left(), stop)
            if any(QtGui.QColor(image.pixel(x, y)).lightness() > 200
                   for y in range(title.top() + 2, title.bottom() - 1))]
    assert cols, "no title text painted"
    return cols[0], cols[-1]


@pytest.fixture
def frame(qtbot):
    surface = QtWidgets.QWidget()
    surface.setStyleSheet(stylesheet(touch=48))
    surface.resize(400, 200)
    frame = WidgetFrame("w-1", "Battery voltage, main pack", surface)
    frame.set_view(QtWidgets.QLabel("24.36 V"))
    frame.setGeometry(16, 16, 160, 112)
    qtbot.addWidget(surface)
    surface.show()
    yield frame  # the surface (its parent) lives until the test ends
    surface.close()


@pytest.mark.parametrize("editable", [True, False])
def test_a_long_frame_title_is_cut_with_an_ellipsis_and_shown_whole_in_its_tooltip(frame, editable):
    frame.set_editable(editable)
    QtWidgets.QApplication.processEvents()
    shown = frame.title.text()
    assert shown.endswith("…") and "Battery voltage, main pack".startswith(shown[:-1]) and len(shown) >= 4, shown
    assert frame.title.toolTip() == "Battery voltage, main pack"
    start, end = _text_columns(frame)
    # what is drawn is the whole elided text: nothing clipped at the title's right edge
    advance = frame.title.fontMetrics().horizontalAdvance(shown)
    assert start + advance <= frame.title.geometry().right() + 1 - 4
    # a frame wide enough shows the whole title again
    frame.resize(600, 112)
    QtWidgets.QApplication.processEvents()
    assert frame.title.text() == "Battery voltage, main pack"


def test_the_title_leaves_room_for_the_status_badge(frame):
    frame.resize(300, 112)
    QtWidgets.QApplication.processEvents()
    assert frame.title.text() == "Battery voltage, main pack"
    frame.badge.show_status("down", "LINK DOWN")
    QtWidgets.QApplication.processEvents()
    shown = frame.title.text()
    assert shown.endswith("…"), shown
    start, end = _text_columns(frame)
    advance = frame.title.fontMetrics().horizontalAdvance(shown)
    assert start + advance < frame.badge.x(), (start, advance, frame.badge.geometry())
    frame.badge.show_status("", "")  # the link is back: the whole title again
    QtWidgets.QApplication.processEvents()
    assert frame.title.text() == "Battery voltage, main pack"
    assert frame.title.geometry().contains(QtCore.QPoint(frame.width() // 2, frame.title.y() + 2))


# ------------------------------------------------------------------------------------- the add panel
@pytest.fixture(scope="module")
def plugins():
    return entry_point_plugins()


@pytest.fixture
def window(qtbot, tmp_path, sim_thread, plugins):
    pytest.importorskip("rcon_widgets_std")
    yield from window_session(qtbot, tmp_path / "config", plugins, url=sim_thread.url,
                              topics=("/cmd_vel",), services=("/dock",))


def tap_at(widget: QtWidgets.QWidget, pos: QtCore.QPoint) -> None:
    from qtpy.QtTest import QTest

    QTest.mouseClick(widget, QtCore.Qt.MouseButton.LeftButton, QtCore.Qt.KeyboardModifier.NoModifier, pos)


def pick_widget(window, catalog, name: str, role, kind: str):
    """Tap ``name`` in the Topics or Services list, the role, then the widget ``kind``."""
    tabs = window.side.tabBar()
    tap_at(tabs, tabs.tabRect(window.side.indexOf(catalog)).center())
    tap_item(catalog.tree, catalog.tree.indexFromItem(catalog.item(name)))
    panel = choose_kind(window, role, kind)
    assert panel.stack.currentWidget() is panel.settings_page
    return panel


def fits(widget: QtWidgets.QWidget, text: str, flags: int) -> bool:
    """Whether ``text`` drawn with ``flags`` stays inside ``widget``'s contents."""
    room = widget.contentsRect()
    drawn = widget.fontMetrics().boundingRect(room, flags, text)
    return room.contains(drawn)


def test_the_not_ready_hint_wraps_and_field_choices_show_their_type_uncut(window, qtbot):
    from rcon_core.plugins import Role

    panel = pick_widget(window, window.topics, "/cmd_vel", Role.PUBLISH, "std.compound")
    QtWidgets.QApplication.processEvents()
    handle = panel.drag_handle
    assert handle.text() == "Not ready: add at least one child widget"
    centred_wrapped = int(QtCore.Qt.AlignmentFlag.AlignCenter) | int(QtCore.Qt.TextFlag.TextWordWrap)
    assert fits(handle, handle.text(), centred_wrapped), (handle.contentsRect(), handle.text())
    # the field page of "+ Add child": every choice readable with its type, the whole message's too
    editor = panel.form.children_editors["children"]
    tap(editor.add_button)
    qtbot.waitUntil(lambda: editor.current_page == "fields", timeout=10_000)
    QtWidgets.QApplication.processEvents()
    whole = editor.field_buttons[""]
    assert "Twist" in whole.text() and "whole message" in whole.text(), whole.text()
    for path, button in editor.field_buttons.items():
        lines = button.text().split("\n")
        widest = max(button.fontMetrics().horizontalAdvance(line) for line in lines)
        assert widest <= button.width() - 24, (path, button.text(), button.width())


def test_message_text_settings_are_multi_line_and_take_the_rows_full_width(window):
    from rcon_core.app.settings_form import TextBlock
    from rcon_core.plugins import Role

    panel = pick_widget(window, window.services, "/dock", Role.CALL, "std.button")
    QtWidgets.QApplication.processEvents()
    form = panel.form
    row = panel.settings_scroll.viewport().width()
    payload = form.editor("payload")
    assert isinstance(payload, TextBlock)  # YAML or JSON: more than one line
    assert payload.height() >= 2 * payload.fontMetrics().lineSpacing()
    for name in ("payload", "release_payload"):  # messages: the row's full width
        editor = form.editor(name)
        assert isinstance(editor, TextBlock) and editor.width() >= row * 0.9, (name, editor.width(), row)
    for name in ("text", "release_service", "release_type"):  # a name or a type: room for one
        editor = form.editor(name)
        assert editor.width() >= 240, (name, editor.width(), row)
    # typing a request: the panel's draft gets it as typed, over several lines
    payload.setFocus()
    from qtpy.QtTest import QTest

    QTest.keyClicks(payload, "{}")
    assert panel.draft.settings.payload == "{}"


def test_a_new_widget_is_titled_after_what_it_is_bound_to_and_the_title_stays_editable(window, qtbot):
    from qtpy.QtTest import QTest

    from rcon_core.plugins import Role

    panel = pick_widget(window, window.topics, "/battery", Role.SUBSCRIBE, "std.label")
    assert panel.title_edit.text() == "battery · percentage"
    panel.choose_field("voltage")  # another field: the title follows
    assert panel.title_edit.text() == "battery · voltage"
    assert panel.preview_frame.title.full_title == "battery · voltage"
    tap(panel.place_button)
    placed = window.controller.canvas.widgets[-1]
    assert placed.title == "battery · voltage"
    assert window.controller.surface.frames[placed.id].title.full_title == "battery · voltage"

    # a camera: what it shows, not its topic's plumbing
    panel = pick_widget(window, window.topics, "/camera/front/image_raw", Role.SUBSCRIBE, "sensors.image")
    assert panel.title_edit.text() == "front camera"
    # typed by the operator: kept, also when the field or target changes afterwards
    panel.title_edit.selectAll()
    panel.title_edit.setFocus()
    QTest.keyClicks(panel.title_edit, "Bow")
    assert panel.draft.title == "Bow"
    tap(panel.place_button)
    assert window.controller.canvas.widgets[-1].title == "Bow"

    # a service: its own name, without slashes like a topic's
    panel = pick_widget(window, window.services, "/lights/set", Role.CALL, "std.button")
    assert panel.title_edit.text() == "lights set"
