"""Canvases and editing: hot swap on the robot's side, move, pinch-resize, lock, restart, link loss."""

from __future__ import annotations

import time

import pytest
from app_helpers import Pinch
from app_helpers import open_window as open_app_window
from qtpy import QtCore, QtGui, QtWidgets
from qtpy.QtTest import QTest
from test_app_window import make_plugins, robot  # noqa: F401 - fixture re-used

from rcon_core.app.draft import Draft, Target
from rcon_core.app.geometry import snap
from rcon_core.app.main_window import MainWindow
from rcon_core.bridge import ConnectionState
from rcon_core.plugins import Role
from rcon_core.testing import qt_flushed

pytestmark = pytest.mark.usefixtures("qapp")


def open_window(qtbot, config_dir, url: str | None) -> MainWindow:
    """The probe plugin's window at the offscreen screen's size, connected to ``url`` if given."""
    return open_app_window(qtbot, config_dir, make_plugins(), url=url, size=None, wait_connected=True)


def rect_of(window: MainWindow, widget_id: str) -> tuple[int, int, int, int]:
    """Where the document has the widget (what is saved)."""
    _canvas, widget = window.controller.workspace.find_widget(widget_id)
    g = widget.geometry
    return (int(g.x), int(g.y), int(g.w), int(g.h))


def add_probe(window: MainWindow, topic: str, type_name: str, path: str, at=None):
    spec = window.plugins.widget("apptest.probe")
    settings = spec.make_settings({"caption": topic})
    draft = Draft(spec, Role.SUBSCRIBE, Target(topic, type_name, (path,)), settings, "Probe")
    return window.controller.add_draft(draft, at)


def test_switching_canvas_stops_and_starts_subscriptions(qtbot, tmp_path, robot):  # noqa: F811
    window = open_window(qtbot, tmp_path, robot.url)
    try:
        add_probe(window, "/battery", "sensor_msgs/BatteryState", "percentage")
        window.controller.add_canvas("Lights")
        assert window.tabs.count() == 2 and window.tabs.tabText(1) == "Lights"
        add_probe(window, "/lights/state", "std_msgs/Bool", "data")
        qtbot.waitUntil(lambda: robot.topic_subscriber_count("/lights/state") == 1, timeout=10_000)
        qtbot.waitUntil(lambda: robot.topic_subscriber_count("/battery") == 0, timeout=10_000)
        window.switch_canvas(0)  # the tab bar drives the controller
        qtbot.waitUntil(lambda: robot.topic_subscriber_count("/battery") == 1, timeout=10_000)
        qtbot.waitUntil(lambda: robot.topic_subscriber_count("/lights/state") == 0, timeout=10_000)
        # duplicate, rename and delete canvases
        index = window.controller.duplicate_canvas(0)
        assert window.controller.workspace.canvases[index].name == "Main copy"
        window.controller.rename_canvas(index, "Spare")
        with pytest.raises(ValueError, match="canvas named 'Lights' already exists"):
            window.controller.rename_canvas(index, "Lights")
        assert window.tabs.tabText(index) == "Spare"
        window.controller.delete_canvas(index)
        assert [c.name for c in window.controller.workspace.canvases] == ["Main", "Lights"]
        qtbot.waitUntil(lambda: robot.topic_subscriber_count("/battery") == 1, timeout=10_000)
    finally:
        window.shutdown()


