"""The flight recorder on a Foxglove robot (``rcon_core/record/foxglove_source.py``): each channel written with
the schema and encoding of its advertisement, each payload as the server sent it -- checked against a bare
WebSocket client's copy of the same messages (``fox_raw.py``), against the bytes the peer logged, and read
back with the ``mcap`` reader, ``rosbags`` (a ROS 2 CDR recording) and RCON's own player.  Peers: the
foxglove-sdk server (``rcon_core/foxglove/testing.py``) and the simulated vessel over the Foxglove protocol
(``rcon sim --protocol foxglove``)."""

from __future__ import annotations

import asyncio
import base64
import os
import re
import signal
import sys
import time
from pathlib import Path
from typing import Any

import pytest
from fox_raw import RawFoxClient, run_of
from google.protobuf import descriptor_pb2, descriptor_pool, message_factory
from mcap.reader import make_reader
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_typestore

from rcon_core.bridge.topics import RawPayload
from rcon_core.foxglove import FoxgloveClient
from rcon_core.foxglove.testing import REG, FoxPeer
from rcon_core.record.foxglove_source import FoxgloveRecorder, profile_of, recorder_for, wait_profile
from rcon_core.record.writer import McapSink
from rcon_core.testing import until

pytestmark = pytest.mark.usefixtures("transport")  # every test runs on each WebSocket transport

PEER_TOPICS = ["/chatter", "/rosout_str", "/pose", "/gps", "/camera/compressed"]
N = 20


def read_mcap(path: Path) -> tuple[Any, dict[str, Any], dict[str, list[Any]]]:
    """``(header, {topic: (schema, channel)}, {topic: [message...]})``."""
    with open(path, "rb") as f:
        reader = make_reader(f)
        header = reader.get_header()
        summary = reader.get_summary()
        assert summary is not None, "the file was not closed properly"
        msgs: dict[str, list[Any]] = {}
        for _s, ch, m in reader.iter_messages(log_time_order=False):
            msgs.setdefault(ch.topic, []).append(m)
    chans = {c.topic: (summary.schemas.get(c.schema_id), c) for c in summary.channels.values()}
    return header, chans, msgs


def proto_class(schema: Any) -> Any:
    fds = descriptor_pb2.FileDescriptorSet.FromString(schema.data)
    pool = descriptor_pool.DescriptorPool()
    for fd in fds.file:
        pool.Add(fd)
    return message_factory.GetMessageClass(pool.FindMessageTypeByName(schema.name))


def log_all(peer: FoxPeer, n: int) -> dict[str, list[bytes]]:
    """Log ``n`` messages on every channel of the peer; the CDR ones' bytes as logged."""
    sent: dict[str, list[bytes]] = {"/rosout_str": [], "/pose": []}
    for i in range(n):
        peer.say(f"hello {i}")
        text = REG.serialize_cdr("std_msgs/msg/String", {"data": f"string {i}"})
        peer.text.log(text)
        sent["/rosout_str"].append(text)
        pose = REG.serialize_cdr("geometry_msgs/msg/Pose", REG.complete("geometry_msgs/msg/Pose", {
            "position": {"x": float(i), "y": 2.0, "z": 0.0}}))
        peer.pose.log(pose)
        sent["/pose"].append(pose)
        peer.log_fix(57.7 + i * 1e-6, 11.97)
        peer.log_image(bytes([i]) * 64)
    return sent


async def test_recording_the_foxglove_peer_keeps_each_channel_schema_encoding_and_payload(tmp_path: Path) -> None:
    peer = FoxPeer()
    out = tmp_path / "fox.mcap"
    try:
        async with RawFoxClient(peer.url, PEER_TOPICS) as raw:
            client = FoxgloveClient(peer.url, call_timeout=5)
            await client.connect(timeout=10)
            profile = await wait_profile(client)
            assert profile == ""  # json, cdr and protobuf channels: a file of mixed encodings
            sink = McapSink(str(out), profile)
            rec = recorder_for(client, sink, ros2=False, robot="fox", all_topics=True, operator=False)
            assert isinstance(rec, FoxgloveRecorder)
            started = time.time_ns()
            await rec.start()
            await until(lambda: all(peer.subscribers.get(t) == 2 for t in PEER_TOPICS), what="both subscribed")
            sent = log_all(peer, N)
            await until(lambda: all(sink.stats.per_topic.get(t) == N and len(raw.payloads[t]) == N
                                    for t in PEER_TOPICS), what="every message recorded")
            ended = time.time_ns()
            rec.stop()
            await client.close()
            await asyncio.get_running_loop().run_in_executor(None, sink.close)
            assert rec.problems == []
    finally:
        peer.stop()
    header, chans, msgs = read_mcap(out)
    assert header.profile == ""
    for topic in PEER_TOPICS:
        schema, ch = chans[topic]
        adv = raw.channels[topic]
        assert (schema.name, schema.encoding, ch.message_encoding) == (adv["schemaName"], adv["schemaEncoding"],
                                                                        adv["encoding"]), topic
        binary = adv["schemaEncoding"] == "protobuf"
        assert schema.data == (base64.b64decode(adv["schema"]) if binary else adv["schema"].encode()), topic
        assert [m.data for m in msgs[topic]] == raw.payloads[topic], f"{topic}: not the bytes the server sent"
        for m in msgs[topic]:
            assert started <= m.log_time <= ended and m.publish_time == m.log_time  # no header in these types
    assert [m.data for m in msgs["/rosout_str"]] == sent["/rosout_str"]
    assert [m.data for m in msgs["/pose"]] == sent["/pose"]
    # the schema in the file reads the payloads: protobuf through its own descriptor set
    fix = proto_class(chans["/gps"][0]).FromString(msgs["/gps"][3].data)
    assert (fix.latitude, fix.longitude) == (pytest.approx(57.7 + 3e-6), 11.97)
    image = proto_class(chans["/camera/compressed"][0]).FromString(msgs["/camera/compressed"][5].data)
    assert (image.format, image.data) == ("jpeg", bytes([5]) * 64)
    assert chans["/rcon/link"][1].message_encoding == "cdr"  # RCON's own channels: ROS 2 CDR in such a file


