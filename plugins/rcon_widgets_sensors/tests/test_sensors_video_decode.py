"""The video decode path (rcon_widgets_sensors.video and .bitstream) on real streams made with PyAV: keyframes
known from the bitstream, joins mid-GOP, lost packets, garbage bytes; every codec the wheel decodes."""

from __future__ import annotations

import numpy as np
import pytest
import video_helpers as vh
from rcon_widgets_sensors.bitstream import H264Order, codec_of, is_keyframe
from rcon_widgets_sensors.decode import DecodeError
from rcon_widgets_sensors.video import (
    Packet,
    VideoDecoder,
    VideoStream,
    VideoUnavailable,
    is_video,
    packet_of,
)


def packets(codec: str, stream: list[tuple[bytes, bool]], indices=None) -> list[Packet]:
    chosen = range(len(stream)) if indices is None else indices
    return [Packet(stream[i][0], codec, is_keyframe(codec, stream[i][0]), None, 0.0) for i in chosen]


def picture_numbers(codec: str, pkts: list[Packet]) -> list[int | None]:
    """What each packet fed in order gives: the frame number of its picture, or None."""
    s = VideoStream(codec)
    out = []
    for p in pkts:
        f = s.feed(p)
        out.append(None if f is None else vh.frame_number(f.to_ndarray(format="rgb24"), 24))
    return out


@pytest.mark.parametrize("codec", sorted(vh.ENCODERS))
def test_keyframes_are_known_from_the_bitstream(codec):
    stream = vh.encode(codec, 24, gop=10)
    assert [is_keyframe(codec, d) for d, _k in stream] == [k for _d, k in stream]
    assert [k for _d, k in stream].count(True) == 3


@pytest.mark.parametrize("codec", sorted(vh.ENCODERS))
def test_every_codec_plays_from_its_first_keyframe(codec):
    stream = vh.encode(codec, 24, gop=10)
    assert picture_numbers(codec, packets(codec, stream)) == list(range(24))


@pytest.mark.parametrize("codec", sorted(vh.ENCODERS))
def test_a_stream_joined_mid_gop_waits_for_the_next_keyframe(codec):
    stream = vh.encode(codec, 24, gop=10)
    s = VideoStream(codec)
    shown = []
    for p in packets(codec, stream, range(3, 24)):  # joined at frame 3
        f = s.feed(p)
        shown.append(None if f is None else vh.frame_number(f.to_ndarray(format="rgb24"), 24))
        if f is None:
            assert s.waiting == "joined"
    assert shown == [None] * 7 + list(range(10, 24))
    assert s.skipped == 7 and s.waiting is None and s.errors == 0


def test_a_lost_h264_packet_holds_the_picture_until_the_next_keyframe():
    stream = vh.encode("h264", 24, gop=10)
    got = picture_numbers("h264", packets("h264", stream, [i for i in range(24) if i != 5]))
    # frames 0-4 shown, 6-9 dropped (their chain lost frame 5: never a smeared picture), 10 on again
    assert got == [0, 1, 2, 3, 4] + [None] * 4 + list(range(10, 24))


def test_h264_order_sees_only_lost_reference_pictures():
    stream = vh.encode("h264", 30, gop=10)
    order = H264Order()
    assert [order.check(d) for d, _k in stream] == [False] * 30
    order = H264Order()
    lost = [order.check(d) for i, (d, _k) in enumerate(stream) if i not in (4, 15)]
    assert lost.count(True) == 2 and order.losses == 2
    # before any SPS nothing is claimed (a join mid-GOP is the keyframe gate's business)
    fresh = H264Order()
    assert not any(fresh.check(d) for d, _k in stream[3:9])


def test_ffmpeg_packet_pts_jump_is_a_loss_even_without_frame_num():
    stream = vh.encode("hevc", 24, gop=10)  # H.265: no frame_num to follow; FFMPEGPacket's pts tells
    s = VideoStream("hevc")
    shown = []
    for i, (data, key) in enumerate(stream):
        if i == 5:
            continue
        pkt = packet_of(vh.ffmpeg_packet(data, key, i, "hevc"), 0.0)
        shown.append(s.feed(pkt) is not None)
    assert shown == [True] * 5 + [False] * 4 + [True] * 14
    assert s.losses == 1


