"""The flight recorder in the real window: the Record control records what the robot sent and what the
operator did (through any widget: tapped below them), and a recording opened as the robot plays with a
timeline whose commands go nowhere."""

from __future__ import annotations

from pathlib import Path

import pytest
from app_helpers import entry_point_plugins, settle, window_session
from mcap.reader import make_reader
from qtpy import QtWidgets
from record_helpers import DEMO_BAG
from rogue_widget import CMD, RoguePlugin

from rcon_core.bridge import ConnectionState
from rcon_core.canvas import Binding, Geometry
from rcon_core.msgs import TypeRegistry
from rcon_core.record.schema import OPERATOR_DEFINITION, OPERATOR_TYPE
from rcon_core.sim.playback import played_in_thread

pytestmark = pytest.mark.usefixtures("qapp")


@pytest.fixture
def plugins():
    pm = entry_point_plugins()
    pm.register(RoguePlugin(view="rogue_widget_view:RogueView"), "rogue")
    return pm


def place(window, kind, binding, x, title, settings=None):
    return window.doc.add_widget(window.controller.canvas.id, kind, binding, Geometry(x, 24, 240, 160),
                                 settings or {}, title)


def hosted(window, qtbot, widget_id):
    qtbot.waitUntil(lambda: (h := window.host.hosted.get(widget_id)) is not None and h.view is not None,
                    timeout=10_000)
    return window.host.hosted[widget_id]


