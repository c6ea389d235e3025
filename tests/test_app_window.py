"""The app end to end against the embedded robot: adding widgets three ways, canvases, editing, restart.

A small label-like widget plugin is defined here and registered directly with the plugin manager, so
these tests do not depend on the widget packages.
"""

from __future__ import annotations

import attrs
import pytest
from app_helpers import open_window, tap, tap_item
from qtpy import QtCore, QtGui, QtWidgets
from qtpy.QtTest import QTest

from rcon_core.app.config import AppConfig
from rcon_core.app.main_window import MainWindow
from rcon_core.plugins import Accepts, PluginManager, Role, WidgetModel, WidgetSpec, hookimpl

pytestmark = pytest.mark.usefixtures("qapp")


# ------------------------------------------------------------------------------------- test widget
@attrs.define
class ProbeSettings:
    """A label widget: needs a caption before it can be placed."""

    caption: str = ""
    digits: int = 2

    def problems(self) -> list[str]:
        return [] if self.caption.strip() else ["caption is empty"]


class ProbeModel(WidgetModel):
    stale_after = 30.0


class ProbeView(QtWidgets.QLabel):
    def __init__(self, model: ProbeModel) -> None:
        super().__init__("—")
        self.model = model
        self.painted = 0

    def refresh(self, state) -> None:
        self.painted += 1
        self.setText(f"{self.model.settings.caption}: {state.value!r}")


class ProbePlugin:
    @hookimpl
    def rcon_register_widgets(self, registry) -> None:
        registry.add(
            WidgetSpec(
                kind="apptest.probe",
                title="Probe",
                model=ProbeModel,
                view=f"{__name__}:ProbeView",
                roles={Role.SUBSCRIBE, Role.PUBLISH, Role.CALL},
                accepts=Accepts(fields=["float", "bool"], prefer=("percentage", "data")),
                settings=ProbeSettings,
                default_size=(192, 112),
            )
        )


def make_plugins() -> PluginManager:
    pm = PluginManager(environ={})
    pm.register(ProbePlugin(), name="apptest")
    return pm


# ------------------------------------------------------------------------------------- fixtures
@pytest.fixture
def robot():
    from rcon_core.sim.server import SimServer

    with SimServer.in_thread(port=0) as server:
        yield server


@pytest.fixture
def make_window(qtbot, tmp_path, robot):
    made: list[MainWindow] = []

    def make(connect: bool = True) -> MainWindow:  # a 1280x800 tablet (the offscreen screen is 800x800)
        window = open_window(qtbot, tmp_path / "config", make_plugins(), url=robot.url if connect else None,
                             wait_connected=True, topics=("/battery",))
        made.append(window)
        return window

    yield make
    for window in made:
        window.shutdown()


def running(window: MainWindow, qtbot, widget_id: str):
    """The widget's hosted entry once the canvas runtime (bridge thread) built its model and view."""
    hosted = window.host.hosted[widget_id]
    qtbot.waitUntil(lambda: hosted.model is not None and hosted.view is not None, timeout=10_000)
    return hosted


def fill_caption(window: MainWindow, text: str) -> None:
    editor = window.add_panel.form.editor("caption")
    editor.setFocus()
    QTest.keyClicks(editor, text)