async def test_raw_and_decoding_consumers_share_one_foxglove_subscription(fox: FoxPeer,
                                                                          fox_client: FoxgloveClient) -> None:
    """The recorder's raw subscription and a widget's decoded one on the same topic: one subscription on
    the server, the payload bytes to the one, dicts to the other; when the raw one leaves the other goes on."""
    got_raw: list[RawPayload] = []
    got: list[dict[str, Any]] = []
    widget = fox_client.node("widget").subscribe("/rosout_str", got.append)
    recorder = fox_client.node("recorder").subscribe("/rosout_str", got_raw.append, raw=True)
    await until(lambda: fox.subscribers.get("/rosout_str") == 1, what="one subscription")
    fox.log_string("one")
    await until(lambda: got and got_raw, what="both consumers")
    assert got[0] == {"data": "one"}
    assert got_raw[0].data == REG.serialize_cdr("std_msgs/msg/String", {"data": "one"})
    assert type(got_raw[0].data) is bytes  # a copy: on picows the frame is a view into its read buffer
    assert got_raw[0].type == "std_msgs/msg/String" and got_raw[0].secs > 0
    recorder.unsubscribe()
    fox.log_string("two")
    await until(lambda: len(got) == 2, what="the widget's next message")
    assert got[1] == {"data": "two"} and len(got_raw) == 1
    widget.unsubscribe()
    # the server must see the unsubscribe first: else "subscribed again" holds before it did (a race)
    await until(lambda: fox.subscribers.get("/rosout_str") == 0, what="unsubscribed")
    only_raw = fox_client.node("recorder-2").subscribe("/rosout_str", got_raw.append, raw=True)
    await until(lambda: fox.subscribers.get("/rosout_str") == 1, what="subscribed again")
    fox.log_string("three")
    await until(lambda: len(got_raw) == 2, what="the raw consumer alone")
    assert isinstance(got_raw[1], RawPayload) and got_raw[1].data.endswith(b"three\x00")
    only_raw.unsubscribe()


def test_the_profile_follows_the_channels() -> None:
    class Ch:
        def __init__(self, encoding: str, schema_encoding: str) -> None:
            self.encoding, self.schema_encoding = encoding, schema_encoding

    assert profile_of([Ch("cdr", "ros2msg"), Ch("cdr", "ros2idl")]) == "ros2"
    assert profile_of([Ch("ros1", "ros1msg")]) == "ros1"
    assert profile_of([Ch("cdr", "ros2msg"), Ch("json", "jsonschema")]) == ""
    assert profile_of([Ch("protobuf", "protobuf")]) == ""


# ------------------------------------------------------------------------------------------- the CLI


async def record_until(url: str, out: Path, done: Any, *extra: str) -> tuple[int, str]:
    """Run ``rcon record`` until ``done(messages_so_far)`` holds (read off its progress line), then SIGTERM;
    returns its exit status and its stderr."""
    proc = await asyncio.create_subprocess_exec(
        sys.executable, "-m", "rcon_core", "record", "-o", str(out), "--url", url, *extra,
        stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.PIPE)
    assert proc.stderr is not None
    said = b""
    try:
        deadline = time.monotonic() + 90
        while time.monotonic() < deadline:
            try:
                chunk = await asyncio.wait_for(proc.stderr.read(4096), 5)
            except TimeoutError:
                chunk = b""
            said += chunk
            counts = re.findall(rb"(\d+) msgs", said)
            if counts and done(int(counts[-1])):
                break
            if proc.returncode is not None or (not chunk and proc.stderr.at_eof()):
                break
        proc.send_signal(signal.SIGTERM)
        rest = await asyncio.wait_for(proc.stderr.read(), 30)
        await asyncio.wait_for(proc.wait(), 30)
    finally:
        if proc.returncode is None:
            proc.kill()
    return proc.returncode or 0, (said + rest).decode(errors="replace")


