"""Make the screenshots of docs/using-the-app.md: the add-widget pathway, step by step.

    python docs/make_screenshots.py [--out docs/screenshots]

Starts the embedded simulated robot in a thread, opens the app's main window (1280x800, the installed
widget plugins, a temporary config directory, headless unless QT_QPA_PLATFORM says otherwise), connects,
and drives the window the way a person does (taps, as the app tests do), saving one PNG per step:

1. topics listed; 2. the role chosen for /battery; 3. the compatible widgets, best first;
4. settings not configured (the Label's scale cleared to 0: the preview's warning);
5. settings valid, the Field chooser on ``voltage``; 6. the widget placed on the canvas, live;
7. operator mode; 8. a Compound on /cmd_vel with two children in its children editor.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")

from qtpy import QtCore, QtWidgets  # noqa: E402
from qtpy.QtTest import QTest  # noqa: E402

SIZE = (1280, 800)
MAX_BYTES = 200_000
TIMEOUT_S = 15.0
LEFT = QtCore.Qt.MouseButton.LeftButton
NO_MOD = QtCore.Qt.KeyboardModifier.NoModifier


def wait_until(cond: Callable[[], bool], what: str, timeout: float = TIMEOUT_S) -> None:
    """Process events until ``cond()`` holds; a clear error naming ``what`` if it never does."""
    end = time.monotonic() + timeout
    while not cond():
        if time.monotonic() > end:
            raise SystemExit(f"make_screenshots: timed out waiting for {what}")
        QTest.qWait(20)


def settle(ms: int = 400) -> None:
    """Let layouts, repaints and live data catch up before a grab."""
    QTest.qWait(ms)


def tap(widget: QtWidgets.QWidget, pos: QtCore.QPoint | None = None) -> None:
    """A finger tap on a visible, enabled widget, at its centre unless told where."""
    if not (widget.isVisible() and widget.isEnabled()):
        raise SystemExit(f"make_screenshots: cannot tap {widget.objectName() or widget!r}: hidden or disabled")
    QTest.mouseClick(widget, LEFT, NO_MOD, pos if pos is not None else widget.rect().center())


def tap_item(view: QtWidgets.QAbstractItemView, index: QtCore.QModelIndex) -> None:
    """Scroll an item into sight and tap it."""
    view.scrollTo(index)
    QTest.mouseClick(view.viewport(), LEFT, NO_MOD, view.visualRect(index).center())


def pick(combo: QtWidgets.QComboBox, text: str) -> None:
    """Open the combo's popup and tap the entry whose text starts with ``text``."""
    rows = [i for i in range(combo.count()) if combo.itemText(i).startswith(text)]
    if not rows:
        raise SystemExit(f"make_screenshots: {text!r} not in {[combo.itemText(i) for i in range(combo.count())]}")
    tap(combo)
    view = combo.view()
    wait_until(view.isVisible, "the popup")
    QTest.qWait(QtWidgets.QApplication.doubleClickInterval() + 50)  # a popup ignores a release at once
    tap_item(view, combo.model().index(rows[0], 0))
    wait_until(lambda: not view.isVisible(), "the popup to close")


def set_number(editor: QtWidgets.QAbstractSpinBox, value: float) -> None:
    """Type a number into a spin box, as a person would."""
    editor.setFocus()
    editor.selectAll()
    QTest.keyClicks(editor, str(value))


def visible_button(parent: QtWidgets.QWidget, name: str) -> QtWidgets.QPushButton:
    """The visible button called ``name`` (rebuilt pages keep hidden old ones until deleted)."""
    found = [b for b in parent.findChildren(QtWidgets.QPushButton, name) if b.isVisible()]
    if len(found) != 1:
        raise SystemExit(f"make_screenshots: expected one visible {name!r} button, found {len(found)}")
    return found[0]


def scroll_settings_to(panel: QtWidgets.QWidget, widget: QtWidgets.QWidget, margin: int = 8) -> None:
    """Scroll the add panel's settings page so that ``widget`` starts ``margin`` px below its top."""
    settle(200)  # the page's own scrolling (to its top on opening) first
    scroll = panel.settings_scroll
    top = widget.mapTo(scroll.widget(), QtCore.QPoint(0, 0)).y()
    scroll.verticalScrollBar().setValue(max(0, top - margin))


class Shooter:
    """Saves numbered grabs of the window into ``out``."""

    def __init__(self, window: QtWidgets.QWidget, out: Path) -> None:
        self.window, self.out = window, out
        self.saved: list[Path] = []

    def __call__(self, name: str) -> None:
        settle()
        if (self.window.width(), self.window.height()) != SIZE:
            self.window.resize(*SIZE)
            settle()
        image = self.window.grab().toImage()
        if (image.width(), image.height()) != SIZE:
            raise SystemExit(f"make_screenshots: {name} grabbed at {image.width()}x{image.height()}, not {SIZE}")
        path = self.out / f"{name}.png"
        if not image.save(str(path), "PNG", 0):  # quality 0: the strongest PNG compression
            raise SystemExit(f"make_screenshots: could not write {path}")
        size = path.stat().st_size
        if size >= MAX_BYTES:
            raise SystemExit(f"make_screenshots: {path} is {size} bytes, over {MAX_BYTES}")
        self.saved.append(path)
        print(f"{path}  {size // 1024} KB")


