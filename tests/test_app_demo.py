"""The demo layout with the installed widget packages: real kinds, valid settings, running on the sim."""

from __future__ import annotations

import pytest
from qtpy.QtTest import QTest
from test_app_window import robot  # noqa: F401 - fixture re-used

from rcon_core.app.config import AppConfig
from rcon_core.app.demo import CAMERAS, DRIVE, SENSORS, VIDEO, demo_workspace
from rcon_core.app.main import load_plugins
from rcon_core.app.main_window import MainWindow
from rcon_core.bridge import ConnectionState
from rcon_core.canvas.runtime import MissingWidgetModel

pytestmark = pytest.mark.usefixtures("qapp")

#: the packages the demo is written for (tox installs all three)
PACKAGES = ("rcon_widgets_std", "rcon_widgets_sensors", "rcon_widgets_map")


@pytest.fixture(scope="module")
def plugins():
    for name in PACKAGES:
        pytest.importorskip(name, reason=f"the demo needs the {name} widget package installed")
    return load_plugins()


def test_every_demo_slot_uses_an_installed_kind_with_valid_settings(plugins):
    ws = demo_workspace(plugins)
    widgets = [w for c in ws.canvases for w in c.widgets]
    assert len(widgets) == len(DRIVE) + len(CAMERAS) + len(VIDEO) + len(SENSORS)
    for w in widgets:
        assert plugins.has_widget(w.kind), w.kind
        spec = plugins.widget(w.kind)
        assert w.binding.role in spec.roles, (w.title, w.binding.role)
        assert spec.settings_problems(w.settings) == [], (w.title, w.settings)
        assert w.binding.problems() == [], w.title
    kinds = {w.kind for w in widgets}
    assert {"sensors.image", "sensors.teleop", "map.gps", "std.label", "std.slider", "std.switch",
            "std.button", "std.textview"} <= kinds
    assert all(c.locked for c in ws.canvases)  # opened in operator mode: the widgets take touches


def test_demo_runs_on_the_robot_without_warnings(qtbot, tmp_path, plugins, robot):  # noqa: F811
    window = MainWindow(AppConfig(tmp_path), plugins)
    qtbot.addWidget(window)
    window.show()
    QTest.qWaitForWindowExposed(window)
    try:
        window.connect_to(robot.url)
        qtbot.waitUntil(lambda: window.connection.state is ConnectionState.CONNECTED, timeout=10_000)
        window.open_workspace(demo_workspace(plugins))
        for index in range(len(window.controller.workspace.canvases)):
            window.switch_canvas(index)
            canvas = window.controller.canvas
            hosted = [window.host.hosted[w.id] for w in canvas.widgets]
            qtbot.waitUntil(lambda hosted=hosted: all(h.view is not None for h in hosted), timeout=15_000)
            for h in hosted:
                assert not isinstance(h.model, MissingWidgetModel), h.widget.title
                assert h.model.problems() == [], (h.widget.title, h.model.problems())
                assert not h.frame.problems.isVisible(), h.widget.title
            subscribers = [h for h in hosted if h.widget.binding.role.value == "subscribe"]
            qtbot.waitUntil(lambda s=subscribers: all(h.model.state.count > 0 for h in s), timeout=15_000)
    finally:
        window.shutdown()
