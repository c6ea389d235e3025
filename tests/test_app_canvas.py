"""Canvases and editing: hot swap on the robot's side, move, pinch-resize, lock, restart, link loss."""

from __future__ import annotations

import time

import pytest
from qtpy import QtCore
from qtpy.QtTest import QTest
from test_app_window import make_plugins, robot  # noqa: F401 - fixture re-used

from rcon_core.app.config import AppConfig
from rcon_core.app.draft import Draft, Target
from rcon_core.app.main_window import MainWindow
from rcon_core.plugins import Role

pytestmark = pytest.mark.usefixtures("qapp")


class FakePinch:
    """What WidgetFrame.pinch_gesture reads from a QPinchGesture."""

    def __init__(self, state, total: float) -> None:
        self._state, self._total = state, total

    def state(self):
        return self._state

    def totalScaleFactor(self) -> float:  # noqa: N802 - Qt's name
        return self._total


def open_window(qtbot, config_dir, url: str | None) -> MainWindow:
    window = MainWindow(AppConfig(config_dir), make_plugins())
    qtbot.addWidget(window)
    window.show()
    QTest.qWaitForWindowExposed(window)
    if url:
        window.connect_to(url)
        qtbot.waitUntil(lambda: window.connection.state == "connected", timeout=10_000)
    return window


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
            frame.pinch_gesture(FakePinch(state, scale))
        after = rect_of(window, inst.id)
        assert after[2] > before.width() * 1.5 and after[3] > before.height() * 1.5
        # pinching far out never leaves the widget off-screen
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
        # undo/redo work in edit mode
        QTest.mouseClick(tap, QtCore.Qt.MouseButton.LeftButton)
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
        qtbot.waitUntil(lambda: window.connection.state in ("reconnecting", "connecting"), timeout=10_000)
        frame = next(iter(window.controller.surface.frames.values()))
        qtbot.waitUntil(lambda: frame.badge.isVisible() and frame.badge.text() == "LINK DOWN", timeout=5_000)
        qtbot.wait(500)
        with SimServer.in_thread(port=port) as second:
            qtbot.waitUntil(lambda: window.connection.state == "connected", timeout=15_000)
            qtbot.waitUntil(lambda: second.topic_subscriber_count("/battery") == 1, timeout=10_000)
            qtbot.waitUntil(lambda: frame.badge.text() != "LINK DOWN" or not frame.badge.isVisible(), timeout=10_000)
            timer.stop()
    finally:
        window.shutdown()
    assert len(gaps) > 50
    assert max(gaps) < 0.5, f"the GUI loop stalled for {max(gaps):.3f} s"
