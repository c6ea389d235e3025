"""Shared set-up for the Qt app tests: opening a main window on the sim robot and a person's taps.

Plain helpers, imported explicitly by the ``test_app_*`` modules; each module keeps its own small
fixtures that call these with what genuinely differs (window size, type registry, what to wait for).
The one fixture every app module shares, ``plugins`` (the installed widget plugins), comes with the sim
fixtures from ``rcon_core.testing``; a module that needs other plugins defines its own.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from qtpy import QtCore, QtWidgets
from qtpy.QtTest import QTest

from rcon_core.app.add_panel import AddPanel
from rcon_core.app.config import AppConfig
from rcon_core.app.main_window import MainWindow
from rcon_core.bridge import ConnectionState
from rcon_core.canvas import Workspace
from rcon_core.plugins import PluginManager, Role

LEFT = QtCore.Qt.MouseButton.LeftButton
NO_MOD = QtCore.Qt.KeyboardModifier.NoModifier
TIMEOUT_MS = 10_000


def entry_point_plugins() -> PluginManager:
    """A plugin manager holding every widget plugin installed through the entry points (as the shared
    ``plugins`` fixture, for a module that registers more on its own copy)."""
    pm = PluginManager(environ={})
    pm.load_entry_points()
    return pm


def open_window(
    qtbot,
    config_dir: Path,
    plugins: PluginManager,
    *,
    url: str | None = None,
    size: tuple[int, int] | None = (1280, 800),
    types: Any = None,
    demo: Callable[[], Workspace] | None = None,
    layout: Path | None = None,
    activate: bool = False,
    wait_connected: bool = False,
    topics: tuple[str, ...] = (),
    services: tuple[str, ...] = (),
) -> MainWindow:
    """Show a main window (1280x800 unless told; ``size=None``: the screen's) on ``layout`` (a workspace file)
    if given and, given ``url``, connect it and wait for the connection (if ``wait_connected``) and then for
    each of ``topics`` and ``services`` to be listed."""
    win = MainWindow(AppConfig(config_dir), plugins, types=types, demo=demo, layout_path=layout)
    qtbot.addWidget(win)
    if size is not None:
        win.resize(*size)
    win.show()
    QTest.qWaitForWindowExposed(win)
    if activate:
        win.activateWindow()
        QTest.qWaitForWindowActive(win)
    if url:
        win.connect_to(url)
        if wait_connected:
            qtbot.waitUntil(lambda: win.connection.state is ConnectionState.CONNECTED, timeout=TIMEOUT_MS)
        for topic in topics:
            qtbot.waitUntil(lambda topic=topic: win.topics.item(topic) is not None, timeout=TIMEOUT_MS)
        for service in services:
            qtbot.waitUntil(lambda service=service: win.services.item(service) is not None, timeout=TIMEOUT_MS)
    return win


def window_session(qtbot, config_dir: Path, plugins: PluginManager, **options: Any) -> Iterator[MainWindow]:
    """For a fixture's ``yield from``: an :func:`open_window`, shut down after the test."""
    win = open_window(qtbot, config_dir, plugins, **options)
    yield win
    win.shutdown()


def window_maker(qtbot, config_root: Path, plugins: PluginManager, *, demo: bool = False,
                 **options: Any) -> Iterator[Callable[..., MainWindow]]:
    """For a fixture's ``yield from``: ``make(size, demo=...)`` opens one more window (:func:`open_window`
    with ``options``, its own config folder; ``demo``: on the demo layout), each shut down after the test."""
    made: list[MainWindow] = []

    def make(size: tuple[int, int] | None, demo: bool = demo) -> MainWindow:
        from rcon_core.app.demo import demo_workspace

        win = open_window(qtbot, config_root / f"config{len(made)}", plugins, size=size,
                          demo=(lambda: demo_workspace(plugins)) if demo else None, **options)
        made.append(win)
        return win

    yield make
    for win in made:
        win.shutdown()


def settle(passes: int = 3) -> None:
    """Let Qt catch up with what the test just did: the posted events (layout requests, polish, queued
    calls, zero-delay single shots) sent and the window system's events processed, ``passes`` times over
    (what one pass posts, the next sends). It never waits for time to pass, and no timer fires in it:
    what comes on a timer or from another thread (a frame of the frame clock, a value from the sim) is
    waited for with ``qtbot.waitUntil`` on that condition."""
    app = QtWidgets.QApplication.instance()
    for _ in range(passes):
        app.sendPostedEvents()
        app.processEvents(QtCore.QEventLoop.ProcessEventsFlag.X11ExcludeTimers)


def canvas_shown(qtbot, window: MainWindow) -> None:
    """Wait until every widget of the canvas shown has its view, built from the model the bridge thread
    made for it (a canvas switch or a placed widget builds them a moment later), then :func:`settle`."""
    def built() -> None:
        missing = [w.title or w.kind for w in window.controller.canvas.widgets
                   if (h := window.host.hosted.get(w.id)) is None or h.view is None or not h.view.isVisible()]
        assert not missing, missing

    qtbot.waitUntil(built, timeout=TIMEOUT_MS)
    settle()


def compound_in_operate(qtbot, window: MainWindow, widget_id: str, children: int) -> tuple[Any, Any]:
    """Operate mode (the widgets take touches), then wait until the placed Compound ``widget_id`` shows its
    ``children`` child views: (its hosted widget, its view)."""
    if not window.controller.canvas.locked:
        window.lock_button.click()
    hosted = window.host.hosted[widget_id]
    qtbot.waitUntil(lambda: hosted.view is not None and len(getattr(hosted.view, "child_views", [])) == children,
                    timeout=TIMEOUT_MS)
    return hosted, hosted.view


class Pinch:
    """A two-finger pinch as ``WidgetFrame.pinch_gesture`` reads it from a ``QPinchGesture`` (its state and
    total scale factor), for resizing a frame as a person's fingers would."""

    def __init__(self, state: Any, total: float) -> None:
        self._state, self._total = state, total

    def state(self) -> Any:
        return self._state

    def totalScaleFactor(self) -> float:  # noqa: N802 - Qt's name
        return self._total


def all_sent(qtbot, window: MainWindow, sim: Any) -> None:
    """Wait until everything the window sent so far has reached ``sim``: a rosapi call on the same link is
    counted by the sim after the frames sent before it (one connection is handled in order)."""
    key = ("call_service", "/rosapi/topics")
    before = sim.ops_received[key]
    window.link.refresh_catalog()
    qtbot.waitUntil(lambda: sim.ops_received[key] > before, timeout=TIMEOUT_MS)


def tap(widget: QtWidgets.QWidget, pos: QtCore.QPoint | None = None) -> None:
    """A finger tap on a visible, enabled widget, at its centre unless told where."""
    assert widget.isVisible() and widget.isEnabled(), widget.objectName()
    QTest.mouseClick(widget, LEFT, NO_MOD, pos if pos is not None else widget.rect().center())


def tap_through(widget: QtWidgets.QWidget, pos: QtCore.QPoint | None = None) -> None:
    """A finger tap at ``pos`` of ``widget`` (its centre unless told), delivered to the window as the screen
    delivers it: whatever is on top under the finger (a child, a badge, an overlay) gets it."""
    window = widget.window().windowHandle()
    assert window is not None and widget.isVisible(), widget.objectName()
    at = widget.mapTo(widget.window(), pos if pos is not None else widget.rect().center())
    QTest.mouseClick(window, LEFT, NO_MOD, at)


def tap_item(view: QtWidgets.QAbstractItemView, index: QtCore.QModelIndex) -> None:
    """Scroll an item into sight and tap it."""
    view.scrollTo(index)
    QTest.mouseClick(view.viewport(), LEFT, NO_MOD, view.visualRect(index).center())


def tap_topic(window: MainWindow, name: str) -> None:
    """Tap a topic's row in the topic list."""
    tree = window.topics.tree
    index = tree.indexFromItem(window.topics.item(name))
    tree.scrollTo(index)
    tap(tree.viewport(), tree.visualRect(index).center())


def choose_kind(window: MainWindow, role: Role, kind: str) -> AddPanel:
    """In the open add panel, tap the ``role`` button and then the candidate widget ``kind``."""
    panel = window.add_panel
    tap(panel.role_buttons[role])
    kinds = [panel.candidates.item(i).data(QtCore.Qt.ItemDataRole.UserRole).spec.kind
             for i in range(panel.candidates.count())]
    tap_item(panel.candidates, panel.candidates.model().index(kinds.index(kind), 0))
    return panel


def snap_with(window: QtWidgets.QWidget, dialog: QtWidgets.QWidget, name: str) -> None:
    """Like :func:`snap`, with ``dialog`` (a separate top-level window) drawn where it is over the window."""
    out = os.environ.get("RCON_SCREENSHOTS", "")
    if not out or out == "1":
        return
    from qtpy import QtCore, QtGui

    QtWidgets.QApplication.processEvents()
    picture = window.grab()
    painter = QtGui.QPainter(picture)
    painter.drawPixmap(dialog.mapToGlobal(QtCore.QPoint(0, 0)) - window.mapToGlobal(QtCore.QPoint(0, 0)),
                       dialog.grab())
    painter.end()
    Path(out).mkdir(parents=True, exist_ok=True)
    picture.save(str(Path(out) / f"{name}.png"))


def snap(window: QtWidgets.QWidget, name: str) -> None:
    """With ``RCON_SCREENSHOTS=DIR`` set, save a PNG of ``window`` as it is now (to look at it as a person
    would); otherwise nothing."""
    out = os.environ.get("RCON_SCREENSHOTS", "")
    if out and out != "1":
        QtWidgets.QApplication.processEvents()
        Path(out).mkdir(parents=True, exist_ok=True)
        window.grab().save(str(Path(out) / f"{name}.png"))


class FullDisk:
    """A full disk, honestly at the OS call: while ``on``, every ``os.fsync`` (where a full disk reports
    buffered writes it cannot keep) raises ENOSPC. Made by :func:`full_disk` for a module's fixture."""

    def __init__(self) -> None:
        self.on = False


def full_disk(monkeypatch) -> FullDisk:
    import errno

    disk = FullDisk()
    real = os.fsync

    def fsync(fd: int) -> None:
        if disk.on:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        real(fd)

    monkeypatch.setattr(os, "fsync", fsync)
    return disk