# ------------------------------------------------------------------------------------- the three ways
def test_add_from_topic_subscribes_on_the_robot(make_window, robot, qtbot):
    window = make_window()
    topics = window.topics.tree
    tap_item(topics, topics.indexFromItem(window.topics.item("/battery")))
    panel = window.add_panel
    assert panel.isVisible() and panel.stack.currentWidget() is panel.role_page
    assert not panel.role_buttons[Role.CALL].isVisible()  # a topic offers subscribe/publish only
    tap(panel.role_buttons[Role.SUBSCRIBE])
    assert panel.stack.currentWidget() is panel.widgets_page
    assert panel.candidates.count() >= 1
    tap_item(panel.candidates, panel.candidates.model().index(0, 0))
    assert panel.stack.currentWidget() is panel.settings_page
    # not configured yet: the preview carries the warning and nothing can be placed
    assert panel.preview_frame.problems.isVisibleTo(panel.preview_frame)
    assert "caption is empty" in panel.preview_frame.problems.text()
    assert not panel.place_button.isEnabled()
    fill_caption(window, "Charge")
    assert not panel.preview_frame.problems.isVisibleTo(panel.preview_frame)
    assert panel.place_button.isEnabled()
    tap(panel.place_button)
    [inst] = window.controller.canvas.widgets
    assert inst.kind == "apptest.probe"
    assert inst.binding.name == "/battery" and inst.binding.field_paths == ("percentage",)
    assert inst.settings["caption"] == "Charge"
    qtbot.waitUntil(lambda: robot.topic_subscriber_count("/battery") >= 1, timeout=10_000)
    view = running(window, qtbot, inst.id).view
    qtbot.waitUntil(lambda: view.text().startswith("Charge: ") and view.text() != "Charge: None", timeout=10_000)


def test_add_from_service_calls_the_robot(make_window, robot, qtbot):
    window = make_window()
    window.side.setCurrentWidget(window.services)
    qtbot.waitUntil(lambda: window.services.item("/lights/set") is not None, timeout=10_000)
    services = window.services.tree
    tap_item(services, services.indexFromItem(window.services.item("/lights/set")))
    panel = window.add_panel
    assert not panel.role_buttons[Role.SUBSCRIBE].isVisible()
    tap(panel.role_buttons[Role.CALL])
    assert panel.candidates.count() >= 1
    tap_item(panel.candidates, panel.candidates.model().index(0, 0))
    fill_caption(window, "Lights")
    tap(panel.place_button)
    [inst] = window.controller.canvas.widgets
    assert inst.binding.role is Role.CALL and inst.binding.name == "/lights/set"
    hosted = running(window, qtbot, inst.id)
    response = hosted.model.call({"data": True}).result(timeout=10)
    assert response["success"] is True
    view = hosted.view
    qtbot.waitUntil(lambda: "Lights:" in view.text(), timeout=5_000)


def test_add_from_palette_then_drop_on_canvas(make_window, robot, qtbot):
    window = make_window()
    window.side.setCurrentWidget(window.palette_panel)
    item = window.palette_panel.item("apptest.probe")
    tap_item(window.palette_panel.tree, window.palette_panel.tree.indexFromItem(item))
    panel = window.add_panel
    assert panel.stack.currentWidget() is panel.settings_page
    assert set(panel.problems()) >= {"no topic chosen", "caption is empty"}
    offered = [t for i in range(1, panel.target_combo.count()) if (t := panel.target_combo.itemData(i))]
    names = {t.name for t in offered}
    assert "/battery" in names and "/camera/front/image_raw" not in names  # compatible ones only
    with pytest.raises(ValueError, match="not compatible"):
        panel.choose_target("/camera/front/image_raw")
    panel.choose_target("/lights/state")
    fill_caption(window, "Lights on")
    assert panel.drag_handle.isEnabled() and not panel.problems()
    # the drag ends as a drop on the canvas surface
    surface = window.controller.surface
    mime = QtCore.QMimeData()
    mime.setData("application/x-rcon-widget-draft", QtCore.QByteArray(b"draft"))
    for etype in (QtCore.QEvent.Type.DragEnter, QtCore.QEvent.Type.DragMove):
        cls = QtGui.QDragEnterEvent if etype == QtCore.QEvent.Type.DragEnter else QtGui.QDragMoveEvent
        ev = cls(QtCore.QPoint(200, 150), QtCore.Qt.DropAction.CopyAction, mime,
                 QtCore.Qt.MouseButton.LeftButton, QtCore.Qt.KeyboardModifier.NoModifier)
        QtWidgets.QApplication.sendEvent(surface, ev)
    drop = QtGui.QDropEvent(QtCore.QPointF(203, 149), QtCore.Qt.DropAction.CopyAction, mime,
                            QtCore.Qt.MouseButton.LeftButton, QtCore.Qt.KeyboardModifier.NoModifier)
    QtWidgets.QApplication.sendEvent(surface, drop)
    [inst] = window.controller.canvas.widgets
    assert inst.binding.name == "/lights/state"
    assert (inst.geometry.x, inst.geometry.y) == (208, 144)  # snapped to the 16 px grid
    assert not panel.isVisible()
    qtbot.waitUntil(lambda: robot.topic_subscriber_count("/lights/state") >= 1, timeout=10_000)