def test_move_pinch_and_lock(qtbot, tmp_path, robot):  # noqa: F811
    window = open_window(qtbot, tmp_path, None)
    try:
        window.resize(1280, 800)
        inst = add_probe(window, "/battery", "sensor_msgs/BatteryState", "percentage", QtCore.QPoint(96, 96))
        frame = window.controller.surface.frames[inst.id]
        shield = frame.shield
        start = frame.geometry()
        # drag with the mouse: moves and snaps to the grid
        press = QtCore.QPoint(frame.width() // 2, frame.height() // 2)
        QTest.mousePress(shield, QtCore.Qt.MouseButton.LeftButton, QtCore.Qt.KeyboardModifier.NoModifier, press)
        for step in range(1, 6):
            QTest.mouseMove(shield, press + QtCore.QPoint(step * 20, step * 10))
        QTest.mouseRelease(shield, QtCore.Qt.MouseButton.LeftButton, QtCore.Qt.KeyboardModifier.NoModifier,
                           press + QtCore.QPoint(100, 50))
        moved = rect_of(window, inst.id)
        assert (moved[0], moved[1]) != (start.x(), start.y())
        assert moved[0] % 16 == 0 and moved[1] % 16 == 0
        # pinch: the gesture handler fed a QPinchGesture-equivalent (started, updated, finished)
        before = frame.geometry()
        for state, scale in ((QtCore.Qt.GestureState.GestureStarted, 1.0),
                             (QtCore.Qt.GestureState.GestureUpdated, 1.5),
                             (QtCore.Qt.GestureState.GestureFinished, 2.0)):
            frame.pinch_gesture(Pinch(state, scale))
        after = rect_of(window, inst.id)
        assert after[2] > before.width() * 1.5 and after[3] > before.height() * 1.5
        # pinching far out never puts the widget where it cannot be reached
        frame.apply_pinch(20.0)
        assert window.controller.surface.rect().contains(frame.geometry())
        # corner handle resize (mouse): shrink from bottom-right
        geo = frame.geometry()
        corner = frame.handle_rects()["br"].center()
        QTest.mousePress(shield, QtCore.Qt.MouseButton.LeftButton, QtCore.Qt.KeyboardModifier.NoModifier, corner)
        QTest.mouseMove(shield, corner - QtCore.QPoint(100, 60))
        QTest.mouseRelease(shield, QtCore.Qt.MouseButton.LeftButton, QtCore.Qt.KeyboardModifier.NoModifier,
                           corner - QtCore.QPoint(100, 60))
        assert frame.width() < geo.width() and frame.width() >= frame.min_size().width()
        # touch targets are at least 48 px
        assert frame.handle_size() >= 48 and window.lock_button.height() >= 48
        # context menu: duplicate through it
        menu = frame.request_menu(QtCore.QPoint(10, 10))
        [dup] = [a for a in menu.actions() if a.objectName() == "duplicate"]
        dup.trigger()
        menu.close()
        assert len(window.controller.canvas.widgets) == 2
        # lock: nothing moves, no menu, no deletes; the lock is saved
        tap = window.lock_button
        QTest.mouseClick(tap, QtCore.Qt.MouseButton.LeftButton)
        assert window.controller.canvas.locked
        assert not shield.isVisible()
        assert frame.request_menu(QtCore.QPoint(10, 10)) is None
        pos = frame.pos()
        frame.apply_pinch(0.5)
        QTest.mousePress(frame, QtCore.Qt.MouseButton.LeftButton)
        QTest.mouseMove(frame, QtCore.QPoint(200, 200))
        QTest.mouseRelease(frame, QtCore.Qt.MouseButton.LeftButton)
        assert frame.pos() == pos
        assert not window.controller.delete_instance(inst.id)
        assert inst.id in [w.id for w in window.controller.canvas.widgets]
        # tapping the active segment keeps the mode; the Edit segment unlocks
        QTest.mouseClick(tap, QtCore.Qt.MouseButton.LeftButton)
        assert window.controller.canvas.locked and tap.isChecked() and not window.edit_button.isChecked()
        QTest.mouseClick(window.edit_button, QtCore.Qt.MouseButton.LeftButton)
        assert not window.controller.canvas.locked and window.edit_button.isChecked() and not tap.isChecked()
        # undo/redo work in edit mode
        window.undo()
        assert len(window.controller.canvas.widgets) == 1
        window.redo()
        assert len(window.controller.canvas.widgets) == 2
    finally:
        window.shutdown()


def test_layout_survives_restart(qtbot, tmp_path, robot):  # noqa: F811
    window = open_window(qtbot, tmp_path, robot.url)
    inst = add_probe(window, "/battery", "sensor_msgs/BatteryState", "percentage", QtCore.QPoint(160, 96))
    window.controller.add_canvas("Ops")
    window.controller.set_locked(True)
    window.close()
    window.shutdown()

    again = open_window(qtbot, tmp_path, None)
    try:
        ws = again.controller.workspace
        assert [c.name for c in ws.canvases] == ["Main", "Ops"]
        assert again.controller.index == 1 and again.controller.canvas.locked and again.lock_button.isChecked()
        saved = ws.canvases[0].widget(inst.id)
        assert (saved.geometry.x, saved.geometry.y) == (160, 96)
        assert saved.settings["caption"] == "/battery" and saved.binding.field_paths == ("percentage",)
        assert again.connection.url.currentText() == robot.url  # URL history persisted
    finally:
        again.shutdown()


def test_ui_stays_responsive_while_the_link_drops_and_returns(qtbot, tmp_path):
    from rcon_core.sim.server import SimServer

    gaps: list[float] = []
    with SimServer.in_thread(port=0) as first:
        port, url = first.port, first.url
        window = open_window(qtbot, tmp_path, url)
        add_probe(window, "/battery", "sensor_msgs/BatteryState", "percentage")
        last = [time.monotonic()]

        def beat() -> None:
            now = time.monotonic()
            gaps.append(now - last[0])
            last[0] = now

        timer = QtCore.QTimer()
        timer.timeout.connect(beat)
        timer.start(10)
        qtbot.wait(300)
    try:
        # the server is gone: the app notices, keeps painting, and shows the link down
        qtbot.waitUntil(lambda: window.connection.state in (ConnectionState.RECONNECTING, ConnectionState.CONNECTING), timeout=10_000)
        frame = next(iter(window.controller.surface.frames.values()))
        qtbot.waitUntil(lambda: frame.badge.isVisible() and frame.badge.status == "LINK DOWN", timeout=5_000)
        qtbot.wait(500)
        with SimServer.in_thread(port=port) as second:
            qtbot.waitUntil(lambda: window.connection.state is ConnectionState.CONNECTED, timeout=15_000)
            qtbot.waitUntil(lambda: second.topic_subscriber_count("/battery") == 1, timeout=10_000)
            qtbot.waitUntil(lambda: frame.badge.status != "LINK DOWN" or not frame.badge.isVisible(), timeout=10_000)
            timer.stop()
    finally:
        window.shutdown()
    assert len(gaps) > 50
    assert max(gaps) < 0.5, f"the GUI loop stalled for {max(gaps):.3f} s"


# ------------------------------------------------------------------ a canvas larger than the window scrolls
def frames_in_stacking_order(surface) -> list[str]:
    from rcon_core.app.widget_frame import WidgetFrame

    return [c.instance_id for c in surface.children() if isinstance(c, WidgetFrame)]


def drag(widget, start: QtCore.QPoint, delta: QtCore.QPoint, steps: int = 6) -> None:
    QTest.mousePress(widget, QtCore.Qt.MouseButton.LeftButton, QtCore.Qt.KeyboardModifier.NoModifier, start)
    for i in range(1, steps + 1):
        QTest.mouseMove(widget, start + QtCore.QPoint(delta.x() * i // steps, delta.y() * i // steps))
    QTest.mouseRelease(widget, QtCore.Qt.MouseButton.LeftButton, QtCore.Qt.KeyboardModifier.NoModifier,
                       start + delta)


def send_drop(surface, at: QtCore.QPoint, mime: QtCore.QMimeData) -> None:
    """What Qt delivers to the canvas when a drag ends over it: enter, move, drop (surface coordinates)."""
    for cls in (QtGui.QDragEnterEvent, QtGui.QDragMoveEvent):
        QtWidgets.QApplication.sendEvent(surface, cls(at, QtCore.Qt.DropAction.CopyAction, mime,
                                                      QtCore.Qt.MouseButton.LeftButton,
                                                      QtCore.Qt.KeyboardModifier.NoModifier))
    QtWidgets.QApplication.sendEvent(surface, QtGui.QDropEvent(
        QtCore.QPointF(at), QtCore.Qt.DropAction.CopyAction, mime, QtCore.Qt.MouseButton.LeftButton,
        QtCore.Qt.KeyboardModifier.NoModifier))


def overlapping(rects) -> list[tuple[int, int]]:
    return [(i, j) for i, a in enumerate(rects) for j, b in enumerate(rects) if i < j and a.intersects(b)]


def test_a_small_window_or_the_add_panel_scrolls_the_canvas_and_never_moves_a_widget(qtbot, tmp_path):
    window = open_window(qtbot, tmp_path, None)
    try:
        window.resize(1280, 800)
        a = add_probe(window, "/battery", "sensor_msgs/BatteryState", "percentage", QtCore.QPoint(16, 16))
        b = add_probe(window, "/battery", "sensor_msgs/BatteryState", "percentage", QtCore.QPoint(640, 448))
        surface = window.controller.surface
        saved = {i: rect_of(window, i) for i in (a.id, b.id)}
        shown = {i: surface.frames[i].geometry() for i in (a.id, b.id)}
        window.resize(1024, 600)
        qt_flushed(qtbot)
        # the add panel takes room from the canvas too
        window.add_panel.start_from_widget(window.plugins.widget("apptest.probe"))
        scroll = surface.scroll_area
        qtbot.waitUntil(lambda: window.add_panel.isVisible() and scroll.viewport().width() < 640 + 192)
        qt_flushed(qtbot)  # the far widget is out of view...
        assert {i: surface.frames[i].geometry() for i in (a.id, b.id)} == shown  # ...and was not moved
        assert {i: rect_of(window, i) for i in (a.id, b.id)} == saved
        assert not overlapping(list(shown.values()))
        assert scroll.horizontalScrollBar().maximum() > 0 and scroll.verticalScrollBar().maximum() > 0
        for frame in surface.frames.values():  # every widget is reachable by scrolling
            assert surface.rect().contains(frame.geometry())
    finally:
        window.shutdown()


def test_a_drop_lands_where_it_was_aimed_in_a_scrolled_canvas(qtbot, tmp_path):
    window = open_window(qtbot, tmp_path, None)
    try:
        window.resize(1024, 600)
        add_probe(window, "/battery", "sensor_msgs/BatteryState", "percentage", QtCore.QPoint(1200, 800))
        surface = window.controller.surface
        scroll = surface.scroll_area
        qt_flushed(qtbot)
        scroll.horizontalScrollBar().setValue(400)
        scroll.verticalScrollBar().setValue(200)
        aimed = QtCore.QPoint(100, 100)  # in the viewport
        spec = window.plugins.widget("apptest.probe")
        draft = Draft(spec, Role.SUBSCRIBE, Target("/battery", "sensor_msgs/BatteryState", ("percentage",)),
                      spec.make_settings({"caption": "x"}), "Probe")
        mime = QtCore.QMimeData()
        mime.setData("application/x-rcon-widget-draft", QtCore.QByteArray(b"draft"))
        window.controller.on_drop = lambda s, pt: window.controller.add_draft(draft, pt)
        send_drop(surface, surface.mapFrom(scroll.viewport(), aimed), mime)
        new = window.controller.canvas.widgets[-1]
        frame = surface.frames[new.id]
        where = frame.mapTo(scroll.viewport(), QtCore.QPoint(0, 0))
        assert abs(where.x() - aimed.x()) <= 8 and abs(where.y() - aimed.y()) <= 8
        assert (new.geometry.x, new.geometry.y) == (snap(400 + 100), snap(200 + 100))
    finally:
        window.shutdown()


def test_stacking_follows_the_canvas_order_and_survives_undo(qtbot, tmp_path):
    window = open_window(qtbot, tmp_path, None)
    try:
        ids = [add_probe(window, "/battery", "sensor_msgs/BatteryState", "percentage",
                         QtCore.QPoint(32 + 48 * i, 32 + 32 * i)).id for i in range(3)]
        surface = window.controller.surface
        assert frames_in_stacking_order(surface) == ids
        # tap the bottom one: raised while selected; tapping the canvas puts it back
        bottom = surface.frames[ids[0]]
        QTest.mouseClick(bottom.shield, QtCore.Qt.MouseButton.LeftButton, QtCore.Qt.KeyboardModifier.NoModifier,
                         QtCore.QPoint(12, bottom.height() // 2))
        assert frames_in_stacking_order(surface)[-1] == ids[0]
        QTest.mouseClick(surface, QtCore.Qt.MouseButton.LeftButton, QtCore.Qt.KeyboardModifier.NoModifier,
                         QtCore.QPoint(surface.width() - 20, surface.height() - 20))
        assert frames_in_stacking_order(surface) == ids
        # delete the middle one and undo it: it comes back in the middle, not on top
        window.controller.delete_instance(ids[1])
        QTest.keyClick(window, QtCore.Qt.Key.Key_Z, QtCore.Qt.KeyboardModifier.ControlModifier)
        assert [w.id for w in window.controller.canvas.widgets] == ids
        assert frames_in_stacking_order(window.controller.surface) == ids
    finally:
        window.shutdown()


def test_saved_geometry_is_on_the_grid_after_dragging_past_the_edge(qtbot, tmp_path):
    window = open_window(qtbot, tmp_path, None)
    try:
        window.resize(1024, 600)
        inst = add_probe(window, "/battery", "sensor_msgs/BatteryState", "percentage", QtCore.QPoint(96, 96))
        frame = window.controller.surface.frames[inst.id]
        drag(frame.shield, QtCore.QPoint(frame.width() // 2, frame.height() // 2), QtCore.QPoint(1203, 717))
        x, y, w, h = rect_of(window, inst.id)
        assert all(v % 16 == 0 for v in (x, y, w, h)), (x, y, w, h)
        assert x > 1024 and y > 600  # nothing clamped it into the window
        assert window.controller.surface.rect().contains(frame.geometry())  # and it can be scrolled to
        # dragged up-left past the origin: stops at the canvas edge, never at negative coordinates
        drag(frame.shield, QtCore.QPoint(frame.width() // 2, frame.height() // 2), QtCore.QPoint(-5000, -5000))
        assert rect_of(window, inst.id)[:2] == (0, 0)
    finally:
        window.shutdown()


def test_a_touch_scrolls_from_the_background_but_never_from_a_widget(qtbot, tmp_path):
    """QScroller asks the viewport (ScrollPrepare) before it takes a touch: refused over a widget, so a
    widget dragged in edit mode (or a teleop pad in operator mode) keeps its finger."""
    window = open_window(qtbot, tmp_path, None)
    try:
        window.resize(1024, 600)
        inst = add_probe(window, "/battery", "sensor_msgs/BatteryState", "percentage", QtCore.QPoint(96, 96))
        add_probe(window, "/battery", "sensor_msgs/BatteryState", "percentage", QtCore.QPoint(1400, 900))
        surface = window.controller.surface
        view = surface.scroll_area.viewport()
        assert QtWidgets.QScroller.hasScroller(view)
        frame = surface.frames[inst.id]

        def prepare(at: QtCore.QPoint) -> bool:
            event = QtGui.QScrollPrepareEvent(QtCore.QPointF(at))
            event.setAccepted(False)
            QtWidgets.QApplication.sendEvent(view, event)
            return event.isAccepted()

        for locked in (False, True):
            window.controller.set_locked(locked)
            assert not prepare(frame.mapTo(view, frame.rect().center()))
            assert prepare(QtCore.QPoint(view.width() - 10, view.height() - 10))
    finally:
        window.shutdown()


def test_deleting_a_canvas_with_widgets_asks_first_and_undo_brings_it_back(qtbot, tmp_path):
    window = open_window(qtbot, tmp_path, None)
    try:
        window.controller.add_canvas("Deck")
        add_probe(window, "/battery", "sensor_msgs/BatteryState", "percentage", QtCore.QPoint(64, 64))

        def ask_and_answer(name: str) -> None:
            window.canvas_actions["delete"].trigger()
            box = window.confirm_dialog
            qtbot.waitUntil(box.isVisible)
            assert "Deck" in box.text() and "1 widget" in box.informativeText()
            [button] = [b for b in box.buttons() if b.objectName() == name]
            assert button.height() >= 48 and button.width() >= 48  # touch-sized
            QTest.mouseClick(button, QtCore.Qt.MouseButton.LeftButton)
            qtbot.waitUntil(lambda: not box.isVisible())

        ask_and_answer("confirmCancel")
        assert [c.name for c in window.controller.workspace.canvases] == ["Main", "Deck"]
        ask_and_answer("confirmYes")
        assert [c.name for c in window.controller.workspace.canvases] == ["Main"]
        QTest.keyClick(window, QtCore.Qt.Key.Key_Z, QtCore.Qt.KeyboardModifier.ControlModifier)
        assert [c.name for c in window.controller.workspace.canvases] == ["Main", "Deck"]
        assert len(window.controller.workspace.canvas_named("Deck").widgets) == 1
        # an empty canvas goes without a question
        window.controller.add_canvas("Empty")
        window.canvas_actions["delete"].trigger()
        assert "Empty" not in [c.name for c in window.controller.workspace.canvases]
    finally:
        window.shutdown()


def test_a_refused_canvas_edit_is_said_on_the_notice_bar_not_in_the_connection_bar(qtbot, tmp_path):
    window = open_window(qtbot, tmp_path, None)
    try:
        before = window.connection.message.text()
        window.delete_canvas()  # the only canvas: refused (its menu entry is greyed out for that reason)
        assert [c.name for c in window.controller.workspace.canvases] == ["Main"]
        assert window.notice.kind == "problem" and "cannot delete the last canvas" in window.banner.text()
        assert window.connection.message.text() == before  # the connection's own line is left alone
    finally:
        window.shutdown()


def test_duplicate_puts_the_copy_on_a_free_spot(qtbot, tmp_path):
    window = open_window(qtbot, tmp_path, None)
    try:
        inst = add_probe(window, "/battery", "sensor_msgs/BatteryState", "percentage", QtCore.QPoint(16, 16))
        add_probe(window, "/battery", "sensor_msgs/BatteryState", "percentage", QtCore.QPoint(224, 16))
        frame = window.controller.surface.frames[inst.id]
        menu = frame.request_menu(frame.mapToGlobal(QtCore.QPoint(10, 10)))
        [dup] = [a for a in menu.actions() if a.objectName() == "duplicate"]
        dup.trigger()
        menu.close()
        surface = window.controller.surface
        rects = [surface.frames[w.id].geometry() for w in window.controller.canvas.widgets]
        assert len(rects) == 3 and not overlapping(rects)
        copy = window.controller.canvas.widgets[-1]
        assert (copy.geometry.w, copy.geometry.h) == (inst.geometry.w, inst.geometry.h)
        assert copy.settings == inst.settings and copy.id != inst.id
    finally:
        window.shutdown()


def test_the_configure_dialog_is_a_labelled_form(qtbot, tmp_path):
    window = open_window(qtbot, tmp_path, None)
    try:
        inst = add_probe(window, "/battery", "sensor_msgs/BatteryState", "percentage", QtCore.QPoint(16, 16))
        frame = window.controller.surface.frames[inst.id]
        menu = frame.request_menu(frame.mapToGlobal(QtCore.QPoint(10, 10)))
        [configure] = [a for a in menu.actions() if a.objectName() == "configure"]
        configure.trigger()
        menu.close()
        dialog = window.configurer.dialog
        qtbot.waitUntil(dialog.isVisible)
        title = dialog.findChild(QtWidgets.QLineEdit, "configureTitle")
        labels = [lbl for lbl in dialog.findChildren(QtWidgets.QLabel) if lbl.buddy() is title]
        assert [lbl.text() for lbl in labels] == ["Title"] and labels[0].isVisible()
        # the labels sit on the form's white page, not in boxes of their own on the dialog's grey
        body = dialog.findChild(QtWidgets.QFrame, "configureBody")
        assert body.isAncestorOf(labels[0]) and body.isAncestorOf(title)
        title.selectAll()
        QTest.keyClicks(title, "Charge")
        dialog.accept()
        assert window.controller.canvas.widget(inst.id).title == "Charge"
    finally:
        window.shutdown()