def run(out: Path) -> list[Path]:
    """Drive the window through the add-widget pathway and save each step in ``out``."""
    app = QtWidgets.QApplication.instance() or QtWidgets.QApplication(sys.argv[:1])
    app.setApplicationName("RCON")

    from rcon_core.app import theme
    from rcon_core.app.config import AppConfig
    from rcon_core.app.main_window import MainWindow
    from rcon_core.plugins import PluginManager, Role
    from rcon_core.sim import SimServer

    theme.apply(app)
    plugins = PluginManager(environ={})
    plugins.load_entry_points()
    out.mkdir(parents=True, exist_ok=True)

    with tempfile.TemporaryDirectory(prefix="rcon-shots-") as tmp, SimServer.in_thread(port=0) as robot:
        win = MainWindow(AppConfig(Path(tmp) / "config"), plugins)
        win.resize(*SIZE)
        win.show()
        QTest.qWaitForWindowExposed(win)
        shoot = Shooter(win, out)
        try:
            win.connect_to(robot.url, remember=False)
            wait_until(lambda: win.connection.state == "connected", "the connection")
            for topic in ("/battery", "/cmd_vel"):
                wait_until(lambda topic=topic: win.topics.item(topic) is not None, f"{topic} to be listed")
            win.side.setCurrentWidget(win.topics)
            settle(1000)  # the round-trip time shows
            shoot("1-topics")

            # 2: tap /battery, choose "show it" (subscribe)
            tree = win.topics.tree
            tap_item(tree, tree.indexFromItem(win.topics.item("/battery")))
            panel = win.add_panel
            wait_until(lambda: panel.stack.currentWidget() is panel.role_page, "the role page")
            shoot("2-role")

            # 3: the compatible widgets, best first
            tap(panel.role_buttons[Role.SUBSCRIBE])
            wait_until(lambda: panel.stack.currentWidget() is panel.widgets_page, "the widget list")
            shoot("3-compatible-widgets")

            # 4: a Label, its scale cleared to 0: not configured, the preview warns
            kinds = [panel.candidates.item(i).data(QtCore.Qt.ItemDataRole.UserRole).spec.kind
                     for i in range(panel.candidates.count())]
            tap_item(panel.candidates, panel.candidates.model().index(kinds.index("std.label"), 0))
            wait_until(lambda: panel.stack.currentWidget() is panel.settings_page, "the settings page")
            scale = panel.form.editor("scale")
            set_number(scale, 0)
            wait_until(lambda: not panel.place_button.isEnabled(), "the scale problem to block placing")
            wait_until(lambda: panel.preview_frame is not None and "scale" in panel.preview_frame.problems.text(),
                       "the preview's warning")
            scroll_settings_to(panel, panel.preview_slot, margin=40)  # the warning and the scale of 0
            shoot("4-settings-not-configured")

            # 5: scale back to 1, the Field chooser on voltage: valid
            set_number(scale, 1)
            pick(panel.field_combo, "voltage")
            wait_until(panel.place_button.isEnabled, "the settings to be valid")
            panel.settings_scroll.verticalScrollBar().setValue(0)
            win.setFocus()
            settle(1500)  # the preview shows the robot's live voltage
            shoot("5-settings-valid")

            # 6: placed on the canvas, live
            tap(panel.place_button)
            [inst] = win.controller.canvas.widgets
            hosted = win.host.hosted[inst.id]
            wait_until(lambda: hosted.model is not None and hosted.model.state.count > 0, "live data on the canvas")
            settle(800)
            shoot("6-placed")

            # 7: operator mode
            tap(win.lock_button)
            wait_until(lambda: win.controller.canvas.locked, "operator mode")
            shoot("7-operator-mode")

            # 8: back to Edit, a Compound on /cmd_vel with a slider and a stepper
            tap(win.edit_button)
            wait_until(lambda: not win.controller.canvas.locked, "edit mode")
            win.side.setCurrentWidget(win.topics)
            tap_item(tree, tree.indexFromItem(win.topics.item("/cmd_vel")))
            tap(panel.role_buttons[Role.PUBLISH])
            kinds = [panel.candidates.item(i).data(QtCore.Qt.ItemDataRole.UserRole).spec.kind
                     for i in range(panel.candidates.count())]
            tap_item(panel.candidates, panel.candidates.model().index(kinds.index("std.compound"), 0))
            editor = panel.form.children_editors["children"]
            for path, kind, numbers, title in (
                ("linear.x", "std.slider", (("minimum", 0.0), ("maximum", 2.0), ("step", 0.5)), ""),
                ("angular.z", "std.stepper", (("minimum", -1.0), ("maximum", 1.0), ("step", 0.25)), "Turn"),
            ):
                tap(editor.add_button)
                wait_until(lambda: editor.current_page == "fields", "the fields of /cmd_vel")
                tap(editor.field_buttons[path])
                tap(editor.kind_buttons[kind])
                for name, value in numbers:
                    set_number(editor.child_form.editor(name), value)
                if title:
                    QTest.keyClicks(editor.child_title, title)
                tap(visible_button(editor, "childDone"))
                wait_until(lambda: editor.current_page == "list", "the children list")
            wait_until(panel.place_button.isEnabled, "the Compound to be valid")
            win.setFocus()
            settle(200)
            panel.settings_scroll.ensureWidgetVisible(editor.add_button)  # both children and "+ Add child"
            shoot("8-compound-children")
        finally:
            win.shutdown()
            win.close()
    return shoot.saved


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="Make the screenshots of docs/using-the-app.md.")
    parser.add_argument("--out", type=Path, default=Path(__file__).resolve().parent / "screenshots",
                        help="where to write the PNGs (default: docs/screenshots)")
    args = parser.parse_args(argv)
    run(args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
