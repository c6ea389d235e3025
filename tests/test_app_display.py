"""Canvas ▾ → Display… on the real window against the sim (issue 21.14): the high-contrast Sunlight theme
and the dark Night theme switch at run time and are kept for the next start; every bundled widget's view
follows the theme; the text size (100–200 %) is followed by the whole window, which stays 1024x600 with no
label or button cut (in Operate and Edit mode, connected and not)."""

from __future__ import annotations

import pytest
from app_helpers import TIMEOUT_MS, canvas_shown, choose_kind, open_window, settle, snap, tap, tap_topic
from fit_check import problems
from qtpy import QtCore, QtGui, QtWidgets
from test_app_accessibility import every_widget

from rcon_core.app import theme
from rcon_core.app.config import AppConfig
from rcon_core.app.demo import demo_workspace
from rcon_core.bridge import ConnectionState
from rcon_core.plugins import Role
from rcon_core.sim.server import SimServer

pytestmark = pytest.mark.usefixtures("qapp")
PACKAGES = ("rcon_widgets_std", "rcon_widgets_sensors", "rcon_widgets_map")
#: views that show a picture (a camera's): their lightness is the picture's, not the theme's
PICTURES = ("sensors.image", "sensors.camera")


@pytest.fixture(scope="module")
def bundled():
    from app_helpers import entry_point_plugins

    for name in PACKAGES:
        pytest.importorskip(name)
    return entry_point_plugins()


@pytest.fixture(autouse=True)
def standard_look():
    """Each test starts, and leaves the app, in the standard look."""
    app = QtWidgets.QApplication.instance()
    theme.apply(app, theme.DEFAULT_THEME, 100)
    yield
    theme.apply(app, theme.DEFAULT_THEME, 100)


def display(window, qtbot, button: str) -> None:
    """Canvas ▾ → Display…, tap ``button`` (an object name: "theme-night", "text-200"), close."""
    window.canvas_actions["display"].trigger()
    dialog = window.display.dialog
    qtbot.waitUntil(dialog.isVisible, timeout=TIMEOUT_MS)
    tap(dialog.findChild(QtWidgets.QPushButton, button))
    snap(dialog, f"display-{button}")
    dialog.close()
    settle()


