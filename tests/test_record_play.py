"""``rcon sim --play``: recordings RCON did not write (rosbag1, rosbag2 sqlite3/mcap, rosbag2's own files)
served as a robot over rosbridge (``rcon_core/sim/playback.py``, ``rcon_core/record/files.py``)."""

from __future__ import annotations

import asyncio
import math
from typing import Any

import pytest
from record_helpers import (
    CDR_TEST,
    DEMO_BAG,
    DEMO_MCAP,
    DEMO_SQLITE3,
    TALKER_MCAP,
    TALKER_SQLITE3,
    playing,
)

from rcon_core.bridge import ServiceError
from rcon_core.bridge.topics import RawPayload
from rcon_core.record.files import RecordingError, open_recording
from rcon_core.testing import connected, until

DEMO_TOPICS = {"/odom": "nav_msgs/Odometry", "/gps/fix": "sensor_msgs/NavSatFix", "/map": "nav_msgs/OccupancyGrid",
               "/camera/image_raw": "sensor_msgs/Image", "/battery": "sensor_msgs/BatteryState"}


@pytest.mark.parametrize("path, kind, ros2", [(DEMO_BAG, "rosbag1", False), (DEMO_SQLITE3, "rosbag2", True),
                                              (DEMO_MCAP, "rosbag2", True),
                                              (DEMO_MCAP / "demo_mcap.mcap", "mcap", True)])
async def test_generated_bags_play_as_a_robot(path: Any, kind: str, ros2: bool) -> None:
    """rosapi lists the recording's topics with their types in the file's flavour, the definitions come
    from the file, and the messages arrive decoded as on a live robot: the odometry goes round its circle."""
    async with playing(path, rate=4.0) as (server, player), connected(server.url) as client:
        assert player.recording.kind == kind and server.ros2 is ros2
        listed = await client.rosapi.topics()
        for topic, type_name in DEMO_TOPICS.items():
            assert listed[topic] == (type_name.replace("/", "/msg/") if ros2 else type_name)
        details = await client.rosapi.message_details(listed["/odom"])
        assert details[0]["fieldnames"][:2] == ["header", "child_frame_id"]
        got: list[dict[str, Any]] = []
        client.node("t").subscribe("/odom", got.append)
        await until(lambda: len(got) >= 3, what="odometry from the recording")
    pos = got[-1]["pose"]["pose"]["position"]
    assert math.hypot(pos["x"], pos["y"]) == pytest.approx(4.0)
    stamp = got[-1]["header"]["stamp"]
    assert set(stamp) == ({"sec", "nanosec"} if ros2 else {"secs", "nsecs"})


@pytest.mark.parametrize("path", [DEMO_BAG, DEMO_MCAP])
async def test_cbor_raw_subscribers_get_the_recorded_bytes(path: Any) -> None:
    """A cbor-raw subscriber gets each message's bytes exactly as they are in the file."""
    with open_recording(path) as rec:
        recorded = [data for topic, _t, data in rec.messages() if topic == "/odom"]
    async with playing(path, rate=4.0, paused=True) as (server, player), connected(server.url) as client:
        got: list[RawPayload] = []
        client.node("rec").subscribe("/odom", got.append, raw=True)
        await until(lambda: server.topic_subscriber_count("/odom") == 1)
        await until(lambda: client.session.topics["/odom"].raw_type is not None, what="cbor-raw subscription")
        player.play()
        await until(lambda: len(got) >= 5, what="raw odometry")
    assert all(isinstance(p, RawPayload) for p in got)
    first = recorded.index(got[0].data)
    assert [p.data for p in got] == recorded[first:first + len(got)]


async def test_a_latched_topic_reaches_a_late_subscriber() -> None:
    """/map was published once at the start (latched in the bag); a subscriber that comes later gets it."""
    async with playing(DEMO_BAG, rate=8.0) as (server, player), connected(server.url) as client:
        await until(lambda: player.position > 2.0, what="the player past the map")
        maps: list[dict[str, Any]] = []
        client.node("late").subscribe("/map", maps.append)
        await until(lambda: maps, what="the latched map")
    assert maps[0]["info"]["width"] == 20 and len(maps[0]["data"]) == 400


async def test_commands_to_a_recording_go_nowhere_and_say_so() -> None:
    """A client's publish is accepted, logged and counted but not passed on; a call to a service the
    recording does not have fails with a sentence saying it is a recording."""
    async with playing(DEMO_BAG, rate=4.0) as (server, player), connected(server.url) as client:
        seen: list[dict[str, Any]] = []
        logs: list[dict[str, Any]] = []
        node = client.node("op")
        node.subscribe("/cmd_vel", seen.append, type="geometry_msgs/Twist")
        node.subscribe("/rosout", logs.append)
        pub = node.advertise("/cmd_vel", "geometry_msgs/Twist")
        await until(lambda: server.topic_subscriber_count("/cmd_vel") == 1)
        await until(lambda: (pub.publish({"linear": {"x": 1.0}}) or True) and player.absorbed["/cmd_vel"] >= 1,
                    what="the publish absorbed")
        with pytest.raises(ServiceError, match="recording"):
            await node.call_service("/dock", {})
        await until(lambda: any("go nowhere" in m.get("msg", "") for m in logs), what="the word on /rosout")
    assert server.published("/cmd_vel")  # it was received (and logged)...
    assert seen == []  # ...and went nowhere


