"""The app on a Foxglove robot (the foxglove-sdk peer, ``rcon_core/foxglove/testing.py``), driven as a person would,
offscreen: the URL alone connects (the protocol found by subprotocol), the connection bar names the server,
the side panel lists its topics, each of the three ways to add a widget works (a topic first, a widget from
the palette then its topic, a new topic to publish on), the Parameters panel lists and sets its parameters,
and one canvas holds a rosbridge robot and a Foxglove robot side by side.

``RCON_SCREENSHOTS=DIR`` saves PNGs of the window there."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from app_helpers import TIMEOUT_MS, choose_kind, entry_point_plugins, open_window, tap, tap_item, tap_topic
from qtpy import QtGui, QtWidgets
from qtpy.QtTest import QTest

from rcon_core.bridge import ConnectionState
from rcon_core.canvas import Binding, Document, Geometry, Workspace, WorkspaceStore
from rcon_core.canvas.robots import Robot
from rcon_core.foxglove.testing import FoxPeer
from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import Role

pytestmark = pytest.mark.usefixtures("qapp", "transport")  # every test runs on each WebSocket transport
pytest.importorskip("rcon_widgets_std")
pytest.importorskip("rcon_widgets_sensors")
pytest.importorskip("rcon_widgets_map")

REG = TypeRegistry.standard(ros2=True)


def snap(window: QtWidgets.QWidget, name: str) -> None:
    out = os.environ.get("RCON_SCREENSHOTS", "")
    if out and out != "1":
        QtWidgets.QApplication.processEvents()
        Path(out).mkdir(parents=True, exist_ok=True)
        window.grab().save(str(Path(out) / f"{name}.png"))


@pytest.fixture(scope="module")
def plugins():
    return entry_point_plugins()


@pytest.fixture
def peer():
    p = FoxPeer()
    p.start_talking()
    yield p
    p.stop()


@pytest.fixture
def window(qtbot, tmp_path, peer, plugins):
    win = open_window(qtbot, tmp_path / "config", plugins, url=peer.url, wait_connected=True,
                      topics=("/gps", "/camera/compressed", "/pose"))
    yield win
    win.shutdown()


def hosted_state(window, wid: str):
    model = window.host.hosted[wid].model
    return model.state if model is not None else None


def test_the_url_alone_connects_and_the_bar_names_the_foxglove_server(window, peer, qtbot):
    assert window.link.client.protocol == "foxglove"
    text = window.connection.message.text()
    assert text.startswith("Foxglove WebSocket · fox-peer · cdr, json") and "no actions" in text
    assert window.services.item("/reset") is not None
    # what the protocol cannot do is said where the operator looks for it
    window.side.setCurrentWidget(window.actions_list)
    qtbot.waitUntil(lambda: window.actions_list.empty.text().startswith("The Foxglove WebSocket protocol has no "
                                                                         "actions"), timeout=TIMEOUT_MS)
    assert window.actions_list.empty.isVisible()
    snap(window, "foxglove-connected")


def test_pathway_1_a_topic_first_a_map_on_the_foxglove_fix(window, qtbot, peer):
    tap_topic(window, "/gps")
    panel = choose_kind(window, Role.SUBSCRIBE, "map.gps")
    assert not panel.problems(), panel.problems()
    tap(panel.place_button)
    [inst] = window.controller.canvas.widgets
    assert (inst.kind, inst.binding.name, inst.binding.type) == ("map.gps", "/gps", "foxglove.LocationFix")
    window.lock_button.click()

    def fixed():
        state = hosted_state(window, inst.id)
        value = state.value if state is not None else None
        return value is not None and any(t.has_position for t in value.tracks) and state.error is None

    try:
        qtbot.waitUntil(fixed, timeout=TIMEOUT_MS)
    except Exception:
        c = window.link.client
        raise AssertionError(f"no fix: {peer.subscribed} {hosted_state(window, inst.id)} {c.stats} {c.state} "
                             f"{list(c.session.topics)} {c.session.subs} {list(c.session.by_topic)}") from None
    snap(window, "foxglove-map")


def test_pathway_2_a_widget_from_the_palette_then_its_topic_an_image(window, qtbot):
    window.side.setCurrentWidget(window.palette_panel)
    tree = window.palette_panel.tree
    tap_item(tree, tree.indexFromItem(window.palette_panel.item("sensors.image")))
    panel = window.add_panel
    panel.choose_target("/camera/compressed")
    assert panel.draft.binding.name == "/camera/compressed" and not panel.problems(), panel.problems()
    tap(panel.place_button)
    [inst] = window.controller.canvas.widgets
    window.lock_button.click()

    def shown():
        state = hosted_state(window, inst.id)
        return state is not None and state.count > 0 and state.value is not None and state.error is None

    try:
        qtbot.waitUntil(shown, timeout=TIMEOUT_MS)
    except Exception:
        raise AssertionError(f"no image: {hosted_state(window, inst.id)}") from None
    frame = hosted_state(window, inst.id).value
    assert "jpeg" in frame.info  # decoded from the Foxglove CompressedImage (64x48, red and black)
    qtbot.wait(200)  # the view paints the frame on its next pass
    snap(window, "foxglove-image")


def test_pathway_3_a_new_topic_to_publish_on_reaches_the_robot_as_cdr(window, peer, qtbot):
    window.side.setCurrentWidget(window.palette_panel)
    tree = window.palette_panel.tree
    tap_item(tree, tree.indexFromItem(window.palette_panel.item("std.textview")))
    panel = window.add_panel
    panel.role_combo.setCurrentIndex(panel.role_combo.findText(Role.PUBLISH.value))
    box = panel.choose_new_topic()
    box.name_edit.setFocus()
    QTest.keyClicks(box.name_edit, "ops/chat")
    tap_item(box.type_list, box.type_list.indexFromItem(box.item_for("std_msgs/msg/String")))  # the robot spells ROS 2 names
    assert panel.problems() == [], panel.problems()
    tap(panel.place_button)
    [inst] = window.controller.canvas.widgets
    window.lock_button.click()
    hosted = window.host.hosted[inst.id]
    qtbot.waitUntil(lambda: hosted.view is not None and hosted.view.input is not None
                    and hosted.view.input.isVisible(), timeout=TIMEOUT_MS)
    hosted.view.input.setFocus()
    QTest.keyClicks(hosted.view.input, "hello foxglove")
    from qtpy import QtCore

    QTest.keyClick(hosted.view.input, QtCore.Qt.Key.Key_Return)
    qtbot.waitUntil(lambda: any(t == "/ops/chat" for t, _e, _d in peer.received), timeout=TIMEOUT_MS)
    topic, encoding, data = next(r for r in peer.received if r[0] == "/ops/chat")
    assert encoding == "cdr" and REG.deserialize_cdr("std_msgs/msg/String", data) == {"data": "hello foxglove"}


def test_the_parameters_panel_lists_and_sets_the_foxglove_parameters(window, peer, qtbot):
    panel = window.params_panel
    window.side.setCurrentWidget(panel)
    qtbot.waitUntil(lambda: panel.item("/boat.max_speed") is not None and not panel.busy, timeout=TIMEOUT_MS)
    assert panel.shown_value("/boat.max_speed") == "2.5"
    tap_item(panel.tree, panel.tree.indexFromItem(panel.item("/boat.max_speed")))
    panel.edit_value.setFocus()
    panel.edit_value.selectAll()
    QTest.keyClicks(panel.edit_value, "1.25")
    tap(panel.set_button)
    qtbot.waitUntil(lambda: window.confirm_dialog.isVisible(), timeout=TIMEOUT_MS)
    tap(window.confirm_dialog.findChild(QtWidgets.QPushButton, "confirmYes"))
    qtbot.waitUntil(lambda: panel.status.text().startswith("✓"), timeout=TIMEOUT_MS)
    assert peer.params["/boat.max_speed"].get_value() == 1.25
    snap(window, "foxglove-params")
    # a value the server does not take is said refused, not set
    tap_item(panel.tree, panel.tree.indexFromItem(panel.item("/boat.name")))
    panel.edit_value.setFocus()
    panel.edit_value.selectAll()
    QTest.keyClicks(panel.edit_value, "heron")
    tap(panel.set_button)
    qtbot.waitUntil(lambda: window.confirm_dialog.isVisible(), timeout=TIMEOUT_MS)
    tap(window.confirm_dialog.findChild(QtWidgets.QPushButton, "confirmYes"))
    qtbot.waitUntil(lambda: "kingfisher" in panel.status.text(), timeout=TIMEOUT_MS)
    assert peer.params["/boat.name"].get_value() == "kingfisher"


def test_one_canvas_with_a_rosbridge_robot_and_a_foxglove_robot(qtbot, tmp_path, sim_thread, peer, plugins):
    robots = [Robot("r-1", "Alpha"), Robot("r-2", "Fox", url=peer.url)]
    ws = Workspace.new("Mixed")
    ws.robots = robots
    doc = Document(ws)
    battery = doc.add_widget(doc.current.id, "std.label", Binding("/battery", "sensor_msgs/BatteryState",
                                                                  "subscribe", ("percentage",)),
                             Geometry(16, 16, 240, 112), {})
    pose = doc.add_widget(doc.current.id, "std.label", Binding("/pose", "geometry_msgs/msg/Pose", "subscribe",
                                                               ("position.y",), robot="r-2"),
                          Geometry(272, 16, 240, 112), {})
    (tmp_path / "config").mkdir(parents=True, exist_ok=True)
    WorkspaceStore(tmp_path / "config" / "workspace.json").save(ws)
    win = open_window(qtbot, tmp_path / "config", plugins, url=sim_thread.url, wait_connected=True)
    try:
        chips = win.fleet_ui.chips.chips
        qtbot.waitUntil(lambda: all(c.state is ConnectionState.CONNECTED for c in chips.values()),
                        timeout=TIMEOUT_MS)
        assert win.fleet_ui.links.link("r-2").client.protocol == "foxglove"
        assert win.link.client.protocol == "rosbridge"

        def value(wid: str):
            state = hosted_state(win, wid)
            return getattr(state.value, "raw", None) if state is not None and not state.link_down else None

        try:
            qtbot.waitUntil(lambda: value(battery.id) is not None and value(pose.id) == 2.0, timeout=TIMEOUT_MS)
        except Exception:
            raise AssertionError(f"{hosted_state(win, battery.id)} {hosted_state(win, pose.id)}") from None
        snap(win, "fleet-rosbridge-and-foxglove")
    finally:
        win.shutdown()


def test_the_protocol_line_is_information_and_a_failure_is_a_problem(window, qtbot):
    """Found by a person: the bar showed "Foxglove WebSocket · fox-peer …" in the red bold problem style."""
    from rcon_core.app.theme import colour

    bar = window.connection
    assert bar.message.text().startswith("Foxglove WebSocket")
    assert bar.message.property("role") == "info"
    info_colour = bar.message.palette().color(bar.message.foregroundRole()).name()
    assert info_colour == QtGui.QColor(colour("TEXT")).name() and not bar.message.font().bold()
    window.connect_to("ws://127.0.0.1:9")  # nothing listens there: a problem, in the problem style
    qtbot.waitUntil(lambda: "refused" in bar.message.text(), timeout=TIMEOUT_MS)
    assert bar.message.property("role") == "problem"
    problem_colour = bar.message.palette().color(bar.message.foregroundRole()).name()
    assert problem_colour == QtGui.QColor(colour("PROBLEM")).name() != info_colour and bar.message.font().bold()


def test_a_foxglove_url_enters_the_history_once_server_info_arrived(qtbot, tmp_path, peer, plugins, monkeypatch):
    """Found by a person: with a rosauth secret in force (the environment's, or one saved for the URL), a
    Foxglove URL entered the URL history only after the auth probe -- a service call that waits out the link's
    service grace period (about 1 s).  Foxglove has no rosauth: serverInfo is the answer, no probe is made.
    Here the probe never ends (as a robot that never answers it), so only a link that makes none remembers."""
    import asyncio

    import rcon_core.app.link as app_link
    from rcon_core.app.link import LinkSettings

    probed: list[str] = []

    async def endless_probe(client, timeout: float = 5.0) -> None:
        probed.append(client.protocol)
        await asyncio.sleep(3600)

    monkeypatch.setattr(app_link, "confirm_auth", endless_probe)
    win = open_window(qtbot, tmp_path / "config", plugins)
    try:
        win.connection.overrides = LinkSettings(secret="a-rosauth-secret")
        win.connect_to(peer.url)
        qtbot.waitUntil(lambda: win.connection.state is ConnectionState.CONNECTED, timeout=TIMEOUT_MS)
        assert win.link.client.protocol == "foxglove"
        qtbot.waitUntil(lambda: peer.url in win.config.url_history, timeout=TIMEOUT_MS)
        assert "foxglove" not in probed
    finally:
        win.shutdown()
