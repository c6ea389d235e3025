"""Shared set-up for the Qt app tests: opening a main window on the sim robot and a person's taps.

Plain helpers, imported explicitly by the ``test_app_*`` modules; each module keeps its own small
fixtures that call these with what genuinely differs (window size, type registry, what to wait for).
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
from rcon_core.canvas import Workspace
from rcon_core.plugins import PluginManager, Role

LEFT = QtCore.Qt.MouseButton.LeftButton
NO_MOD = QtCore.Qt.KeyboardModifier.NoModifier
TIMEOUT_MS = 10_000


def entry_point_plugins() -> PluginManager:
    """A plugin manager holding every widget plugin installed through the entry points."""
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
    activate: bool = False,
    wait_connected: bool = False,
    topics: tuple[str, ...] = (),
    services: tuple[str, ...] = (),
) -> MainWindow:
    """Show a main window (1280x800 unless told) and, given ``url``, connect it and wait for
    the connection (if ``wait_connected``) and then for each of ``topics`` and ``services`` to be listed."""
    win = MainWindow(AppConfig(config_dir), plugins, types=types, demo=demo)
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
            qtbot.waitUntil(lambda: win.connection.state == "connected", timeout=TIMEOUT_MS)
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


def snap(window: QtWidgets.QWidget, name: str) -> None:
    """With ``RCON_SCREENSHOTS=DIR`` set, save a PNG of ``window`` as it is now (to look at it as a person
    would); otherwise nothing."""
    out = os.environ.get("RCON_SCREENSHOTS", "")
    if out and out != "1":
        QtWidgets.QApplication.processEvents()
        Path(out).mkdir(parents=True, exist_ok=True)
        window.grab().save(str(Path(out) / f"{name}.png"))
