"""Video streams made with PyAV for the video tests (imported by basename: keep the name unique)."""

from __future__ import annotations

import os
import time
from fractions import Fraction

import av
import numpy as np

#: the encoder each codec's test streams are made with (all in the PyAV wheel the package depends on)
os.environ.setdefault("SVT_LOG", "1")  # SVT-AV1: errors only, not its banner on every stream

ENCODERS = {"h264": "libx264", "hevc": "libx265", "vp9": "libvpx-vp9", "av1": "libsvtav1"}


def colour(i: int) -> tuple[int, int, int]:
    """Frame ``i``'s flat colour: tells which frame a decoded picture is (far apart for 0..11)."""
    return ((i * 21) % 256, 128, (255 - i * 21) % 256)


def pictures(n: int, w: int = 320, h: int = 192) -> list[np.ndarray]:
    """``n`` RGB frames: each a flat colour (:func:`colour`) with a white bar that moves."""
    out = []
    for i in range(n):
        img = np.empty((h, w, 3), np.uint8)
        img[:] = colour(i)
        x = (i * 16) % (w - 16)
        img[:, x:x + 16] = 255
        out.append(img)
    return out


def encode(codec: str, n: int, gop: int = 10, w: int = 320, h: int = 192) -> list[tuple[bytes, bool]]:
    """``n`` frames as one stream of ``codec`` with a keyframe every ``gop`` frames, no B-frames:
    ``[(packet bytes, keyframe by PyAV)]``, one packet per frame."""
    ctx = av.CodecContext.create(ENCODERS[codec], "w")
    ctx.width, ctx.height, ctx.pix_fmt = w, h, "yuv420p"
    ctx.time_base, ctx.framerate = Fraction(1, 30), Fraction(30)
    ctx.gop_size, ctx.max_b_frames = gop, 0
    ctx.bit_rate = 800_000
    ctx.options = {
        "h264": {"preset": "ultrafast", "tune": "zerolatency", "x264-params": f"scenecut=0:keyint={gop}"},
        "hevc": {"preset": "ultrafast", "tune": "zerolatency",
                 "x265-params": f"keyint={gop}:min-keyint={gop}:scenecut=0:bframes=0:log-level=error"},
        "vp9": {"deadline": "realtime", "cpu-used": "8", "lag-in-frames": "0"},
        "av1": {"preset": "10", "svtav1-params": f"keyint={gop}:scd=0:pred-struct=1:rc=2"},
    }[codec]
    packets: list[tuple[bytes, bool]] = []
    for i, img in enumerate(pictures(n, w, h)):
        frame = av.VideoFrame.from_ndarray(img, format="rgb24")
        frame.pts = i
        packets += [(bytes(p), bool(p.is_keyframe)) for p in ctx.encode(frame)]
    packets += [(bytes(p), bool(p.is_keyframe)) for p in ctx.encode(None)]
    return packets


def stamp_ros1(t: float | None = None) -> dict:
    t = time.time() if t is None else t
    return {"secs": int(t), "nsecs": int(t % 1 * 1e9)}


def compressed_video(data: bytes, fmt: str = "h264") -> dict:
    """A foxglove_msgs/CompressedVideo dict."""
    return {"timestamp": stamp_ros1(), "frame_id": "cam", "data": data, "format": fmt}


def ffmpeg_packet(data: bytes, key: bool, pts: int, encoding: str = "h264", size=(320, 192)) -> dict:
    """An ffmpeg_image_transport_msgs/FFMPEGPacket dict."""
    return {"header": {"seq": pts, "stamp": stamp_ros1(), "frame_id": "cam"}, "width": size[0],
            "height": size[1], "encoding": encoding, "pts": pts, "flags": 1 if key else 0, "is_bigendian": False,
            "data": data}


def frame_number(rgb: np.ndarray, n: int = 12) -> int:
    """Which of frames 0..n-1 a decoded picture is, by its colour away from the moving bar (left quarter
    when the bar is right of it, else the right quarter: the median of that region)."""
    h, w = rgb.shape[:2]
    left = np.median(rgb[:, : w // 8].reshape(-1, 3), axis=0)
    right = np.median(rgb[:, -w // 8:].reshape(-1, 3), axis=0)
    sample = left if abs(int(left[1]) - 128) < abs(int(right[1]) - 128) else right
    return int(np.argmin([np.abs(sample - np.array(colour(i))).sum() for i in range(n)]))