def test_palette_says_so_when_no_widget_is_installed(qtbot, tmp_path):
    window = MainWindow(AppConfig(tmp_path), PluginManager(environ={}))
    qtbot.addWidget(window)
    try:
        assert window.palette_panel.empty.isVisibleTo(window.palette_panel)
        assert "No widget plugins are installed" in window.palette_panel.empty.text()
    finally:
        window.shutdown()


def test_window_keeps_qt_actions_and_its_actions_catalog_apart(qtbot, tmp_path):
    """The Actions catalog once sat on ``window.actions``, hiding ``QWidget.actions()`` (mypy found it)."""
    window = MainWindow(AppConfig(tmp_path), PluginManager(environ={}))
    qtbot.addWidget(window)
    try:
        assert window.quit_action in window.actions()  # Qt's own list of the window's actions
        assert window.side.indexOf(window.actions_list) >= 0
        assert window.side.tabText(window.side.indexOf(window.actions_list)) == "Actions"
    finally:
        window.shutdown()


def place_from_palette(window: MainWindow, caption: str) -> None:
    """What a person does: tap the widget in the palette, pick a topic, fill the caption, tap Place."""
    window.side.setCurrentWidget(window.palette_panel)
    item = window.palette_panel.item("apptest.probe")
    tap_item(window.palette_panel.tree, window.palette_panel.tree.indexFromItem(item))
    window.add_panel.choose_target("/battery")
    fill_caption(window, caption)
    tap(window.add_panel.place_button)


def test_place_finds_a_free_spot_in_view_then_below_and_focuses_the_new_widget(make_window, qtbot):
    window = make_window()
    window.activateWindow()
    QTest.qWaitForWindowActive(window)
    surface = window.controller.surface
    placed: list[str] = []
    for n in range(24):
        place_from_palette(window, f"w{n}")
        inst = window.controller.canvas.widgets[-1]
        placed.append(inst.id)
        frame = surface.frames[inst.id]
        # keyboard focus is on the new widget, not on the robot URL field (one key would replace the URL)
        focus = QtWidgets.QApplication.focusWidget()
        assert focus is frame or frame.isAncestorOf(focus), focus
        assert not window.connection.url.lineEdit().hasFocus()
    rects = [surface.frames[i].geometry() for i in placed]
    assert not [(a, b) for k, a in enumerate(rects) for b in rects[k + 1:] if a.intersects(b)]
    assert all(r.x() >= 16 and r.y() >= 16 and r.x() % 16 == 0 and r.y() % 16 == 0 for r in rects)
    # the first ones went into the visible part (the add panel was open then), in reading order
    assert (rects[0].x(), rects[0].y()) == (16, 16) and rects[1].y() == 16 and rects[1].x() > rects[0].right()
    # once the view is full, new ones go below the others (and the canvas scrolls to them)
    view = surface.scroll_area.viewport()
    assert max(r.bottom() for r in rects) > view.height()
    assert surface.scroll_area.verticalScrollBar().value() > 0
    last = surface.frames[placed[-1]]
    assert view.rect().intersects(QtCore.QRect(last.mapTo(view, QtCore.QPoint(0, 0)), last.size()))
