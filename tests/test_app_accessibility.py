"""Every control has an accessible name and role (issue 21.14): a walk over the widget tree of the real
window against the sim fails on any control a screen reader could not name or say what it is. Walked: the
demo (each canvas in Operate and Edit mode, each side panel tab, the add panel's pages, the Display and
Robots dialogs) and a canvas holding one of every bundled widget, each bound to something of the robot it
fits (a ROS 2 sim, so the Action widget has an action)."""

from __future__ import annotations

import pytest
from app_helpers import TIMEOUT_MS, choose_kind, open_window, settle, tap, tap_topic

from rcon_core.app.accessibility import NO_ROLES, nameless_controls, role_of
from rcon_core.app.demo import demo_workspace
from rcon_core.canvas import Binding, Canvas, Geometry, WidgetInstance, Workspace, new_id
from rcon_core.plugins import Role
from rcon_core.sim.server import SimServer

pytestmark = pytest.mark.usefixtures("qapp")
PACKAGES = ("rcon_widgets_std", "rcon_widgets_sensors", "rcon_widgets_map")


@pytest.fixture(scope="module")
def bundled():
    from app_helpers import entry_point_plugins

    for name in PACKAGES:
        pytest.importorskip(name)
    return entry_point_plugins()


def walk(window, where: str, found: dict[str, str]) -> None:
    settle()
    for line in nameless_controls(window):
        found.setdefault(line, where)


def test_the_demo_has_no_nameless_control(qtbot, tmp_path, bundled):
    found: dict[str, str] = {}
    with SimServer.in_thread(port=0) as robot:
        window = open_window(qtbot, tmp_path, bundled, demo=lambda: demo_workspace(bundled), url=robot.url,
                             wait_connected=True, topics=("/battery",))
        try:
            for locked in (True, False):
                if window.controller.canvas.locked != locked:
                    tap(window.lock_button if locked else window.edit_button)
                for k in range(window.tabs.count()):
                    window.switch_canvas(k)
                    qtbot.waitUntil(lambda: all(h.view is not None for h in window.host.hosted.values()
                                                if h.widget in window.controller.canvas.widgets),
                                    timeout=TIMEOUT_MS)
                    walk(window, f"canvas {k}, {'Operate' if locked else 'Edit'}", found)
            for k in range(window.side.count()):
                window.side.setCurrentIndex(k)
                walk(window, f"side tab {window.side.tabText(k)}", found)
            # the add panel, page by page
            window.side.setCurrentIndex(0)
            tap_topic(window, "/battery")
            walk(window, "add panel: role", found)
            choose_kind(window, Role.SUBSCRIBE, "std.label")
            qtbot.waitUntil(lambda: window.add_panel.preview_frame is not None, timeout=TIMEOUT_MS)
            walk(window, "add panel: settings", found)
            window.add_panel.cancel()
            # the dialogs
            window.canvas_actions["display"].trigger()
            walk(window.display.dialog, "Display dialog", found)
            window.display.dialog.close()
            window.canvas_actions["robots"].trigger()
            walk(window.fleet_ui.robots_dialog, "Robots dialog", found)
            window.fleet_ui.robots_dialog.close()
        finally:
            window.shutdown()
    assert not found, "\n".join(f"{where}: {line}" for line, where in found.items())


def every_widget(plugins, catalog) -> Workspace:
    """One canvas with one of every bundled widget, each bound to the first thing of the robot it fits."""
    from rcon_core.app.draft import rank_widgets

    types = plugins.type_registry()
    canvas = Canvas(new_id("c"), "Every widget", locked=True)
    placed, x, y, row = set(), 16, 16, 0
    for role in Role:
        for name, type_name in catalog.get(f"{role.noun}s", []):
            for candidate in rank_widgets(type_name, role, types, plugins):
                kind = candidate.spec.kind
                if kind in placed or not kind.startswith(("std.", "sensors.", "map.")):
                    continue
                placed.add(kind)
                w, h = (max(int(v) // 16 * 16, m) for v, m in zip(candidate.spec.default_size, (192, 128),
                                                                   strict=True))
                if x + w > 1360:  # shelves: the next row below the tallest of this one
                    x, y, row = 16, y + row + 16, 0
                canvas.widgets.append(WidgetInstance(new_id("w"), kind, Binding(name, type_name, role,
                                                                                candidate.field_paths),
                                                     Geometry(x, y, w, h), {}, ""))
                x, row = x + w + 16, max(row, h)
    return Workspace([canvas], canvas.id)


def test_every_bundled_widget_names_its_controls(qtbot, tmp_path, bundled):
    kinds = {spec.kind for spec in bundled.widgets()}
    found: dict[str, str] = {}
    with SimServer.in_thread(port=0, ros2=True) as robot:
        scout = open_window(qtbot, tmp_path / "scout", bundled, url=robot.url, wait_connected=True,
                            topics=("/battery",))
        qtbot.waitUntil(lambda: bool(scout.catalog.get("actions")), timeout=TIMEOUT_MS)
        catalog = dict(scout.catalog)
        scout.shutdown()
        workspace = every_widget(bundled, catalog)
        placed = {w.kind for w in workspace.canvases[0].widgets}
        assert placed == kinds, f"no robot thing fits {sorted(kinds - placed)}"
        window = open_window(qtbot, tmp_path / "all", bundled, demo=lambda: workspace, url=robot.url,
                             wait_connected=True, size=(1400, 1000))
        try:
            hosted = list(window.host.hosted.values())
            qtbot.waitUntil(lambda: all(h.view is not None for h in hosted), timeout=TIMEOUT_MS)
            for h in hosted:  # each widget's view: a name, and a role that says what it is
                view = h.view
                assert view.accessibleName() or h.widget.kind, h.widget.kind
                if view.property("accessibleRole"):
                    assert role_of(view) not in NO_ROLES, h.widget.kind
            walk(window, "every widget, Operate", found)
            tap(window.edit_button)
            walk(window, "every widget, Edit", found)
        finally:
            window.shutdown()
    assert not found, "\n".join(f"{where}: {line}" for line, where in found.items())
