"""Where the keyboard goes: never to the robot URL unless it is tapped (a key would replace the URL), back to
the window after a confirm dialog (Ctrl+Q, Ctrl+Z work at once). Driven with taps and keys against the sim."""

from __future__ import annotations

import pytest
from app_helpers import choose_kind, tap, tap_topic, window_session
from qtpy import QtCore, QtWidgets
from qtpy.QtTest import QTest

from rcon_core.app.main_window import MainWindow
from rcon_core.plugins import Role

pytestmark = pytest.mark.usefixtures("qapp")


@pytest.fixture
def window(qtbot, tmp_path, sim_thread, plugins):
    pytest.importorskip("rcon_widgets_std")
    yield from window_session(qtbot, tmp_path / "config", plugins, url=sim_thread.url, activate=True,
                              topics=("/cmd_vel",))


def url_text(window: MainWindow) -> str:
    return window.connection.url.currentText()


def assert_typing_leaves_the_url_alone(window: MainWindow) -> None:
    """A key typed now (where the keyboard is) does not reach the robot URL."""
    url = window.connection.url
    assert not url.hasFocus() and not url.lineEdit().hasFocus(), QtWidgets.QApplication.focusWidget()
    before = url_text(window)
    QTest.keyClicks(QtWidgets.QApplication.focusWidget() or window, "x")
    assert url_text(window) == before


def test_switch_to_edit_mode_on_the_notice_keeps_the_keyboard_off_the_url(window, qtbot):
    tap(window.lock_button)  # Operate mode
    assert window.controller.canvas.locked
    tap_topic(window, "/battery")
    switch = window.notice.buttons["Switch to Edit mode"]
    tap(switch)
    assert not window.controller.canvas.locked and window.add_panel.isVisible()
    QtWidgets.QApplication.processEvents()
    focus = QtWidgets.QApplication.focusWidget()
    assert focus is not None and window.add_panel.isAncestorOf(focus), focus  # on the panel just opened
    assert_typing_leaves_the_url_alone(window)


def test_add_child_keeps_the_keyboard_in_the_children_editor(window, qtbot):
    tap_topic(window, "/cmd_vel")
    panel = choose_kind(window, Role.PUBLISH, "std.compound")
    editor = panel.form.children_editors["children"]
    panel.settings_scroll.ensureWidgetVisible(editor.add_button)
    tap(editor.add_button)
    qtbot.waitUntil(lambda: editor.current_page == "fields", timeout=10_000)  # typedefs from the robot
    QtWidgets.QApplication.processEvents()
    focus = QtWidgets.QApplication.focusWidget()
    assert focus is not None and editor.pages["fields"].isAncestorOf(focus), focus
    assert_typing_leaves_the_url_alone(window)
    # the same after picking a field (the field page goes away too)
    tap(editor.field_buttons["linear.x"])
    assert editor.current_page == "kinds"
    focus = QtWidgets.QApplication.focusWidget()
    assert focus is not None and editor.pages["kinds"].isAncestorOf(focus), focus
    assert_typing_leaves_the_url_alone(window)


def test_tab_never_lands_on_the_url_but_a_tap_does(window):
    window.controller.surface.setFocus()
    for _ in range(40):
        QTest.keyClick(QtWidgets.QApplication.focusWidget() or window, QtCore.Qt.Key.Key_Tab)
        assert not window.connection.url.lineEdit().hasFocus()
    line = window.connection.url.lineEdit()
    tap(line)
    assert line.hasFocus()
    QTest.keyClick(line, QtCore.Qt.Key.Key_End)
    QTest.keyClicks(line, "0")
    assert url_text(window).endswith("0")


def test_after_cancel_on_a_confirm_dialog_the_keyboard_is_back_on_the_window(window, qtbot):
    window.controller.add_canvas("Second")
    window.switch_canvas(0)
    # a canvas with a widget asks first
    tap_topic(window, "/battery")
    tap(window.add_panel.role_buttons[Role.SUBSCRIBE])
    tap(window.add_panel.candidates.viewport(), window.add_panel.candidates.visualRect(
        window.add_panel.candidates.model().index(0, 0)).center())
    tap(window.add_panel.place_button)
    assert len(window.controller.canvas.widgets) == 1
    window.canvas_actions["delete"].trigger()
    box = window.confirm_dialog
    qtbot.waitUntil(box.isVisible)
    # what a window manager may leave behind (seen on X11): the window no longer remembers a focus widget,
    # so when the dialog goes the keyboard goes nowhere and Ctrl+Q does nothing until a tap
    remembered = window.focusWidget()
    if remembered is not None:
        remembered.clearFocus()
    assert window.focusWidget() is None
    tap(box.findChild(QtWidgets.QPushButton, "confirmCancel"))
    qtbot.waitUntil(lambda: not box.isVisible())
    qtbot.waitUntil(lambda: QtWidgets.QApplication.activeWindow() is window, timeout=5_000)
    focus = QtWidgets.QApplication.focusWidget()
    assert focus is not None and window.isAncestorOf(focus), focus
    assert len(window.controller.workspace.canvases) == 2  # cancelled: nothing deleted
    # Ctrl+Z right away works (undoes the place), and so does Ctrl+Q
    QTest.keyClick(focus, QtCore.Qt.Key.Key_Z, QtCore.Qt.KeyboardModifier.ControlModifier)
    assert window.controller.canvas.widgets == []
    QTest.keyClick(QtWidgets.QApplication.focusWidget() or window, QtCore.Qt.Key.Key_Q,
                   QtCore.Qt.KeyboardModifier.ControlModifier)
    qtbot.waitUntil(lambda: not window.isVisible(), timeout=5_000)
