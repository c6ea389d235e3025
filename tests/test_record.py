"""The flight recorder: MCAP files of a robot's topics and of what the operator sent (``rcon_core/record``),
read back with the ``mcap`` package and ``rosbags`` (readers RCON did not write)."""

from __future__ import annotations

import errno
import os
from pathlib import Path
from typing import Any

import pytest
from mcap.reader import make_reader
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_typestore

from rcon_core.msgs import TypeRegistry
from rcon_core.record import writer as writer_mod
from rcon_core.record.ingest import LINK_TOPIC, OPERATOR_PREFIX, RobotRecorder
from rcon_core.record.schema import OPERATOR_DEFINITION
from rcon_core.record.writer import McapSink
from rcon_core.sim import SimServer
from rcon_core.testing import connected, until


def read_mcap(path: Any) -> tuple[Any, Any, list[tuple[Any, Any, Any]]]:
    with open(path, "rb") as f:
        reader = make_reader(f)
        header, summary = reader.get_header(), reader.get_summary()
        messages = list(reader.iter_messages())
    return header, summary, messages


async def record(server: SimServer, path: Path, *, topics: list[str] | None = None, all_topics: bool = False,
                 until_messages: int = 20, act: Any = None, **sink_options: Any) -> RobotRecorder:
    async with connected(server.url) as client:
        ros2 = (await client.detect_ros()).version == 2
        sink = McapSink(str(path), "ros2" if ros2 else "ros1", **sink_options)
        rec = RobotRecorder(client, sink, ros2=ros2, robot="boat", topics=topics, all_topics=all_topics)
        await rec.start()
        if act is not None:
            await act(client)
        await until(lambda: sink.stats.messages >= until_messages or sink.stopped,
                    what="messages recorded")
        rec.stop()
    sink.close()
    rec.sink = sink
    return rec


async def test_ros1_topics_are_recorded_raw_with_the_robots_definitions(sim: SimServer, tmp_path: Path) -> None:
    path = tmp_path / "run.mcap"
    await record(sim, path, topics=["/odom", "/gps/fix"], until_messages=15)
    header, summary, messages = read_mcap(path)
    assert header.profile == "ros1"
    chans = {c.topic: c for c in summary.channels.values()}
    odom_schema = summary.schemas[chans["/odom"].schema_id]
    assert (odom_schema.name, odom_schema.encoding, chans["/odom"].message_encoding) == \
        ("nav_msgs/Odometry", "ros1msg", "ros1")
    text = odom_schema.data.decode()
    assert text.startswith("std_msgs/Header header") and "MSG: geometry_msgs/PoseWithCovariance" in text
    assert summary.chunk_indexes and summary.chunk_indexes[0].compression == "zstd"
    odoms = [(m.log_time, m.publish_time, m.data) for _s, c, m in messages if c.topic == "/odom"]
    assert odoms
    # the bytes are the robot's own ROS 1 serialization; publish_time is the header stamp
    reg = TypeRegistry.standard()
    msg = reg.deserialize_ros1("nav_msgs/Odometry", odoms[-1][2])
    stamp = msg["header"]["stamp"]
    assert odoms[-1][1] == stamp["secs"] * 1_000_000_000 + stamp["nsecs"]
    assert abs(odoms[-1][0] - odoms[-1][1]) < 5_000_000_000
    # and a reader that is not RCON's decodes it from the schema in the file
    ts = get_typestore(Stores.EMPTY)
    from rosbags.typesys import get_types_from_msg

    ts.register(get_types_from_msg(text, "nav_msgs/msg/Odometry"))
    other = ts.deserialize_ros1(odoms[-1][2], "nav_msgs/msg/Odometry")
    assert other.pose.pose.position.x == pytest.approx(msg["pose"]["pose"]["position"]["x"])