async def test_rcon_record_on_the_foxglove_peer_writes_a_ros2_file_rosbags_reads(tmp_path: Path) -> None:
    """Named CDR topics of a mixed server: a ``ros2`` profile file, the payloads unchanged, rosbags reads it."""
    peer = FoxPeer()
    out = tmp_path / "cli.mcap"
    topics = ["/rosout_str", "/pose"]
    try:
        async with RawFoxClient(peer.url, topics) as raw:
            await until(lambda: raw.subscribed == set(topics), what="the bare client subscribed")

            async def run() -> tuple[int, str]:
                return await record_until(peer.url, out, lambda n: n >= 2 * N + 1, *topics)

            task = asyncio.create_task(run())
            await until(lambda: all(peer.subscribers.get(t) == 2 for t in topics) or task.done(), timeout=60,
                        what="rcon record subscribed")
            sent = log_all(peer, N)
            rc, err = await task
    finally:
        peer.stop()
    assert rc == 0, err
    assert f"{2 * N + 1} messages on 3 topics" in err or f"{2 * N + 2} messages on 3 topics" in err, err
    header, chans, msgs = read_mcap(out)
    assert header.profile == "ros2"
    for topic in topics:
        assert [m.data for m in msgs[topic]] == raw.payloads[topic] == sent[topic]
        assert chans[topic][0].data == raw.channels[topic]["schema"].encode()
    with AnyReader([out], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
        poses = [reader.deserialize(data, conn.msgtype) for conn, _t, data in reader.messages()
                 if conn.topic == "/pose"]
    assert [p.position.x for p in poses] == [float(i) for i in range(N)]


@pytest.fixture
def fox_sim_ros2():
    """``rcon sim --ros2 --protocol foxglove`` on a free port: its URL."""
    import subprocess

    proc = subprocess.Popen([sys.executable, "-m", "rcon_core", "sim", "--port", "0", "--ros2", "--protocol",
                             "foxglove"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env={**os.environ, "PYTHONUNBUFFERED": "1"})
    try:
        assert proc.stdout is not None
        line = proc.stdout.readline()
        match = re.search(r"Foxglove WebSocket protocol on (ws://127\.0\.0\.1:\d+)", line)
        assert match, (line, proc.stderr.read() if proc.poll() is not None and proc.stderr else "")
        yield match.group(1)
    finally:
        proc.terminate()
        proc.wait(10)


async def test_rcon_record_on_the_sim_over_foxglove(fox_sim_ros2: str, tmp_path: Path) -> None:
    """The vessel over Foxglove (ROS 2, CDR): the bytes in the file are a run of what a bare client got, the
    header stamp is the publish time, rosbags and RCON's player read it."""
    out = tmp_path / "sim.mcap"
    topics = ["/odom", "/battery", "/gps/fix"]
    async with RawFoxClient(fox_sim_ros2, topics) as raw:
        rc, err = await record_until(fox_sim_ros2, out, lambda n: n >= 40, *topics)
        assert rc == 0, err
        header, chans, msgs = read_mcap(out)
        # the bare client is still subscribed: what the recorder got reaches it too (it may lag the recorder)
        await until(lambda: all(run_of([m.data for m in msgs[t]], raw.payloads[t]) for t in topics),
                    what="the bare client to have received every message the recorder wrote")
    assert header.profile == "ros2"
    for topic in topics:
        assert run_of([m.data for m in msgs[topic]], raw.payloads[topic]), topic
        schema, ch = chans[topic]
        assert (schema.encoding, ch.message_encoding) == ("ros2msg", "cdr")
        assert schema.data == raw.channels[topic]["schema"].encode()
    reg = REG
    for m in msgs["/odom"]:
        stamp = reg.deserialize_cdr("nav_msgs/msg/Odometry", m.data)["header"]["stamp"]
        assert m.publish_time == stamp["sec"] * 1_000_000_000 + stamp["nanosec"] != m.log_time
    with AnyReader([out], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
        fixes = [reader.deserialize(data, conn.msgtype) for conn, _t, data in reader.messages()
                 if conn.topic == "/gps/fix"]
    assert fixes and all(40 < f.latitude < 70 for f in fixes)
    from rcon_core.record.files import open_recording

    with open_recording(out) as rec:
        assert rec.ros2 and {"/odom", "/battery", "/gps/fix"} <= set(rec.tracks)
        assert rec.tracks["/odom"].count == len(msgs["/odom"])
