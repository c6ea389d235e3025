"""The app on the canvas package: store (corrupt/newer files, --layout), placeholders, the runtime on the
bridge thread (prompt repaint, one repaint per frame), focus loss reaching the models."""

from __future__ import annotations

import json

import pytest
from app_helpers import open_window as open_app_window
from qtpy import QtCore, QtWidgets
from test_app_window import ProbePlugin, ProbeSettings, ProbeView, robot  # noqa: F401 - fixture re-used

from rcon_core.app.draft import Draft, Target
from rcon_core.app.main_window import MainWindow
from rcon_core.app.widget_host import FRAME_INTERVAL, WidgetHost
from rcon_core.canvas import Binding, Canvas, Geometry, WidgetInstance, Workspace, dumps_workspace
from rcon_core.plugins import Accepts, PluginManager, Role, WidgetModel, WidgetSpec, WidgetState, hookimpl
from rcon_core.testing import flushed_sync

pytestmark = pytest.mark.usefixtures("qapp")


class PadModel(WidgetModel):
    """A teleop-like model: must stop driving when the operator looks away."""

    focus_losses = 0

    def on_focus_lost(self) -> None:
        PadModel.focus_losses += 1


class PadView(QtWidgets.QLabel):
    def __init__(self, model: PadModel) -> None:
        super().__init__("pad")

    def refresh(self, state) -> None:
        self.setText(f"pad: {state.count}")


class PadPlugin:
    @hookimpl
    def rcon_register_widgets(self, registry) -> None:
        registry.add(WidgetSpec(kind="apptest.pad", title="Pad", model=PadModel,
                                view=f"{__name__}:PadView", roles={Role.PUBLISH}, default_size=(192, 112),
                                accepts=Accepts(messages=["twist"])))


def plugins() -> PluginManager:
    pm = PluginManager(environ={})
    pm.register(ProbePlugin(), name="apptest")
    pm.register(PadPlugin(), name="apptestpad")
    return pm


def open_window(qtbot, tmp_path, url=None, layout=None) -> MainWindow:
    """This module's plugins' window at the offscreen screen's size, on ``layout``, connected to ``url``."""
    return open_app_window(qtbot, tmp_path / "cfg", plugins(), url=url, size=None, layout=layout,
                           wait_connected=True)


def probe(widget_id: str, topic="/battery", type_name="sensor_msgs/BatteryState", path="percentage",
          kind="apptest.probe", role=Role.SUBSCRIBE, settings=None) -> WidgetInstance:
    return WidgetInstance(widget_id, kind, Binding(topic, type_name, role, (path,) if path else ()),
                          Geometry(32, 32, 192, 112), settings if settings is not None else {"caption": topic},
                          widget_id)


def running(window, qtbot, widget_id):
    hosted = window.host.hosted[widget_id]
    qtbot.waitUntil(lambda: hosted.view is not None, timeout=10_000)
    return hosted


@pytest.mark.parametrize("content, why", [
    (b'{"format": "rcon-workspace", "version": 1, "canvases": [', "not valid JSON"),
    (json.dumps({"format": "rcon-workspace", "version": 99, "canvases": []}).encode(), "newer"),
])
def test_unreadable_layout_is_reported_and_never_overwritten(qtbot, tmp_path, content, why):
    path = tmp_path / "site.json"
    path.write_bytes(content)
    window = open_window(qtbot, tmp_path, layout=path)
    try:
        assert window.banner.isVisible()
        text = window.banner.text()
        assert "site.json" in text and "will not be overwritten" in text
        assert why in text.lower() or why in text
        # edits still work in the window, but nothing is written over the file
        window.controller.add_canvas("Scratch")
        window.controller.set_locked(True)
    finally:
        window.shutdown()
    assert path.read_bytes() == content
    assert list(tmp_path.glob("site.json.unreadable-*"))  # and a copy was kept next to it