async def test_seek_sends_the_latest_of_each_topic_before_that_time() -> None:
    async with playing(DEMO_BAG, paused=True) as (server, player), connected(server.url) as client:
        got: list[dict[str, Any]] = []
        batteries: list[dict[str, Any]] = []
        client.node("t").subscribe("/odom", got.append)
        client.node("b").subscribe("/battery", batteries.append)
        await until(lambda: server.topic_subscriber_count("/odom") == 1 and
                    server.topic_subscriber_count("/battery") == 1)
        player.seek(5.05)
        await until(lambda: got and batteries, what="the state at 5 s")
        assert not player.playing
    # odometry every 0.1 s from t0: the last one before 5.05 s is number 50 (angle 50/100 of a turn)
    pos = got[-1]["pose"]["pose"]["position"]
    assert (pos["x"], pos["y"]) == pytest.approx((4 * math.cos(math.pi), 4 * math.sin(math.pi)), abs=1e-9)
    assert batteries[-1]["voltage"] == pytest.approx(24.0 - 50 * 0.01)


async def test_forced_ros2_serves_a_ros1_bag_in_ros2_shapes() -> None:
    async with playing(DEMO_BAG, rate=4.0, ros2=True) as (server, _player), connected(server.url) as client:
        assert (await client.rosapi.topics())["/odom"] == "nav_msgs/msg/Odometry"
        got: list[dict[str, Any]] = []
        client.node("t").subscribe("/odom", got.append)
        raws: list[Any] = []
        client.node("r").subscribe("/gps/fix", raws.append, raw=True)
        await until(lambda: got and raws, what="odometry and a raw fix")
    assert set(got[0]["header"]) == {"stamp", "frame_id"}
    assert set(got[0]["header"]["stamp"]) == {"sec", "nanosec"}
    fix = raws[0]
    assert isinstance(fix, RawPayload) and fix.data[:4] == b"\x00\x01\x00\x00"  # CDR, made from the ROS 1 bytes


@pytest.mark.parametrize("path", [TALKER_MCAP, TALKER_SQLITE3, TALKER_MCAP / "talker.mcap"])
async def test_rosbag2s_own_talker_bags(path: Any) -> None:
    """Bags written by ROS 2's rosbag2 (its test resources): the talker's strings arrive; in the sqlite3
    one the file's placeholder definition of rcl_interfaces/msg/Log is not trusted, /rosout still decodes."""
    async with playing(path, rate=8.0, paused=True) as (server, player), connected(server.url) as client:
        said: list[dict[str, Any]] = []
        logs: list[dict[str, Any]] = []
        client.node("t").subscribe("/topic", said.append)
        client.node("l").subscribe("/rosout", logs.append)
        await until(lambda: server.topic_subscriber_count("/topic") and server.topic_subscriber_count("/rosout"))
        player.play()
        await until(lambda: said and any(m.get("name") == "minimal_publisher" for m in logs), what="the talker")
    assert said[0]["data"].startswith("Hello, world!")


async def test_rosbag2_cdr_test_types_come_from_the_file() -> None:
    """test_msgs/BasicTypes is in no standard set: its definition comes from the file (rosbag2's cdr_test)."""
    async with playing(CDR_TEST, rate=1.0) as (server, _player), connected(server.url) as client:
        basics: list[dict[str, Any]] = []
        client.node("t").subscribe("/test_topic", basics.append)
        await until(lambda: basics, what="a BasicTypes message (latched)")
        types = await client.rosapi.topics()
    assert types["/test_topic"] == "test_msgs/msg/BasicTypes"
    assert {"bool_value", "float64_value", "int32_value"} <= set(basics[0])


def test_a_file_that_is_not_a_recording_is_refused_with_the_reason(tmp_path: Any) -> None:
    bad = tmp_path / "notes.mcap"
    bad.write_bytes(b"hello")
    with pytest.raises(RecordingError, match="not a readable MCAP"):
        open_recording(bad)
    with pytest.raises(RecordingError, match="no such file"):
        open_recording(tmp_path / "missing.bag")


async def test_player_plays_in_order_and_ends() -> None:
    async with playing(DEMO_BAG, rate=8.0) as (server, player), connected(server.url) as client:
        got: list[dict[str, Any]] = []
        client.node("t").subscribe("/odom", got.append)
        await until(lambda: player.ended, timeout=20, what="the end of the recording")
        await asyncio.sleep(0)
    seqs = [m["header"]["seq"] for m in got]
    assert seqs == sorted(seqs) and len(seqs) >= 10


async def test_loop_starts_again_at_the_start() -> None:
    async with playing(DEMO_BAG, rate=8.0, loop=True, start=8.0) as (server, player), connected(server.url) as client:
        got: list[dict[str, Any]] = []
        client.node("t").subscribe("/battery", got.append)
        await until(lambda: player.seeks >= 2, timeout=20, what="two rounds")
        assert not player.ended
    # started 8 s in: the battery of 7 s (the state there), 8 s and 9 s, then again from 8 s on
    volts = [round(m["voltage"], 2) for m in got]
    assert set(volts) <= {23.3, 23.2, 23.1}
    last = volts.index(23.1)
    assert any(v > 23.1 for v in volts[last + 1:]), volts  # it went back