async def test_ros2_recording_opens_in_rosbags(sim_ros2: SimServer, tmp_path: Path) -> None:
    path = tmp_path / "run2.mcap"
    await record(sim_ros2, path, all_topics=True, until_messages=40)
    header, summary, _messages = read_mcap(path)
    assert header.profile == "ros2"
    assert {c.message_encoding for c in summary.channels.values()} == {"cdr"}
    decoded: dict[str, int] = {}
    with AnyReader([path], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
        for conn, _t, raw in reader.messages():
            reader.deserialize(raw, conn.msgtype)
            decoded[conn.topic] = decoded.get(conn.topic, 0) + 1
    assert {"/odom", "/imu/data", LINK_TOPIC} <= set(decoded)


async def test_what_the_operator_sent_is_recorded_with_its_widget_and_robot(sim: SimServer, tmp_path: Path) -> None:
    """Every publish, call and response, and parameter set that leaves through the client is written on
    /rcon/operator/<kind>, tapped below the widgets (the node's id is the widget's)."""
    path = tmp_path / "op.mcap"

    async def act(client: Any) -> None:
        node = client.node("teleop-7")
        pub = node.advertise("/cmd_vel", "geometry_msgs/Twist")
        await until(lambda: client.session.adverts["/cmd_vel"].active)
        pub.publish({"linear": {"x": 0.5, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.1}})
        await node.call_service("/lights/set", {"data": True})
        await node.call_service("/rosapi/topics", {})  # the app's own question: not the operator's
        await client.params.set("/kingfisher/max_speed", 2.5)
        await sim.wait_for_published("/cmd_vel")

    rec = await record(sim, path, topics=["/battery"], until_messages=1, act=act)
    assert rec.events == 4
    _h, summary, messages = read_mcap(path)
    reg = TypeRegistry.standard()
    reg.add_msg_text("rcon_msgs/OperatorEvent", OPERATOR_DEFINITION)
    events = [(c.topic, reg.deserialize_ros1("rcon_msgs/OperatorEvent", m.data)) for _s, c, m in messages
              if c.topic.startswith(OPERATOR_PREFIX)]
    kinds = [(t.rsplit("/", 1)[-1], e["widget"], e["name"], e["outcome"]) for t, e in events]
    assert kinds == [("publish", "teleop-7", "/cmd_vel", "sent"), ("call", "teleop-7", "/lights/set", ""),
                     ("response", "teleop-7", "/lights/set", "ok"), ("param", "params", "/kingfisher/max_speed", "ok")]
    assert all(e["robot"] == "boat" for _t, e in events)
    assert '"x":0.5' in events[0][1]["data"] and events[0][1]["type"] == "geometry_msgs/Twist"


async def test_a_type_without_any_definition_is_recorded_as_json_and_said(tmp_path: Path,
                                                                          monkeypatch: pytest.MonkeyPatch) -> None:
    """A robot whose rosapi cannot describe a lab's type (no full text, message_details fails) and an RCON
    that does not know it: the topic is recorded as JSON, and the recorder says so."""
    from rcon_core.sim.graph import ServiceFailure

    async with SimServer(robot=False) as server, connected(server.url) as client:
        server.types.registry.add_msg_text("lab_msgs/Winch", "float64 rope\nstring state\n")
        monkeypatch.setattr(server.rosapi, "_full_text", lambda _type: "")

        def no_details(_args: Any) -> Any:
            raise ServiceFailure("error processing request: Unable to load the type")

        server.services["/rosapi/message_details"].handler = no_details
        pub = client.node("lab").advertise("/winch", "lab_msgs/Winch")
        await until(lambda: client.session.adverts["/winch"].active)
        sink = McapSink(str(tmp_path / "lab.mcap"), "ros1")
        rec = RobotRecorder(client, sink, ros2=False, topics=["/winch"], registry=TypeRegistry.standard())
        await rec.start()
        await until(lambda: server.topic_subscriber_count("/winch") == 1)
        await until(lambda: (pub.publish({"rope": 1.5, "state": "out"}) or True) and sink.stats.per_topic.get("/winch"),
                    what="the winch recorded")
        rec.stop()
    sink.close()
    assert any("no definition of lab_msgs/Winch" in p and "JSON" in p for p in rec.problems)
    _h, summary, messages = read_mcap(tmp_path / "lab.mcap")
    chan = next(c for c in summary.channels.values() if c.topic == "/winch")
    assert (chan.message_encoding, chan.schema_id) == ("json", 0)
    assert b'"rope":1.5' in next(m.data for _s, c, m in messages if c.topic == "/winch")


def test_the_disk_budget_warns_then_closes_the_file_properly(tmp_path: Path) -> None:
    sink = McapSink(str(tmp_path / "b.mcap"), "ros1", budget=200_000, chunk_size=20_000, compression="none")
    sink.add_channel("/blob", "std_msgs/String", "ros1msg", b"string data\n", "ros1")
    for i in range(400):
        sink.write("/blob", i, i, os.urandom(1000))
    sink.close()
    assert sink.warning is not None and "90 %" in sink.warning
    assert sink.problem is not None and "budget" in sink.problem
    assert sink.stats.dropped > 0
    _h, summary, messages = read_mcap(tmp_path / "b.mcap")  # closed with a summary
    assert summary is not None and 150 <= len(messages) < 400


def test_a_full_disk_stops_the_recording_says_so_and_leaves_it_readable(tmp_path: Path,
                                                                         monkeypatch: pytest.MonkeyPatch) -> None:
    """The OS refuses writes past 300 kB (ENOSPC): the recorder says the disk is full, counts what it
    drops, and the file holds every chunk written before (read through the recovery path)."""
    limit = {"left": 300_000}
    real_write = os.write

    def full_disk(fd: int, data: Any) -> int:
        if limit["left"] < len(data):
            raise OSError(errno.ENOSPC, "No space left on device")
        limit["left"] -= len(data)
        return real_write(fd, data)

    def full_disk_v(fd: int, pieces: Any) -> int:
        size = sum(memoryview(p).nbytes for p in pieces)
        if limit["left"] < size:
            raise OSError(errno.ENOSPC, "No space left on device")
        limit["left"] -= size
        return real_writev(fd, pieces)

    real_writev = os.writev
    monkeypatch.setattr(writer_mod.os, "write", full_disk)
    monkeypatch.setattr(writer_mod.os, "writev", full_disk_v)  # a chunk goes to the OS in one writev
    problems: list[str] = []
    path = tmp_path / "full.mcap"
    sink = McapSink(str(path), "ros1", chunk_size=50_000, compression="none", on_problem=problems.append)
    sink.add_channel("/blob", "std_msgs/String", "ros1msg", b"string data\n", "ros1")
    for i in range(600):
        sink.write("/blob", i, i, os.urandom(1000))
    sink.close()
    assert problems == [sink.problem] and "disk is full" in problems[0]
    assert sink.stats.dropped > 0
    from rcon_core.record.recover import Recovered, read_complete

    found = Recovered()
    got = list(read_complete(str(path), found))
    assert 200 <= len(got) <= 300 and found.cut
    assert [m.log_time for _c, m in got] == list(range(len(got)))


def test_split_size_starts_new_files_each_with_every_channel(tmp_path: Path) -> None:
    sink = McapSink(str(tmp_path / "s.mcap"), "ros1", split_size=100_000, chunk_size=20_000, compression="none")
    sink.add_channel("/blob", "std_msgs/String", "ros1msg", b"string data\n", "ros1")
    for i in range(350):
        sink.write("/blob", i, i, os.urandom(1000))
    sink.close()
    assert [Path(f).name for f in sink.stats.files][:3] == ["s.mcap", "s_1.mcap", "s_2.mcap"]
    total = 0
    for f in sink.stats.files:
        _h, summary, messages = read_mcap(f)
        assert [c.topic for c in summary.channels.values()] == ["/blob"]
        total += len(messages)
    assert total == 350


async def test_follow_session_records_what_the_apps_other_consumers_subscribe_to(sim: SimServer,
                                                                                  tmp_path: Path) -> None:
    """A widget reading a topic beside its binding (a button showing /lights/state): the app's recorder
    follows the client's subscriptions, so that topic is in the file too."""
    path = tmp_path / "follow.mcap"
    async with connected(sim.url) as client:
        sink = McapSink(str(path), "ros1")
        rec = RobotRecorder(client, sink, ros2=False, topics=["/battery"], follow_session=True, discover_every=0.1)
        await rec.start()
        client.node("lights-button").subscribe("/lights/state", lambda _m: None)
        await until(lambda: "/lights/state" in rec.topics, what="the followed topic")
        await client.node("op").call_service("/lights/set", {"data": True})
        await until(lambda: sink.stats.per_topic.get("/lights/state"), what="the lights recorded")
        rec.stop()
    sink.close()
    _h, summary, _m = read_mcap(path)
    assert {"/battery", "/lights/state"} <= {c.topic for c in summary.channels.values()}


async def test_action_goals_feedback_results_and_cancels_are_recorded(sim_ros2: SimServer, tmp_path: Path) -> None:
    """ROS 2: a goal, its feedback and its result, and a cancelled goal, on /rcon/operator/goal, feedback,
    result and cancel, with the node that sent them."""
    path = tmp_path / "goals.mcap"

    async def act(client: Any) -> None:
        node = client.node("action-3")
        goal = node.send_action_goal("/fibonacci", "action_tutorials_interfaces/action/Fibonacci", {"order": 3},
                                     feedback=lambda _v: None)
        await goal.result(timeout=20)
        other = node.send_action_goal("/fibonacci", "action_tutorials_interfaces/action/Fibonacci", {"order": 40},
                                      feedback=lambda _v: None)
        await until(lambda: other.last_feedback is not None, what="the second goal running")
        other.cancel()
        await other.result(timeout=20)

    rec = await record(sim_ros2, path, topics=["/battery"], until_messages=1, act=act)
    _h, _summary, messages = read_mcap(path)
    reg = TypeRegistry.standard(ros2=True)
    reg.add_msg_text("rcon_msgs/msg/OperatorEvent", OPERATOR_DEFINITION)
    events = [(c.topic.rsplit("/", 1)[-1], reg.deserialize_cdr("rcon_msgs/msg/OperatorEvent", m.data))
              for _s, c, m in messages if c.topic.startswith(OPERATOR_PREFIX)]
    kinds = [k for k, _e in events]
    assert kinds.count("goal") == 2 and kinds.count("result") == 2 and kinds.count("cancel") == 1
    assert kinds.count("feedback") >= 2
    results = [e for k, e in events if k == "result"]
    assert [e["outcome"] for e in results] == ["succeeded", "canceled"]
    assert all(e["widget"] == "action-3" and e["name"] == "/fibonacci" for _k, e in events)
    assert rec.events == len(events)