def test_the_packet_flag_of_ffmpeg_packets_is_trusted():
    stream = vh.encode("h264", 12, gop=10)
    data, _key = stream[0]
    pkt = packet_of(vh.ffmpeg_packet(data, True, 0, "libx264;yuv420p;bgr8;bgr8"), 1.0)
    assert pkt.codec == "h264" and pkt.key and pkt.pts == 0 and pkt.stamp is not None
    p1 = packet_of(vh.ffmpeg_packet(stream[1][0], False, 1), 1.0)
    assert not p1.key


@pytest.mark.parametrize("junk", [
    b"",
    b"\x00\x00\x00\x01",
    b"\x00\x00\x01\x65" + bytes(range(256)) * 4,  # an "IDR" NAL unit of nonsense
    b"\x00\x00\x01\x67\xff\xff\xff",  # a truncated SPS
    np.random.default_rng(1).integers(0, 256, 50_000, dtype=np.uint8).tobytes(),
])
def test_garbage_never_raises_and_the_next_keyframe_plays(junk):
    stream = vh.encode("h264", 24, gop=10)
    s = VideoStream("h264")
    pkts = packets("h264", stream)
    for p in pkts[:4]:
        s.feed(p)
    bad = Packet(junk, "h264", is_keyframe("h264", junk), None, 0.0)
    assert s.feed(bad) is None or s.waiting is None  # refused, or (nonsense that decodes) at worst a picture
    if bad.key:
        assert s.waiting in ("bad data", None)
    got = [s.feed(p) for p in pkts[4:]]
    # from the next keyframe on, every packet gives its picture again
    assert all(f is not None for f in got[6:]), [f is not None for f in got]
    assert vh.frame_number(got[-1].to_ndarray(format="rgb24"), 24) == 23


def test_a_keyframe_damaged_in_the_middle_is_refused_or_flagged_never_shown_smeared_later():
    stream = vh.encode("h264", 24, gop=10)
    s = VideoStream("h264")
    pkts = packets("h264", stream)
    key = bytearray(pkts[10].data)
    key[len(key) // 2:] = bytes(len(key) - len(key) // 2)  # the second half zeroed
    for p in pkts[:10]:
        s.feed(p)
    s.feed(Packet(bytes(key), "h264", True, None, 0.0))
    assert [s.feed(p) is not None for p in pkts[20:]] == [True] * 4


def test_the_decoder_handles_batches_and_shows_only_the_newest_picture():
    shown = []
    dec = VideoDecoder(lambda frame, pkt: shown.append(vh.frame_number(frame.to_ndarray(format="rgb24"), 24)))
    stream = vh.encode("h264", 24, gop=10)
    dec.handle(packets("h264", stream, range(0, 15)), False)
    assert shown == [14] and dec.info.decoded == 15  # every packet decoded, one picture made
    dec.handle(packets("h264", stream, range(15, 24)), True)  # the queue overflowed before these
    assert shown == [14, 23] and dec.info.losses == 1 and dec.info.skipped == 5  # 15-19 waited for 20
    assert (dec.info.width, dec.info.height, dec.info.title) == (320, 192, "H.264")


def test_message_shapes():
    data = vh.encode("h264", 1)[0][0]
    assert is_video(vh.compressed_video(data)) and is_video(vh.ffmpeg_packet(data, True, 0))
    assert not is_video({"format": "jpeg", "data": b"\xff\xd8"})
    assert not is_video({"header": {}, "height": 2, "width": 2, "encoding": "rgb8", "data": b""})
    pkt = packet_of(vh.compressed_video(data), 5.0)
    assert pkt.key and pkt.codec == "h264" and pkt.received == 5.0 and pkt.stamp is not None
    with pytest.raises(DecodeError, match="'mjpeg' is not one"):
        packet_of({"format": "mjpeg", "data": b"", "timestamp": vh.stamp_ros1()}, 0.0)
    assert codec_of("H265") == "hevc" and codec_of("hevc_nvenc;yuv420p") == "hevc" and codec_of("jpeg") is None


def test_a_codec_the_decoder_lacks_is_named_with_how_to_install():
    with pytest.raises(VideoUnavailable, match=r"no prores_x decoder.*pip install av"):
        VideoStream("prores_x")