def test_layout_option_opens_a_store_file_and_saves_back_to_it(qtbot, tmp_path, robot):  # noqa: F811
    path = tmp_path / "ops.json"
    ops = Canvas("c-ops", "Ops", [probe("w-batt"), probe("w-old", kind="retired.gauge",
                                                            settings={"needle": [1, 2], "note": "é"})])
    nav = Canvas("c-nav", "Nav", [probe("w-lights", "/lights/state", "std_msgs/Bool", "data")])
    path.write_text(dumps_workspace(Workspace([ops, nav], "c-ops")), encoding="utf-8")
    window = open_window(qtbot, tmp_path, robot.url, layout=path)
    try:
        assert [window.tabs.tabText(i) for i in range(window.tabs.count())] == ["Ops", "Nav"]
        qtbot.waitUntil(lambda: robot.topic_subscriber_count("/battery") == 1, timeout=10_000)
        # the widget whose plugin is missing: a placeholder saying so, and its settings are kept
        old = window.host.hosted["w-old"].frame
        qtbot.waitUntil(lambda: "not installed" in getattr(old.view, "text", lambda: "")(), timeout=10_000)
        assert "retired.gauge" in old.view.text()
        window.switch_canvas(1)
        qtbot.waitUntil(lambda: robot.topic_subscriber_count("/lights/state") == 1, timeout=10_000)
        qtbot.waitUntil(lambda: robot.topic_subscriber_count("/battery") == 0, timeout=10_000)
    finally:
        window.shutdown()
    saved = json.loads(path.read_text(encoding="utf-8"))
    assert saved["current"] == "c-nav"
    [kept] = [w for w in saved["canvases"][0]["widgets"] if w["id"] == "w-old"]
    assert kept["kind"] == "retired.gauge" and kept["settings"] == {"needle": [1, 2], "note": "é"}


def test_values_are_painted_without_waiting_for_the_frame_clock(qtbot, tmp_path, robot):  # noqa: F811
    window = open_window(qtbot, tmp_path, robot.url)
    try:
        spec = window.plugins.widget("apptest.probe")
        draft = Draft(spec, Role.SUBSCRIBE, Target("/battery", "sensor_msgs/BatteryState", ("percentage",)),
                      spec.make_settings({"caption": "Charge"}), "Charge")
        inst = window.controller.add_draft(draft)
        hosted = running(window, qtbot, inst.id)
        window.clock.stop()  # from now on only the bridge thread's wake-ups can refresh the view
        painted = hosted.view.painted
        wakes = window.waker.wakes
        qtbot.waitUntil(lambda: hosted.view.painted >= painted + 3, timeout=10_000)
        assert window.waker.wakes > wakes
        assert hosted.view.text().startswith("Charge: ") and hosted.view.text() != "Charge: None"
    finally:
        window.shutdown()


class CountingModel:
    """Just enough of a model for the host (what ``HostedModel`` says the host reads): a state whose seq the
    test moves."""

    view_only = None
    dry_run = False
    shows_every_robot = False

    def __init__(self) -> None:
        self.seq = 0
        self.settings = ProbeSettings(caption="n")

    def child_models(self) -> list:
        return []

    @property
    def state(self) -> WidgetState:
        return WidgetState(value=self.seq, count=self.seq, seq=self.seq, running=True)

    def problems(self) -> list[str]:
        return []


def test_host_repaints_a_widget_at_most_once_per_frame_and_the_latest_value_wins(qtbot):
    pm = PluginManager(environ={})
    pm.register(ProbePlugin(), name="apptest")
    host = WidgetHost(pm)
    host.set_link_up(True)
    widget = probe("w-1")
    frame = host.build_frame(widget)
    qtbot.addWidget(frame)
    frame.show()
    model = CountingModel()
    host.attach("w-1", model)
    view: ProbeView = host.hosted["w-1"].view
    seen: list[int] = []
    host.paint_hooks.append(lambda _h, state: seen.append(state.value))
    t = 100.0
    model.seq = 1
    assert host.refresh({"w-1"}, now=t) is None and seen == [1]
    model.seq = 2
    due = host.refresh({"w-1"}, now=t + 0.004)  # too soon: waits for its frame interval
    assert seen == [1] and due == pytest.approx(FRAME_INTERVAL - 0.004)
    model.seq = 3
    host.refresh(set(), now=t + 0.010)
    assert seen == [1]
    host.refresh(set(), now=t + FRAME_INTERVAL + 0.001)  # the waiting widget, with its latest value
    assert seen == [1, 3] and view.painted == 2
    assert host.refresh(None, now=t + 1.0) is None and seen == [1, 3]  # unchanged: no repaint


