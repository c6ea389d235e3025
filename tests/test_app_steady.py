"""Nothing under the operator's finger moves on its own, on the real window against the sim: a notice
floats over the bottom edge instead of pushing the window's content down; a preview dropped while the add
panel is open stays where it was dropped when the panel closes.

``RCON_SCREENSHOTS=DIR`` writes a PNG of the window at each step.
"""

from __future__ import annotations

import pytest
from app_helpers import (
    LEFT,
    NO_MOD,
    choose_kind,
    settle,
    snap,
    tap,
    tap_topic,
    window_maker,
)
from qtpy import QtCore, QtGui, QtWidgets
from qtpy.QtTest import QTest

from rcon_core.app.canvas_surface import DRAFT_MIME
from rcon_core.plugins import Role

pytestmark = pytest.mark.usefixtures("qapp")
pytest.importorskip("rcon_widgets_std")
pytest.importorskip("rcon_widgets_sensors")


@pytest.fixture
def make_window(qtbot, tmp_path, sim_thread, plugins):
    yield from window_maker(qtbot, tmp_path, plugins, demo=True, url=sim_thread.url, wait_connected=True,
                            topics=("/battery",))


def where(window: QtWidgets.QWidget, widget: QtWidgets.QWidget) -> QtCore.QRect:
    return QtCore.QRect(widget.mapTo(window, QtCore.QPoint(0, 0)), widget.size())


@pytest.mark.parametrize("size", [(1280, 800), (1024, 600)])
def test_a_notice_moves_nothing_under_the_finger(make_window, qtbot, size):
    window = make_window(size)
    settle()
    if not window.side.isVisible():
        tap(window.side_toggle)  # a small screen in Operate mode: the operator brings the topics back
        settle()
    frames = [window.host.hosted[w.id].frame for w in window.controller.canvas.widgets]
    controls = [window.side_toggle, window.tabs, window.edit_button, window.lock_button, window.topics.tree,
                *frames]
    before = [where(window, w) for w in controls]
    tap_topic(window, "/battery")  # in Operate mode: the notice offers to switch to Edit mode
    notice = window.notice
    qtbot.waitUntil(notice.isVisible, timeout=5_000)
    settle()
    snap(window, f"notice-{size[0]}")
    assert [where(window, w) for w in controls] == before  # nothing moved
    # it floats over the bottom edge of the canvas, leaving the bars and the side panel uncovered
    rect = where(window, notice)
    canvas = where(window, window.controller.surface.scroll_area)
    assert window.rect().contains(rect) and rect.bottom() == window.rect().bottom() == canvas.bottom()
    assert rect.top() > where(window, window.lock_button).bottom()
    assert rect.left() == canvas.left() and rect.width() >= canvas.width()
    assert not rect.intersects(where(window, window.side))
    [action] = notice.buttons.values()
    assert window.rect().contains(where(window, action))
    tap(action)  # "Switch to Edit mode": taken at once, and the panel opens for /battery
    settle()
    assert not notice.isVisible() and not window.controller.canvas.locked
    assert window.add_panel.isVisible()


def test_a_notice_follows_the_window_size_and_leaves_the_add_panel_uncovered(make_window, qtbot):
    window = make_window((1280, 800), demo=False)
    tap(window.edit_button)
    window.notice.show_notice("⚠ The layout could not be saved: disk full",
                              actions=[("Start a new layout", lambda: None)])
    settle()
    assert where(window, window.notice).bottom() == window.rect().bottom()
    window.resize(1024, 600)
    settle()
    rect = where(window, window.notice)
    assert rect.bottom() == window.rect().bottom()
    assert rect.width() == where(window, window.controller.surface.scroll_area).width()
    tap_topic(window, "/battery")
    panel = choose_kind(window, Role.SUBSCRIBE, "std.label")
    settle()
    snap(window, "notice-with-add-panel")
    rect = where(window, window.notice)
    for button in (panel.place_button, *panel.findChildren(QtWidgets.QPushButton, "cancelButton")):
        if button.isVisible():  # the panel's buttons stay where the finger expects them, uncovered
            assert not rect.intersects(where(window, button)), button.objectName()
    tap(window.notice.dismiss_button)
    assert not window.notice.isVisible()


