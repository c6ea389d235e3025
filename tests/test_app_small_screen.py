"""A small screen (a 1024x600 tablet): the window never grows past it, every toolbar button and the add panel
stay inside, the side panel makes room (its toggle; hidden by itself in Operate mode), canvas tabs readable.
Driven with taps against the sim, on the demo layout."""

from __future__ import annotations

import pytest
from app_helpers import settle, tap, tap_topic, window_maker
from qtpy import QtCore, QtGui, QtWidgets
from qtpy.QtTest import QTest

from rcon_core.app.main_window import MainWindow
from rcon_core.plugins import Role

pytestmark = pytest.mark.usefixtures("qapp")


@pytest.fixture
def make_window(qtbot, tmp_path, sim_thread, plugins):
    pytest.importorskip("rcon_widgets_std")
    yield from window_maker(qtbot, tmp_path, plugins, demo=True, url=sim_thread.url, topics=("/cmd_vel",))


def inside_window(window: MainWindow, widget: QtWidgets.QWidget) -> bool:
    rect = QtCore.QRect(widget.mapTo(window, QtCore.QPoint(0, 0)), widget.size())
    return window.rect().contains(rect)


def toolbar(window: MainWindow) -> list[QtWidgets.QWidget]:
    return [window.side_toggle, window.tabs, window.menu_button, window.canvas_buttons["undo"],
            window.canvas_buttons["redo"], window.edit_button, window.lock_button]


def assert_toolbar_inside(window: MainWindow) -> None:
    for widget in toolbar(window):
        assert widget.isVisible() and inside_window(window, widget), (widget.objectName(), widget.geometry())
    # the last segment is not flush with the window's edge
    right = window.lock_button.mapTo(window, QtCore.QPoint(window.lock_button.width(), 0)).x()
    assert window.width() - right >= 8


def assert_current_tab_readable(window: MainWindow) -> None:
    tabs = window.tabs
    i = tabs.currentIndex()
    rect = tabs.tabRect(i)
    assert tabs.rect().contains(rect), (rect, tabs.rect())
    scrollers = [b for b in tabs.findChildren(QtWidgets.QToolButton) if b.isVisible()]
    assert not any(b.geometry().intersects(rect) for b in scrollers), "the current tab is under the arrows"
    assert rect.width() >= tabs.tabSizeHint(i).width()  # its whole name, not "Can"


def test_the_window_opens_no_larger_than_the_screen(make_window):
    window = make_window(None)
    screen = window.screen().availableGeometry()
    assert window.width() <= screen.width() and window.height() <= screen.height(), (window.size(), screen)
    assert window.width() == min(1280, screen.width())


def test_a_1024x600_window_keeps_everything_inside_with_the_add_panel_open(make_window):
    window = make_window((1024, 600))
    tap(window.edit_button)
    settle()
    assert window.size() == QtCore.QSize(1024, 600)
    assert window.side.isVisible()  # Edit mode: topics to pick from
    assert_toolbar_inside(window)
    assert_current_tab_readable(window)

    tap_topic(window, "/cmd_vel")
    tap(window.add_panel.role_buttons[Role.PUBLISH])
    settle()
    assert window.size() == QtCore.QSize(1024, 600)  # the panel took its room, the window did not grow
    assert window.add_panel.isVisible() and inside_window(window, window.add_panel)
    assert window.add_panel.width() >= 300
    assert not window.side.isVisible()  # it gave its room to the panel
    assert_toolbar_inside(window)
    assert_current_tab_readable(window)
    # no room to show it beside the canvas and the panel: the toggle says so instead of growing the window
    assert not window.side_toggle.isEnabled()
    assert "No room" in window.side_toggle.toolTip()

    [cancel] = [b for b in window.add_panel.findChildren(QtWidgets.QPushButton, "cancelButton") if b.isVisible()]
    tap(cancel)
    settle()
    assert window.side.isVisible() and window.size() == QtCore.QSize(1024, 600)


def test_operate_mode_on_a_small_window_hides_the_side_panel_and_its_toggle_brings_it_back(make_window):
    window = make_window((1024, 600))
    tap(window.lock_button)  # Operate
    settle()
    assert window.controller.canvas.locked
    assert not window.side.isVisible()  # the canvas gets the room
    assert_toolbar_inside(window)
    canvas_width = window.controller.surface.scroll_area.viewport().width()
    assert canvas_width > 900
    tap(window.side_toggle)
    settle()
    assert window.side.isVisible() and window.size() == QtCore.QSize(1024, 600)
    assert_toolbar_inside(window)
    tap(window.side_toggle)
    settle()
    assert not window.side.isVisible()
    tap(window.edit_button)  # back to Edit mode: the side panel is back for adding
    settle()
    assert window.side.isVisible()


def test_canvas_tabs_stay_readable_with_the_add_panel_open_at_1280(make_window):
    window = make_window((1280, 800))
    tap(window.edit_button)
    for name in ("Docking", "Cameras"):
        window.controller.add_canvas(name)
    window.switch_canvas(0)
    tap_topic(window, "/battery")
    tap(window.add_panel.role_buttons[Role.SUBSCRIBE])
    settle()
    assert window.size() == QtCore.QSize(1280, 800)
    assert inside_window(window, window.add_panel)
    assert_toolbar_inside(window)
    assert_current_tab_readable(window)
    window.switch_canvas(2)
    settle()
    assert_current_tab_readable(window)