def test_focus_loss_and_leaving_the_canvas_reach_the_models(qtbot, tmp_path, robot):  # noqa: F811
    window = open_window(qtbot, tmp_path, robot.url)
    try:
        spec = window.plugins.widget("apptest.pad")
        draft = Draft(spec, Role.PUBLISH, Target("/cmd_vel", "geometry_msgs/Twist"), None, "Drive")
        inst = window.controller.add_draft(draft)
        running(window, qtbot, inst.id)
        before = PadModel.focus_losses
        app = QtWidgets.QApplication.instance()
        app.applicationStateChanged.emit(QtCore.Qt.ApplicationState.ApplicationInactive)
        qtbot.waitUntil(lambda: PadModel.focus_losses == before + 1, timeout=5_000)
        window.controller.add_canvas("Other")  # leaving the canvas: focus lost, then the pad stops
        qtbot.waitUntil(lambda: PadModel.focus_losses >= before + 2, timeout=5_000)
        qtbot.waitUntil(lambda: window.host.hosted[inst.id].model is None, timeout=5_000)
    finally:
        window.shutdown()


def test_undo_is_refused_in_operator_mode_and_the_lock_is_not_an_undo_step(qtbot, tmp_path):
    window = open_window(qtbot, tmp_path)
    try:
        spec = window.plugins.widget("apptest.probe")
        draft = Draft(spec, Role.SUBSCRIBE, Target("/battery", "sensor_msgs/BatteryState", ("percentage",)),
                      spec.make_settings({"caption": "x"}), "x")
        inst = window.controller.add_draft(draft)
        window.controller.set_locked(True)
        assert not window.controller.undo()
        assert [w.id for w in window.controller.canvas.widgets] == [inst.id]
        window.controller.set_locked(False)
        assert window.controller.undo() and window.controller.canvas.widgets == []
        assert not window.controller.canvas.locked
        # an offline widget still runs (placeholder-free) and says the link is down
        window.controller.redo()
        hosted = running(window, qtbot, inst.id)
        qtbot.waitUntil(lambda: hosted.frame.badge.status == "LINK DOWN", timeout=5_000)
    finally:
        window.shutdown()


def test_previews_of_controls_never_reach_the_robot(qtbot, tmp_path, robot):  # noqa: F811
    window = open_window(qtbot, tmp_path, robot.url)
    panel = window.add_panel
    try:
        qtbot.waitUntil(lambda: window.topics.item("/cmd_vel") is not None, timeout=10_000)
        # a widget that shows: its preview is live on the robot
        panel.start_from_topic("/depth", "sensor_msgs/Range")
        panel.choose_role(Role.SUBSCRIBE)
        panel.choose_candidate(0)
        qtbot.waitUntil(lambda: robot.topic_subscriber_count("/depth") == 1, timeout=10_000)
        # a control: previewed offline, nothing advertised, and the frame says so
        panel.cancel()
        qtbot.waitUntil(lambda: robot.topic_subscriber_count("/depth") == 0, timeout=10_000)
        panel.start_from_widget(window.plugins.widget("apptest.pad"))
        panel.choose_target("/cmd_vel")
        assert not panel.problems()
        preview_id = window.preview.widget.id
        hosted = running(window, qtbot, preview_id)
        qtbot.waitUntil(lambda: hosted.frame.badge.status == "PREVIEW ONLY", timeout=5_000)
        assert hosted.model.publish({"linear": {"x": 1.0}})  # what a touch on the pad would do
        # a marker through the window's (only) link to the robot arrives; the preview's command did not
        flushed_sync(window.link.thread, window.link.client, robot, qtbot=qtbot)
        assert robot.published("/cmd_vel") == []
        # placed, the same widget is live
        window.place_draft()
        [placed] = window.controller.canvas.widgets
        live = running(window, qtbot, placed.id)
        qtbot.waitUntil(lambda: bool(live.model.publish({"linear": {"x": 0.5}}) and robot.published("/cmd_vel")),
                        timeout=10_000)
    finally:
        window.shutdown()
