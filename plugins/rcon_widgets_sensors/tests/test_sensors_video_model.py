"""The Image widget's model on video: both message types from the sim, the server options it asks for, the
"waiting for a keyframe" notice, latest-wins showing, a queue that overflows, garbage and mid-GOP streams
that end in no hang (a subprocess with a timeout proves it), PyAV missing."""

from __future__ import annotations

import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import pytest
import video_helpers as vh
from rcon_widgets_sensors.image import VIDEO_QUEUE_LENGTH, Frame, ImageModel, ImageSettings
from rcon_widgets_sensors.slots import QueueWorker
from sensors_helpers import in_thread

from rcon_core.plugins import Binding
from rcon_core.testing import until_sync

HERE = Path(__file__).parent


def sim_options(sim, topic):
    subs = [conn.subscriptions[topic] for conn in sim.connections if topic in conn.subscriptions]
    assert subs, f"nobody subscribed to {topic}"
    return list(subs[0].ids.values())[0]


@pytest.mark.parametrize("topic,type_name", [
    ("/camera/front/image_raw/foxglove", "foxglove_msgs/CompressedVideo"),
    ("/camera/front/image_raw/ffmpeg", "ffmpeg_image_transport_msgs/FFMPEGPacket"),
])
async def test_both_video_types_play_from_the_sim(sim, client, topic, type_name):
    model = ImageModel(ImageSettings(max_fps=5), Binding(topic, type_name, "subscribe"), client.node("vid"))
    model.start()
    try:
        first = await in_thread(model.wait_frame, 0, 15.0)
        later = await in_thread(model.wait_frame, first.index + 5, 15.0)
        assert isinstance(later, Frame) and later.kind == "video" and later.info == "H.264 640×360"
        assert later.rgb.shape == (360, 640, 3) and (later.width, later.height) == (640, 360)
        assert later.stamp is not None and abs(later.stamp - time.time()) < 10
        # the sim's scene: sky at the top, brighter than the water at the bottom
        assert later.rgb[5].mean() > later.rgb[-60].mean()
        assert later.byte_rate > 0 and model.meter.total_count >= 6
        info = model.video.info
        assert info.errors == 0 and info.losses == 0 and info.decoded >= 6 and model.notice is None
        # every packet asked for (no throttle: a skipped packet breaks the chain), a short queue, binary
        opts = sim_options(sim, topic)
        assert (opts.throttle_rate, opts.queue_length, opts.compression) == (0, VIDEO_QUEUE_LENGTH, "cbor")
    finally:
        model.stop()
    assert model.worker is None



class _Port:
    """A port that takes the subscription and nothing else (the test feeds messages itself)."""

    def subscribe(self, *_a, **_k):
        return self

    def unsubscribe(self):
        pass


async def test_video_plays_from_a_ros2_sim_too(sim_ros2):
    from rcon_core.testing import connected

    async with connected(sim_ros2.url) as client:
        model = ImageModel(ImageSettings(), Binding("/camera/front/image_raw/foxglove",
                                                    "foxglove_msgs/msg/CompressedVideo", "subscribe"),
                           client.node("vid"))
        model.start()
        try:
            frame = await in_thread(model.wait_frame, 0, 15.0)
            assert frame.kind == "video" and frame.info == "H.264 640×360" and frame.stamp is not None
        finally:
            model.stop()


@pytest.mark.parametrize("ros2", [False, True])
@pytest.mark.parametrize("name", ["foxglove_msgs/msg/CompressedVideo", "ffmpeg_image_transport_msgs/msg/FFMPEGPacket"])
def test_messages_as_a_recording_stores_them_play(ros2, name):
    """A recorder keeps each message's serialized bytes (ROS 1 or CDR, by the shipped definitions); what
    comes back out of them plays like the live stream."""
    from rcon_core.msgs import TypeRegistry

    reg = TypeRegistry.standard(ros2=ros2)
    stream = vh.encode("h264", 12, gop=10)
    model = fed_model()
    try:
        for i, (data, key) in enumerate(stream):
            msg = vh.ffmpeg_packet(data, key, i) if "FFMPEG" in name else vh.compressed_video(data)
            if ros2:
                msg["header" if "FFMPEG" in name else "timestamp"] = _ros2_time(msg)
                back = reg.deserialize_cdr(name, reg.serialize_cdr(name, msg))
            else:
                back = reg.deserialize_ros1(name, reg.serialize_ros1(name, msg))
            assert bytes(back["data"]) == data
            model.on_message(back)
        frame = model.wait_frame(0, 20.0)
        while vh.frame_number(frame.rgb, 24) != 11:
            frame = model.wait_frame(frame.index, 20.0)
        assert frame.stamp is not None
        assert model.video.info.losses == 0 and model.video.info.errors == 0
    finally:
        model.stop()