def test_record_control_records_the_canvas_topics_and_what_the_operator_sent(qtbot, tmp_path, plugins,
                                                                            sim_thread):
    win = next(window_session(qtbot, tmp_path / "cfg", plugins, url=sim_thread.url, wait_connected=True))
    battery = place(win, "std.label", Binding("/battery", "sensor_msgs/BatteryState", "subscribe",
                                              ("percentage",)), 24, "Battery")
    rogue = place(win, "test.rogue", Binding("/cmd_vel", "geometry_msgs/Twist", "publish"), 288, "Lab's widget")
    label = hosted(win, qtbot, battery.id)
    lab = hosted(win, qtbot, rogue.id)
    control = win.record_control
    control.directory = tmp_path / "rec"
    control.button.click()  # ● Rec
    assert control.recording is not None and control.recording.active
    assert control.indicator.isVisible() and control.indicator.reading.startswith("REC 00:0")
    qtbot.waitUntil(lambda: control.indicator.text() == control.indicator.reading, timeout=5_000)  # laid out
    qtbot.waitUntil(lambda: control.recording.status().messages >= 3, timeout=10_000)
    lab.view.model.publish(CMD)  # a lab's widget sends: recorded below it, at its port's node
    sim_thread.wait_for_published_sync("/cmd_vel", lambda m: m.get("linear", {}).get("x") == CMD["linear"]["x"])
    qtbot.waitUntil(lambda: control.recording.status().events >= 1, timeout=10_000)
    qtbot.waitUntil(lambda: label.model.state.count > 0, timeout=10_000)
    control.button.click()  # ■ Stop: the file is closed properly
    assert not control.recording.active and not control.indicator.isVisible()
    assert "Recorded" in win.notice.label.text()
    files = list((tmp_path / "rec").glob("rcon-*.mcap"))
    assert len(files) == 1
    with open(files[0], "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        messages = list(reader.iter_messages())
    topics = {c.topic for c in summary.channels.values()}
    assert {"/battery", "/rcon/link", "/rcon/operator/publish"} <= topics
    reg = TypeRegistry.standard()
    reg.add_msg_text(OPERATOR_TYPE, OPERATOR_DEFINITION)
    sent = [reg.deserialize_ros1(OPERATOR_TYPE, m.data) for _s, c, m in messages if c.topic == "/rcon/operator/publish"]
    assert any(e["widget"] == rogue.id and e["name"] == "/cmd_vel" and e["outcome"] == "sent" for e in sent)
    assert all(e["robot"] == "Robot" for e in sent)


def test_a_recording_opened_as_the_robot_plays_seeks_and_sends_nothing(qtbot, tmp_path, plugins):
    with played_in_thread(str(DEMO_BAG), paused=True) as (server, player):
        win = next(window_session(qtbot, tmp_path / "cfg", plugins))
        odom = place(win, "std.label", Binding("/odom", "nav_msgs/Odometry", "subscribe",
                                               ("pose.pose.position.x",)), 24, "x")
        rogue = place(win, "test.rogue", Binding("/cmd_vel", "geometry_msgs/Twist", "publish"), 288, "Teleop")
        bar = win.fleet_ui.recordings.play_first(server, player)
        assert win.replay is bar and "commands go nowhere" in bar.words.text()
        qtbot.waitUntil(lambda: win.connection.state.value == "connected", timeout=10_000)
        qtbot.waitUntil(lambda: bool(hosted(win, qtbot, rogue.id).model.view_only), timeout=10_000)
        lab = hosted(win, qtbot, rogue.id)  # the recording's robot is view-only
        assert "recording" in lab.model.view_only
        lab.view.model.publish(CMD)  # the view's own code sends anyway: refused at its port, said
        qtbot.waitUntil(lambda: "recording" in (lab.model.state.error or ""), timeout=10_000)
        bar.set_speed(8.0)
        bar.play_button.click()
        qtbot.waitUntil(lambda: player.playing and player.position > 1.0, timeout=10_000)
        qtbot.waitUntil(lambda: hosted(win, qtbot, odom.id).model.state.count > 0, timeout=10_000)
        bar.play_button.click()  # pause
        qtbot.waitUntil(lambda: not player.playing, timeout=5_000)
        bar.seek(5.05)  # the widgets start again on the state at 5.05 s
        qtbot.waitUntil(lambda: abs(player.position - 5.05) < 0.2, timeout=5_000)
        x = hosted(win, qtbot, odom.id)
        qtbot.waitUntil(lambda: x.model.state.value is not None and abs(x.model.state.value.raw + 4.0) < 1e-6,
                        timeout=10_000)  # odometry number 50: half a turn, x = -4
        bar.poll(0.0)
        assert bar.time_label.text().startswith("0:05")
        assert player.absorbed == {}  # nothing even reached the recording
        assert server.ops_received[("publish", "/cmd_vel")] == 0
        win.shutdown()


def test_rcon_play_rejects_a_file_that_is_not_a_recording(tmp_path: Path, capsys) -> None:
    from rcon_core.cli.main import main

    bad = tmp_path / "x.mcap"
    bad.write_text("not mcap")
    assert main(["--play", str(bad)]) == 2
    assert "cannot play" in capsys.readouterr().err


def test_recording_at_200_percent_text_on_a_1024_px_window_keeps_the_window_and_the_robots_host(
        qtbot, tmp_path, plugins, sim_thread):
    """At 200 % text the URL field takes the bar's room first (it shows which robot): recording then shows
    a red ● where the bar has no room for "REC 00:01" (the reading in its accessible name, the details in
    its tooltip), and the window stays 1024 px wide."""
    from rcon_core.app import theme
    from rcon_core.app.display_settings import set_display

    win = next(window_session(qtbot, tmp_path / "cfg", plugins, url=sim_thread.url, wait_connected=True,
                              size=(1024, 600)))
    try:
        set_display(win.config, None, text_size=200)
        control = win.record_control
        control.directory = tmp_path / "rec"
        control.set_compact(True)
        line = win.connection.url.lineEdit()
        qtbot.waitUntil(lambda: "127.0.0.1" in line.shown_text(), timeout=5_000)
        control.action.trigger()  # Canvas ▾ → ● Record every robot
        qtbot.waitUntil(lambda: control.indicator.isVisible() and control.indicator.text() == "●", timeout=5_000)
        settle()
        assert win.width() == 1024 and "127.0.0.1" in line.shown_text(), (win.width(), line.shown_text())
        assert control.indicator.accessibleName().startswith("recording: REC 00:0")
        assert "MB" in control.indicator.toolTip()
        control.action.trigger()
        assert not control.recording.active and not control.indicator.isVisible()
    finally:
        win.shutdown()
        theme.apply(QtWidgets.QApplication.instance(), theme.DEFAULT_THEME, 100)


def test_the_compact_control_of_a_small_screen_keeps_the_bar_no_wider(qtbot, tmp_path, plugins, sim_thread):
    """On a screen below 1100 px the button is left out (Canvas ▾ → Record every robot starts and stops)
    and the short indicator takes the round-trip time's place while recording."""
    win = next(window_session(qtbot, tmp_path / "cfg", plugins, url=sim_thread.url, wait_connected=True,
                              size=(1280, 800)))
    control = win.record_control
    control.directory = tmp_path / "rec"
    control.set_compact(False)
    qtbot.waitUntil(lambda: control.button.isVisible(), timeout=5_000)
    settle()
    wide = win.connection.minimumSizeHint().width()
    control.set_compact(True)
    qtbot.waitUntil(lambda: win.connection.minimumSizeHint().width() < wide, timeout=5_000)
    assert not control.button.isVisible()
    narrow = win.connection.minimumSizeHint().width()
    control.action.trigger()  # Canvas ▾ → ● Record every robot
    assert control.recording.active and control.action.text() == "■ Stop recording"
    qtbot.waitUntil(lambda: control.indicator.text().startswith("REC 00:0"), timeout=5_000)
    assert "MB" not in control.indicator.text() and "MB" in control.indicator.toolTip()
    assert not win.connection.latency_label.isVisible()
    settle()
    assert win.connection.minimumSizeHint().width() <= narrow + 40
    control.action.trigger()
    assert not control.recording.active and win.connection.latency_label.isVisible()


def test_a_compact_recording_stopped_after_the_link_went_shows_no_round_trip(qtbot, tmp_path, plugins, sim_thread):
    """Found by a person on a small screen: stopping a recording put the round-trip time back on the bar even
    when the robot was no longer connected (the recorder and the bar each set the label's visibility; now
    the bar alone decides, the recorder only asks for its place)."""
    win = next(window_session(qtbot, tmp_path / "cfg", plugins, url=sim_thread.url, wait_connected=True,
                              size=(1024, 600)))
    control = win.record_control
    control.directory = tmp_path / "rec"
    control.set_compact(True)
    latency = win.connection.latency_label
    control.action.trigger()
    assert control.recording.active and not latency.isVisible()
    win.connection.connect_button.click()  # Disconnect
    qtbot.waitUntil(lambda: win.connection.state is not ConnectionState.CONNECTED, timeout=5_000)
    control.action.trigger()  # stop
    assert not control.recording.active
    settle()
    assert not latency.isVisible()
    win.connection.connect_button.click()  # Connect: the round trip comes back with the link
    qtbot.waitUntil(lambda: win.connection.state is ConnectionState.CONNECTED, timeout=10_000)
    qtbot.waitUntil(latency.isVisible, timeout=5_000)
    control.action.trigger()  # recording again while connected: its indicator takes the place
    qtbot.waitUntil(lambda: not latency.isVisible(), timeout=5_000)
    control.action.trigger()