def test_the_stylesheet_parses_without_a_warning(qtbot):
    """Qt prints "Could not parse application stylesheet" (and keeps going unstyled) on a QSS error."""
    from rcon_core.app.theme import stylesheet

    messages: list[str] = []

    def handler(_mode, _context, text) -> None:
        messages.append(text)

    previous = QtCore.qInstallMessageHandler(handler)
    try:
        widget = QtWidgets.QWidget()
        qtbot.addWidget(widget)
        QtWidgets.QVBoxLayout(widget).addWidget(QtWidgets.QPushButton("x"))
        widget.setStyleSheet(stylesheet(touch=48))
        widget.show()
        widget.ensurePolished()
        QtWidgets.QApplication.processEvents()
    finally:
        QtCore.qInstallMessageHandler(previous)
    assert not [m for m in messages if "parse" in m.lower()], messages
    # and a broken sheet would be caught the same way
    broken: list[str] = []
    previous = QtCore.qInstallMessageHandler(lambda _m, _c, text: broken.append(text))
    try:
        other = QtWidgets.QPushButton("y")
        qtbot.addWidget(other)
        other.setStyleSheet(stylesheet(touch=48) + "\nQPushButton { color: ")
        other.show()
        other.ensurePolished()
        QtWidgets.QApplication.processEvents()
    finally:
        QtCore.qInstallMessageHandler(previous)
    assert [m for m in broken if "parse" in m.lower()], broken
    assert isinstance(QtGui.QGuiApplication.instance(), QtWidgets.QApplication)


@pytest.mark.parametrize("size", [(1280, 800), (1024, 600)])
def test_the_add_panel_shows_its_preview_without_scrolling(make_window, qtbot, size):
    from app_helpers import choose_kind, snap

    window = make_window(size)
    tap(window.edit_button)
    tap_topic(window, "/cmd_vel")
    panel = choose_kind(window, Role.PUBLISH, "std.slider")
    qtbot.waitUntil(lambda: panel.preview_frame is not None and panel.preview_frame.isVisible(), timeout=10_000)
    settle()
    snap(window, f"add-panel-preview-{size[0]}")
    frame = panel.preview_frame
    assert inside_window(window, frame)  # all of it in sight, not below the fold of the settings
    assert window.childAt(frame.mapTo(window, frame.rect().center())) in (frame, *frame.findChildren(QtWidgets.QWidget))
    scroll = panel.settings_scroll
    assert scroll.verticalScrollBar().value() == 0  # nothing scrolled to see it
    # the settings below keep room for a few rows, and Place stays in sight
    assert scroll.viewport().height() >= 3 * 48, scroll.viewport().height()
    assert inside_window(window, panel.place_button) and panel.place_button.isVisible()


@pytest.mark.parametrize("size", [(1280, 800), (1024, 600)])
def test_the_demo_fits_without_scrolling_with_a_camera_beside_the_drive_pad(make_window, qtbot, sim_thread, size):
    from app_helpers import snap

    window = make_window(size)
    settle()
    scroll = window.controller.surface.scroll_area
    for index, name in enumerate(("Drive", "Cameras", "Sensors", "Video")):
        window.switch_canvas(index)
        settle()
        assert window.tabs.tabText(index) == name
        scroll = window.controller.surface.scroll_area
        viewport = scroll.viewport()
        hosted = {w.title: window.host.hosted[w.id] for w in window.controller.canvas.widgets}
        for title, h in hosted.items():  # every widget in sight, nothing to scroll to
            corner = h.frame.mapTo(viewport, QtCore.QPoint(0, 0))
            assert viewport.rect().contains(QtCore.QRect(corner, h.frame.size())), (name, title, size)
        assert scroll.verticalScrollBar().maximum() == 0 and scroll.horizontalScrollBar().maximum() == 0, name
        snap(window, f"demo-{name.lower()}-{size[0]}")
    window.switch_canvas(0)
    settle()
    hosted = {w.title: window.host.hosted[w.id] for w in window.controller.canvas.widgets}
    camera, pad = hosted["Front camera"].frame, hosted["Drive"].frame
    assert camera.geometry().right() < pad.geometry().left()  # side by side...
    assert camera.geometry().top() == pad.geometry().top()  # ...on the same row
    # watching and driving at once: a finger on the pad drives while the camera stays in sight
    drive = hosted["Drive"]  # its view may be built after the switch: read it once it is there
    qtbot.waitUntil(lambda: drive.view is not None and drive.view.isVisible() and drive.model.running,
                    timeout=10_000)
    view = drive.view
    centre = view.rect().center()
    QTest.mousePress(view, QtCore.Qt.MouseButton.LeftButton, QtCore.Qt.KeyboardModifier.NoModifier, centre)
    QTest.mouseMove(view, centre - QtCore.QPoint(0, 60))
    moving = sim_thread.wait_for_published_sync("/cmd_vel", lambda m: m["linear"]["x"] > 0.1, timeout=10)
    assert moving["linear"]["x"] > 0.1
    QTest.mouseRelease(view, QtCore.Qt.MouseButton.LeftButton, QtCore.Qt.KeyboardModifier.NoModifier,
                       centre - QtCore.QPoint(0, 60))
    sim_thread.wait_for_published_sync("/cmd_vel", lambda m: m["linear"]["x"] == 0, timeout=10)  # the stop
    assert camera.isVisible()
    qtbot.waitUntil(lambda: hosted["Front camera"].model.state.count > 0, timeout=10_000)  # and it shows