def _ros2_time(msg: dict) -> dict:
    """The message's time in ROS 2's shape ({sec, nanosec}; a header keeps its frame id, no seq)."""
    if "header" in msg:
        t = msg["header"]["stamp"]
        return {"stamp": {"sec": t["secs"], "nanosec": t["nsecs"]}, "frame_id": msg["header"]["frame_id"]}
    t = msg["timestamp"]
    return {"sec": t["secs"], "nanosec": t["nsecs"]}


def fed_model() -> ImageModel:
    model = ImageModel(ImageSettings(), Binding("/v", "foxglove_msgs/CompressedVideo", "subscribe"), _Port())
    model.start()
    return model


def wait_decoded(model: ImageModel, n: int, timeout: float = 20.0) -> None:
    def taken() -> bool:
        dec = model.video
        return dec is not None and dec.stream is not None and dec.stream.decoded + dec.stream.skipped >= n

    until_sync(taken, timeout, what=f"the video worker taking {n} packets")


def test_joined_mid_gop_the_widget_says_waiting_then_plays():
    stream = vh.encode("h264", 24, gop=10)
    model = fed_model()
    try:
        for data, _key in stream[3:10]:  # frames 3-9: no keyframe among them
            model.on_message(vh.compressed_video(data))
        wait_decoded(model, 7)
        assert model.state.value is None
        assert model.notice == "waiting for a keyframe (joined mid-stream)"
        for data, _key in stream[10:14]:
            model.on_message(vh.compressed_video(data))
        frame = model.wait_frame(0, 20.0)
        while vh.frame_number(frame.rgb, 24) != 13:
            frame = model.wait_frame(frame.index, 20.0)
        assert model.notice is None and model.state.error is None
    finally:
        model.stop()


def test_a_lost_packet_holds_the_last_good_picture_until_the_keyframe():
    stream = vh.encode("h264", 24, gop=10)
    model = fed_model()
    try:
        for data, _key in stream[:5]:
            model.on_message(vh.compressed_video(data))
        frame = model.wait_frame(0, 20.0)
        while vh.frame_number(frame.rgb, 24) != 4:
            frame = model.wait_frame(frame.index, 20.0)
        held = frame.index
        for data, _key in stream[6:10]:  # frame 5 lost
            model.on_message(vh.compressed_video(data))
        wait_decoded(model, 9)
        assert model.notice == "waiting for a keyframe (packets were lost)"
        assert model.state.value.index == held and vh.frame_number(model.state.value.rgb, 24) == 4
        model.on_message(vh.compressed_video(stream[10][0]))
        frame = model.wait_frame(held, 20.0)
        assert vh.frame_number(frame.rgb, 24) == 10 and model.notice is None
    finally:
        model.stop()


def test_garbage_messages_are_reported_and_the_stream_recovers():
    stream = vh.encode("h264", 24, gop=10)
    model = fed_model()
    try:
        model.on_message({"timestamp": vh.stamp_ros1(), "frame_id": "c", "format": "h264", "data": "%%%not base64"})
        until_sync(lambda: model.state.error is not None)
        assert model.state.error.startswith("video data:"), model.state.error
        model.on_message(vh.compressed_video(b"\x00\x00\x01\x65" + b"\x17" * 3000))
        for data, _key in stream[:12]:
            model.on_message(vh.compressed_video(data))
        frame = model.wait_frame(0, 20.0)
        while vh.frame_number(frame.rgb, 24) != 11:
            frame = model.wait_frame(frame.index, 20.0)
        assert model.worker is None or model.worker.alive
    finally:
        model.stop()


def test_the_queue_overflowing_is_a_gap_never_a_growing_backlog():
    release = threading.Event()
    batches: list[tuple[list, bool]] = []

    def handle(items, overflowed):
        release.wait(10)
        batches.append((items, overflowed))

    worker = QueueWorker("test-queue", handle, max_items=5)
    try:
        worker.submit(0)  # taken at once: the handler blocks on it
        until_sync(lambda: worker.queued == 0)
        for i in range(1, 13):
            worker.submit(i)
        assert worker.queued <= 5 and worker.dropped == 10 and worker.overflows == 2
        release.set()
        until_sync(lambda: len(batches) == 2)
        assert batches[0] == ([0], False) and batches[1] == ([11, 12], True)
    finally:
        release.set()
        worker.close()
    assert not worker.alive