def lightness(widget: QtWidgets.QWidget, at: QtCore.QPoint | None = None) -> float:
    """The mean lightness (0-255) of ``widget`` as painted, or of one pixel."""
    image = widget.grab().toImage()
    if at is not None:
        return QtGui.QColor(image.pixel(at)).lightness()
    step = max(1, min(image.width(), image.height()) // 24)
    values = [QtGui.QColor(image.pixel(x, y)).lightness()
              for x in range(0, image.width(), step) for y in range(0, image.height(), step)]
    return sum(values) / len(values)


def test_the_theme_switches_at_run_time_and_is_kept(qtbot, tmp_path, bundled):
    with SimServer.in_thread(port=0) as robot:
        window = open_window(qtbot, tmp_path / "config", bundled, demo=lambda: demo_workspace(bundled),
                             url=robot.url, wait_connected=True)
        try:
            surface = window.controller.surface
            corner = QtCore.QPoint(surface.width() - 4, surface.height() - 4)
            bar = window.connection
            margin = QtCore.QPoint(bar.width() - 3, 3)  # the bar's own background (its controls vary)
            assert lightness(surface, corner) > 200 and lightness(bar, margin) > 200  # sunlight
            display(window, qtbot, "theme-night")
            assert lightness(surface, corner) < 40 and lightness(bar, margin) < 80
            text = window.connection.state_label.palette().color(QtGui.QPalette.ColorRole.WindowText)
            assert AppConfig(tmp_path / "config").theme == "night"
            snap(window, "theme-night")
            display(window, qtbot, "theme-sunlight")
            assert lightness(surface, corner) > 200
            assert text.isValid()
            display(window, qtbot, "theme-night")
        finally:
            window.shutdown()
        # the next start keeps it
        again = open_window(qtbot, tmp_path / "config", bundled, url=robot.url, wait_connected=True)
        try:
            assert theme.current_theme() == "night"
            assert lightness(again.controller.surface, QtCore.QPoint(8, 8)) < 40
        finally:
            again.shutdown()


def test_every_bundled_widget_follows_the_theme(qtbot, tmp_path, bundled):
    with SimServer.in_thread(port=0, ros2=True) as robot:
        scout = open_window(qtbot, tmp_path / "scout", bundled, url=robot.url, wait_connected=True,
                            topics=("/battery",))
        qtbot.waitUntil(lambda: bool(scout.catalog.get("actions")), timeout=TIMEOUT_MS)
        workspace = every_widget(bundled, dict(scout.catalog))
        scout.shutdown()
        window = open_window(qtbot, tmp_path / "all", bundled, demo=lambda: workspace, url=robot.url,
                             wait_connected=True, size=(1400, 1000))
        try:
            hosted = list(window.host.hosted.values())
            qtbot.waitUntil(lambda: all(h.view is not None for h in hosted), timeout=TIMEOUT_MS)
            looks = {}
            for name in ("sunlight", "night"):
                display(window, qtbot, f"theme-{name}")
                settle()
                looks[name] = {h.widget.kind: lightness(h.view) for h in hosted}
                snap(window, f"every-widget-{name}")
            for kind in looks["night"]:
                if kind in PICTURES:
                    continue
                day, night = looks["sunlight"][kind], looks["night"][kind]
                assert day > 150 and night < 100, (kind, day, night)  # light by day, dark at night
        finally:
            window.shutdown()


@pytest.mark.parametrize("size", [125, 150, 200])
def test_the_whole_window_follows_the_text_size_without_a_cut_at_1024x600(qtbot, tmp_path, bundled, size):
    with SimServer.in_thread(port=0) as robot:
        window = open_window(qtbot, tmp_path / "config", bundled, demo=lambda: demo_workspace(bundled),
                             url=robot.url, wait_connected=True, size=(1024, 600), topics=("/battery",))
        try:
            before = window.connection.connect_button.font().pixelSize()
            display(window, qtbot, f"text-{size}")
            assert AppConfig(tmp_path / "config").text_size == size
            assert window.connection.connect_button.font().pixelSize() == round(before * size / 100)
            for k in range(window.tabs.count()):  # Operate mode, every canvas
                window.switch_canvas(k)
                canvas_shown(qtbot, window)
                assert window.size() == QtCore.QSize(1024, 600)
                assert problems(window) == [], (k, problems(window))
            snap(window, f"text-{size}-operate")
            tap(window.edit_button)
            settle()
            assert window.size() == QtCore.QSize(1024, 600) and problems(window) == []
            snap(window, f"text-{size}-edit")
            if not window.side.isVisible():  # no room beside the canvas: ▶ shows it in the canvas's place
                assert window.side_toggle.isEnabled() and "in place of the canvas" in window.side_toggle.toolTip()
                tap(window.side_toggle)
                settle()
                assert window.side.isVisible() and not window.center.isVisible()
                assert window.size() == QtCore.QSize(1024, 600) and problems(window) == []
                snap(window, f"text-{size}-side")
            tap_topic(window, "/battery")  # adding a widget: the add panel beside the canvas, nothing cut
            choose_kind(window, Role.SUBSCRIBE, "std.label")
            qtbot.waitUntil(lambda: window.add_panel.preview_frame is not None, timeout=TIMEOUT_MS)
            settle()
            # beside the canvas, or in its place when the two do not fit side by side
            assert window.add_panel.isVisible() and window.center.isVisible() != window.side_policy.panel_alone
            assert window.size() == QtCore.QSize(1024, 600) and problems(window) == []
            snap(window, f"text-{size}-adding")
            tap(window.add_panel.place_button)
            canvas_shown(qtbot, window)  # the placed widget's view too
            assert window.center.isVisible() and len(window.controller.canvas.widgets) > 0
            assert window.size() == QtCore.QSize(1024, 600) and problems(window) == []
            tap(window.connection.connect_button)  # disconnected: the longest state word
            qtbot.waitUntil(lambda: window.connection.state is ConnectionState.CLOSED, timeout=TIMEOUT_MS)
            settle()
            assert window.size() == QtCore.QSize(1024, 600) and problems(window) == []
            window.canvas_actions["display"].trigger()  # the dialog itself
            settle()
            assert problems(window.display.dialog) == []
            window.display.dialog.close()
        finally:
            window.shutdown()