def send_drop(surface: QtWidgets.QWidget, at: QtCore.QPoint) -> None:
    """What Qt delivers to the canvas when the operator lets go of the dragged preview over it."""
    mime = QtCore.QMimeData()
    mime.setData(DRAFT_MIME, QtCore.QByteArray(b"draft"))
    for cls in (QtGui.QDragEnterEvent, QtGui.QDragMoveEvent):
        QtWidgets.QApplication.sendEvent(surface, cls(at, QtCore.Qt.DropAction.CopyAction, mime, LEFT, NO_MOD))
    QtWidgets.QApplication.sendEvent(surface, QtGui.QDropEvent(QtCore.QPointF(at), QtCore.Qt.DropAction.CopyAction,
                                                               mime, LEFT, NO_MOD))


@pytest.mark.parametrize("size", [(1280, 800), (1024, 600)])
def test_a_dropped_preview_stays_where_it_was_dropped_when_the_panel_closes(make_window, qtbot, size):
    window = make_window(size, demo=False)
    tap(window.edit_button)
    settle()
    tap_topic(window, "/battery")
    panel = choose_kind(window, Role.SUBSCRIBE, "std.label")
    qtbot.waitUntil(lambda: panel.drag_handle.isEnabled(), timeout=5_000)
    settle()
    side_before = window.side.isVisible()
    surface = window.controller.surface
    viewport = surface.scroll_area.viewport()
    aimed = QtCore.QPoint(120, 100)  # where the finger lets go, in the canvas's view
    finger = viewport.mapTo(window, aimed)
    send_drop(surface, surface.mapFrom(viewport, aimed))
    [inst] = window.controller.canvas.widgets
    frame = window.host.hosted[inst.id].frame
    placed = where(window, frame)
    assert (placed.topLeft() - finger).manhattanLength() <= 32  # under the finger (snapped to the grid)
    for _ in range(5):
        settle()
    snap(window, f"dropped-{size[0]}")
    assert not panel.isVisible()
    assert where(window, frame) == placed  # the panel closed and nothing moved sideways
    assert window.side.isVisible() == side_before  # the side panel did not come back by itself...
    if not side_before:
        tap(window.side_toggle)  # ...the operator brings it back when wanted
        settle()
        assert window.side.isVisible()


@pytest.mark.parametrize("mode", ["operate", "edit"])
def test_dragging_the_canvas_background_with_the_mouse_scrolls_it(make_window, qtbot, mode):
    window = make_window((1024, 600))
    window.resize(1024, 420)  # the demo fits 1024x600: a shorter window makes its canvas scroll
    if mode == "edit":
        tap(window.edit_button)
    settle()
    surface = window.controller.surface
    bar = surface.scroll_area.verticalScrollBar()
    qtbot.waitUntil(lambda: bar.maximum() > 100, timeout=5_000)
    content = surface.content_rect()
    start = QtCore.QPoint(content.right() + 40, 300)  # the background right of the widgets
    assert surface.childAt(start) in (None, surface.placeholder)
    frames = {w.id: where(window, window.host.hosted[w.id].frame) for w in window.controller.canvas.widgets}
    layout = {w.id: w.geometry for w in window.controller.canvas.widgets}
    QTest.mousePress(surface, LEFT, NO_MOD, start)
    for step in range(1, 11):  # the hand moves up 100 px: the canvas follows it
        QTest.mouseMove(surface, start - QtCore.QPoint(0, 10 * step) + QtCore.QPoint(0, bar.value()))
    QTest.mouseRelease(surface, LEFT, NO_MOD, start - QtCore.QPoint(0, 100) + QtCore.QPoint(0, bar.value()))
    settle()
    assert 90 <= bar.value() <= 110, bar.value()
    snap(window, f"panned-{mode}")
    # the layout did not change: only the view moved
    assert {w.id: w.geometry for w in window.controller.canvas.widgets} == layout
    moved = {i: where(window, window.host.hosted[i].frame).translated(0, bar.value()) for i in frames}
    assert moved == frames
