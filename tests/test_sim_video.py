"""The sim's H.264 front camera (rcon_core/sim/video.py): both message types, keyframes on the clock set by
the node's parameters, a stream that starts with a keyframe, a viewer joining mid-stream, the CLI's options,
and no video topics (said why) without PyAV."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import av

from rcon_core.cli.main import main
from rcon_core.sim.video import FFMPEG_TOPIC, FOXGLOVE_TOPIC, H264Encoder, VideoSettings
from rcon_core.testing import connected, until

H264_IDR = 5


def is_key(data: bytes) -> bool:
    """An IDR slice among the packet's NAL units (read here without the widget's parser)."""
    parts = data.split(b"\x00\x00\x01")[1:]
    return any(p and p[0] & 0x1F == H264_IDR for p in parts)


async def collect(client, topic: str, n: int, timeout: float = 20.0) -> list[dict]:
    got: list[dict] = []
    sub = client.node("video-test").subscribe(topic, got.append, compression="cbor", queue_length=50)
    await until(lambda: len(got) >= n, timeout, f"{n} packets on {topic}")
    sub.unsubscribe()
    return got


async def test_both_types_carry_one_h264_stream_each_starting_with_a_keyframe(sim, client):
    video = await collect(client, FOXGLOVE_TOPIC, 20)
    assert video[0]["format"] == "h264" and video[0]["frame_id"] == "camera_front_optical"
    assert set(video[0]) == {"timestamp", "frame_id", "data", "format"}
    keys = [i for i, m in enumerate(video) if is_key(m["data"])]
    assert keys[0] == 0 and keys[1] == 15  # 15 fps, a keyframe every 1 s by default
    # the packets decode (PyAV as a second opinion), 640x360
    dec = av.CodecContext.create("h264", "r")
    frames = [f for m in video for f in dec.decode(av.Packet(m["data"]))]
    assert len(frames) == 20 and (frames[-1].width, frames[-1].height) == (640, 360)
    packets = await collect(client, FFMPEG_TOPIC, 3)
    first = packets[0]
    assert first["encoding"].split(";")[0] == "h264" and (first["width"], first["height"]) == (640, 360)
    assert first["flags"] == 1 and is_key(first["data"]) and [p["pts"] for p in packets] == [0, 1, 2]
    assert sim.robot_node.video.published_bytes[FOXGLOVE_TOPIC] > 0


async def test_the_keyframe_interval_and_bitrate_are_the_nodes_parameters(sim, client):
    node = sim.robot_node.node
    sim.params_tree.set(f"{node}/video/keyframe_interval", 0.4)
    sim.params_tree.set(f"{node}/video/bitrate", 200_000)
    video = await collect(client, FOXGLOVE_TOPIC, 16)
    keys = [i for i, m in enumerate(video) if is_key(m["data"])]
    assert keys[:3] == [0, 6, 12]  # 0.4 s at 15 fps
    enc = sim.robot_node.video._encoders[FOXGLOVE_TOPIC]
    assert enc.settings == VideoSettings(keyframe_interval=0.4, bitrate=200_000)
    # a value out of range is ignored: the default stands
    sim.params_tree.set(f"{node}/video/bitrate", 5)
    assert sim.robot_node.video.current_settings().bitrate == VideoSettings().bitrate


async def test_a_viewer_joining_mid_stream_gets_a_keyframe_within_one_interval(sim, client):
    first = client.node("first").subscribe(FOXGLOVE_TOPIC, lambda m: None, compression="cbor")
    await until(lambda: sim.robot_node.video.published_bytes.get(FOXGLOVE_TOPIC, 0) > 40_000, 20, "streaming")
    async with connected(sim.url) as late:
        packets = await collect(late, FOXGLOVE_TOPIC, 16)
    first.unsubscribe()
    keys = [i for i, m in enumerate(packets) if is_key(m["data"])]
    assert keys and keys[0] <= 15  # at most one keyframe interval of packets before it


def test_encoder_settings():
    enc = H264Encoder(VideoSettings(width=320, height=192, keyframe_interval=0.2, fps=10))
    import numpy as np

    out = [enc.encode(np.full((192, 320, 3), i * 10, np.uint8)) for i in range(5)]
    assert [o[1] for o in out] == [True, False, True, False, True] and [o[2] for o in out] == [0, 1, 2, 3, 4]
    assert VideoSettings(bitrate=10).problems() and VideoSettings(width=641).problems()
    assert VideoSettings.from_params({"bitrate": "fast", "keyframe_interval": 2}).keyframe_interval == 2.0


def test_the_cli_refuses_video_settings_out_of_range(capsys):
    assert main(["sim", "--port", "0", "--video-bitrate", "5"]) == 2
    assert "video bitrate must be between 20 kbit/s and 50 Mbit/s" in capsys.readouterr().err
    assert main(["sim", "--port", "0", "--video-keyframe-interval", "0"]) == 2


NO_AV = textwrap.dedent("""
    import sys
    sys.modules["av"] = None
    from rcon_core.sim import SimServer
    with SimServer.in_thread() as server:
        print("TOPICS", sorted(t for t in server.topics if "image_raw" in t))
        print("WHY", server.robot_node.video.unavailable)
""")


def test_without_pyav_the_sim_has_no_video_topics_and_says_why():
    done = subprocess.run([sys.executable, "-c", NO_AV], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    assert "TOPICS ['/camera/front/image_raw', '/camera/rear/image_raw/compressed']" in done.stdout
    assert "WHY PyAV is not installed (pip install av): the sim publishes no video topics" in done.stdout


def test_the_definitions_ship_for_both_flavours():
    from rcon_core.msgs import TypeRegistry

    for ros2 in (False, True):
        reg = TypeRegistry.standard(ros2=ros2)
        assert [f.name for f in reg.fields("foxglove_msgs/CompressedVideo")] == ["timestamp", "frame_id", "data",
                                                                                 "format"]
        assert [f.name for f in reg.fields("ffmpeg_image_transport_msgs/msg/FFMPEGPacket")] == [
            "header", "width", "height", "encoding", "pts", "flags", "is_bigendian", "data"]
        assert "uint64 pts" in reg.definition_text("ffmpeg_image_transport_msgs/FFMPEGPacket")


async def test_the_sims_rosapi_knows_the_video_types(sim, client):
    answer = await client.call_service("/rosapi/topics", {})
    listed = dict(zip(answer["topics"], answer["types"], strict=True))
    assert listed[FOXGLOVE_TOPIC] == "foxglove_msgs/CompressedVideo"
    assert listed[FFMPEG_TOPIC] == "ffmpeg_image_transport_msgs/FFMPEGPacket"
    details = await client.call_service("/rosapi/message_details", {"type": "foxglove_msgs/CompressedVideo"})
    assert [t["fieldnames"] for t in details["typedefs"] if t["type"] == "foxglove_msgs/CompressedVideo"] == [
        ["timestamp", "frame_id", "data", "format"]]