NO_HANG = textwrap.dedent("""
    import random, sys, time
    sys.path.insert(0, {here!r})
    import video_helpers as vh
    from rcon_widgets_sensors.image import ImageModel, ImageSettings
    from rcon_widgets_sensors.video import VideoStream, packet_of
    from rcon_core.plugins import Binding

    class Port:
        def subscribe(self, *a, **k): return self
        def unsubscribe(self): pass

    rng = random.Random(5)
    fed = 0
    for codec in ("h264", "hevc", "vp9", "av1"):
        stream = vh.encode(codec, 40, gop=10)
        s = VideoStream(codec)
        # joined mid-GOP, then losses, then every packet cut, flipped, or replaced by noise
        for i, (data, key) in enumerate(stream[3:], 3):
            if i % 7 == 0:
                continue
            if i % 5 == 0:
                data = data[: len(data) // 2]
            elif i % 3 == 0:
                b = bytearray(data)
                for _ in range(20):
                    b[rng.randrange(len(b))] = rng.randrange(256)
                data = bytes(b)
            s.feed(packet_of(vh.compressed_video(data, codec), 0.0))
            fed += 1
        for _ in range(100):
            noise = bytes(rng.randrange(256) for _ in range(rng.randrange(1, 4000)))
            s.feed(packet_of(vh.compressed_video(noise, codec), 0.0))
            fed += 1
        for data, key in stream:  # and it still plays afterwards
            last = s.feed(packet_of(vh.compressed_video(data, codec), 0.0))
        assert last is not None, codec
    model = ImageModel(ImageSettings(), Binding("/v", "foxglove_msgs/CompressedVideo", "subscribe"), Port())
    model.start()
    stream = vh.encode("h264", 40, gop=10)
    for data, key in stream[5:]:
        model.on_message(vh.compressed_video(data[: len(data) - 7]))
    for _ in range(200):
        model.on_message(vh.compressed_video(bytes(rng.randrange(256) for _ in range(500))))
    for data, key in stream:
        model.on_message(vh.compressed_video(data))
    frame = model.wait_frame(0, 60)
    model.stop()
    print("fed", fed, "ok")
""")


def test_garbage_and_mid_gop_streams_end_in_no_hang_within_a_timeout():
    """Fed to every codec's decoder in a child process: a hang (even one holding the GIL inside FFmpeg)
    fails the test at the timeout instead of freezing the run."""
    script = NO_HANG.format(here=str(HERE))
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=240)
    assert done.returncode == 0, done.stderr[-3000:]
    assert done.stdout.strip().endswith("ok"), done.stdout[-500:]


NO_AV = textwrap.dedent("""
    import sys
    sys.modules["av"] = None  # PyAV not installed: its import fails
    import numpy as np
    from rcon_widgets_sensors.image import ImageModel, ImageSettings
    from rcon_core.plugins import Binding
    from rcon_core.testing import until_sync

    class Port:
        def subscribe(self, *a, **k): return self
        def unsubscribe(self): pass

    video = ImageModel(ImageSettings(), Binding("/v", "foxglove_msgs/CompressedVideo", "subscribe"), Port())
    video.start()
    video.on_message({"timestamp": {"secs": 1, "nsecs": 0}, "frame_id": "c", "format": "h264",
                      "data": b"\\x00\\x00\\x01\\x65"})
    until_sync(lambda: video.state.error is not None, 30, what="the video widget's error")
    print("VIDEO:", video.state.error)
    video.on_message({"timestamp": {"secs": 1, "nsecs": 0}, "frame_id": "c", "format": "h264", "data": b"x"})
    raw = ImageModel(ImageSettings(), Binding("/i", "sensor_msgs/Image", "subscribe"), Port())
    raw.start()
    raw.on_message({"header": {"stamp": {"secs": 1, "nsecs": 0}, "frame_id": "c"}, "height": 2, "width": 2,
                    "encoding": "rgb8", "is_bigendian": 0, "step": 6, "data": bytes(12)})
    print("RAW:", raw.wait_frame(0, 30).rgb.shape)
    video.stop(); raw.stop()
""")


def test_without_pyav_the_video_widget_says_how_to_install_and_others_work():
    done = subprocess.run([sys.executable, "-c", NO_AV], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-3000:]
    video = next(line for line in done.stdout.splitlines() if line.startswith("VIDEO:"))
    assert "video needs PyAV, which is not installed (pip install av" in video
    assert "RAW: (2, 2, 3)" in done.stdout
