"""The app's Record control on a Foxglove robot, and on a fleet of one rosbridge robot and one Foxglove robot,
through the real window: the canvases' topics land in each robot's file with their own schemas and bytes,
and what the operator did (a widget's publish, a parameter set in the Parameters panel: the operator tap)
lands on ``/rcon/operator/...`` in the file of the robot it went to."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from app_helpers import TIMEOUT_MS, entry_point_plugins, open_window, tap, tap_item
from mcap.reader import make_reader
from qtpy import QtWidgets
from qtpy.QtTest import QTest
from rogue_widget import CMD, RoguePlugin

from rcon_core.bridge import ConnectionState
from rcon_core.canvas import Binding, Document, Geometry, Workspace, WorkspaceStore
from rcon_core.canvas.robots import Robot
from rcon_core.foxglove.testing import FoxPeer
from rcon_core.msgs import TypeRegistry
from rcon_core.record.schema import OPERATOR_DEFINITION, OPERATOR_TYPE

pytestmark = pytest.mark.usefixtures("qapp", "transport")  # every test runs on each WebSocket transport
pytest.importorskip("rcon_widgets_std")
pytest.importorskip("rcon_widgets_sensors")


@pytest.fixture
def plugins():
    pm = entry_point_plugins()
    pm.register(RoguePlugin(view="rogue_widget_view:RogueView"), "rogue")
    return pm


@pytest.fixture
def peer():
    p = FoxPeer()
    p.start_talking()
    yield p
    p.stop()


def read(path: Path) -> tuple[Any, dict[str, Any], dict[str, list[bytes]]]:
    with open(path, "rb") as f:
        reader = make_reader(f)
        header, summary = reader.get_header(), reader.get_summary()
        msgs: dict[str, list[bytes]] = {}
        for _s, ch, m in reader.iter_messages():
            msgs.setdefault(ch.topic, []).append(m.data)
    assert summary is not None
    return header, {c.topic: (summary.schemas.get(c.schema_id), c) for c in summary.channels.values()}, msgs


def operator_events(msgs: dict[str, list[bytes]], kind: str, ros2: bool) -> list[dict[str, Any]]:
    reg = TypeRegistry.standard(ros2=ros2)
    reg.add_msg_text(OPERATOR_TYPE, OPERATOR_DEFINITION)
    decode = reg.deserialize_cdr if ros2 else reg.deserialize_ros1
    return [decode(OPERATOR_TYPE, d) for d in msgs.get(f"/rcon/operator/{kind}", [])]


def hosted(window, qtbot, widget_id):
    qtbot.waitUntil(lambda: (h := window.host.hosted.get(widget_id)) is not None and h.view is not None,
                    timeout=TIMEOUT_MS)
    return window.host.hosted[widget_id]


def set_param_in_panel(window, qtbot, name: str, text: str) -> None:
    panel = window.params_panel
    window.side.setCurrentWidget(panel)
    qtbot.waitUntil(lambda: panel.item(name) is not None and not panel.busy, timeout=TIMEOUT_MS)
    tap_item(panel.tree, panel.tree.indexFromItem(panel.item(name)))
    panel.edit_value.setFocus()
    panel.edit_value.selectAll()
    QTest.keyClicks(panel.edit_value, text)
    tap(panel.set_button)
    qtbot.waitUntil(lambda: window.confirm_dialog.isVisible(), timeout=TIMEOUT_MS)
    tap(window.confirm_dialog.findChild(QtWidgets.QPushButton, "confirmYes"))
    qtbot.waitUntil(lambda: panel.status.text().startswith("✓"), timeout=TIMEOUT_MS)


def test_record_control_on_a_foxglove_robot(qtbot, tmp_path, plugins, peer):
    win = open_window(qtbot, tmp_path / "cfg", plugins, url=peer.url, wait_connected=True,
                      topics=("/pose", "/camera/compressed"))
    try:
        canvas = win.controller.canvas.id
        pose = win.doc.add_widget(canvas, "std.label", Binding("/pose", "geometry_msgs/msg/Pose", "subscribe",
                                                               ("position.y",)), Geometry(24, 24, 240, 120), {})
        image = win.doc.add_widget(canvas, "sensors.image", Binding("/camera/compressed", "foxglove.CompressedImage",
                                                                    "subscribe"), Geometry(288, 24, 320, 240), {})
        rogue = win.doc.add_widget(canvas, "test.rogue", Binding("/cmd_vel", "geometry_msgs/Twist", "publish"),
                                   Geometry(24, 300, 240, 120), {}, "Lab's widget")
        lab = hosted(win, qtbot, rogue.id)
        hosted(win, qtbot, pose.id)
        hosted(win, qtbot, image.id)
        control = win.record_control
        control.directory = tmp_path / "rec"
        control.button.click()  # ● Rec
        assert control.recording is not None and control.recording.active
        qtbot.waitUntil(lambda: control.recording.status().messages >= 20, timeout=TIMEOUT_MS)
        before = len(peer.received)
        lab.view.model.publish(CMD)  # the lab's widget sends: over clientPublish, recorded below it
        qtbot.waitUntil(lambda: any(t == "/cmd_vel" for t, _e, _d in peer.received[before:]), timeout=TIMEOUT_MS)
        set_param_in_panel(win, qtbot, "/boat.max_speed", "1.75")
        assert peer.params["/boat.max_speed"].get_value() == 1.75
        qtbot.waitUntil(lambda: control.recording.status().events >= 2, timeout=TIMEOUT_MS)
        control.button.click()  # ■ Stop
        assert not control.recording.active and control.recording.status().problem is None, \
            control.recording.status()
    finally:
        win.shutdown()
    [path] = list((tmp_path / "rec").glob("rcon-*.mcap"))
    header, chans, msgs = read(path)
    assert header.profile == ""  # the robot has json, CDR and protobuf channels
    schema, ch = chans["/pose"]
    assert (schema.name, schema.encoding, ch.message_encoding) == ("geometry_msgs/msg/Pose", "ros2msg", "cdr")
    reg = TypeRegistry.standard(ros2=True)
    assert msgs["/pose"] and all(reg.deserialize_cdr("geometry_msgs/msg/Pose", d)["position"]["y"] == 2.0
                                 for d in msgs["/pose"])
    schema, ch = chans["/camera/compressed"]
    assert (schema.name, schema.encoding, ch.message_encoding) == ("foxglove.CompressedImage", "protobuf",
                                                                   "protobuf")
    from google.protobuf import descriptor_pb2, descriptor_pool, message_factory

    pool = descriptor_pool.DescriptorPool()
    for fd in descriptor_pb2.FileDescriptorSet.FromString(schema.data).file:
        pool.Add(fd)
    frame = message_factory.GetMessageClass(pool.FindMessageTypeByName(schema.name)).FromString(
        msgs["/camera/compressed"][0])
    assert frame.format == "jpeg" and frame.data[:2] == b"\xff\xd8"  # the peer's JPEG, as it sent it
    sent = operator_events(msgs, "publish", ros2=True)
    assert any(e["widget"] == rogue.id and e["name"] == "/cmd_vel" and e["outcome"] == "sent" for e in sent), sent
    params = operator_events(msgs, "param", ros2=True)
    assert [(e["name"], e["data"], e["outcome"]) for e in params] == [("/boat.max_speed", "1.75", "ok")]


def test_record_control_on_a_fleet_of_a_rosbridge_robot_and_a_foxglove_robot(qtbot, tmp_path, plugins, peer,
                                                                              sim_thread):
    ws = Workspace.new("Mixed")
    ws.robots = [Robot("r-1", "Alpha"), Robot("r-2", "Fox", url=peer.url)]
    doc = Document(ws)
    page = doc.current.id
    battery = doc.add_widget(page, "std.label", Binding("/battery", "sensor_msgs/BatteryState", "subscribe",
                                                        ("percentage",)), Geometry(16, 16, 240, 112), {})
    pose = doc.add_widget(page, "std.label", Binding("/pose", "geometry_msgs/msg/Pose", "subscribe",
                                                     ("position.y",), robot="r-2"), Geometry(272, 16, 240, 112), {})
    drive_1 = doc.add_widget(page, "test.rogue", Binding("/cmd_vel", "geometry_msgs/Twist", "publish"),
                             Geometry(16, 160, 240, 112), {})
    drive_2 = doc.add_widget(page, "test.rogue", Binding("/cmd_vel", "geometry_msgs/Twist", "publish", robot="r-2"),
                             Geometry(272, 160, 240, 112), {})
    (tmp_path / "cfg").mkdir(parents=True)
    WorkspaceStore(tmp_path / "cfg" / "workspace.json").save(ws)
    win = open_window(qtbot, tmp_path / "cfg", plugins, url=sim_thread.url, wait_connected=True)
    try:
        chips = win.fleet_ui.chips.chips
        qtbot.waitUntil(lambda: all(c.state is ConnectionState.CONNECTED for c in chips.values()),
                        timeout=TIMEOUT_MS)
        assert win.fleet_ui.links.link("r-2").client.protocol == "foxglove"
        labs = [hosted(win, qtbot, w.id) for w in (drive_1, drive_2)]
        hosted(win, qtbot, battery.id)
        hosted(win, qtbot, pose.id)
        control = win.record_control
        control.directory = tmp_path / "rec"
        control.button.click()
        qtbot.waitUntil(lambda: len(control.recording.robots) == 2 and control.recording.status().messages >= 20,
                        timeout=TIMEOUT_MS)
        before = len(peer.received)
        for lab in labs:
            lab.view.model.publish(CMD)
        sim_thread.wait_for_published_sync("/cmd_vel", lambda m: m.get("linear", {}).get("x") == CMD["linear"]["x"])
        qtbot.waitUntil(lambda: any(t == "/cmd_vel" for t, _e, _d in peer.received[before:]), timeout=TIMEOUT_MS)
        qtbot.waitUntil(lambda: control.recording.status().events >= 2, timeout=TIMEOUT_MS)
        qtbot.waitUntil(lambda: all(rec is not None and all(sink.stats.per_topic.get(t) for t in want)
                                    for (_c, rec, sink), want in zip(
                                        (control.recording.robots["r-1"], control.recording.robots["r-2"]),
                                        (["/battery"], ["/pose"]), strict=True)), timeout=TIMEOUT_MS)
        control.button.click()
    finally:
        win.shutdown()
    files = {p.name.rsplit("-", 1)[-1]: p for p in (tmp_path / "rec").glob("rcon-*.mcap")}
    assert set(files) == {"Alpha.mcap", "Fox.mcap"}
    header, chans, msgs = read(files["Alpha.mcap"])  # the rosbridge robot: as before
    assert header.profile == "ros1" and "/battery" in msgs and "/pose" not in chans
    sent = operator_events(msgs, "publish", ros2=False)
    assert [e["widget"] for e in sent if e["name"] == "/cmd_vel"] == [drive_1.id] and sent[0]["robot"] == "Alpha"
    header, chans, msgs = read(files["Fox.mcap"])  # the Foxglove robot: its channels as advertised
    assert header.profile == "" and "/battery" not in chans
    assert chans["/pose"][1].message_encoding == "cdr" and msgs["/pose"]
    sent = operator_events(msgs, "publish", ros2=True)
    assert [e["widget"] for e in sent if e["name"] == "/cmd_vel"] == [drive_2.id] and sent[0]["robot"] == "Fox"
