"""The sim's front camera as H.264 video: ``foxglove_msgs/CompressedVideo`` and ``ffmpeg_image_transport_msgs/
FFMPEGPacket``, encoded with libx264 through PyAV (``av``).

Topics (beside ``/camera/front/image_raw``, as image_transport names a camera's transports):
``/camera/front/image_raw/foxglove`` (CompressedVideo, what foxglove_compressed_video_transport publishes) and
``/camera/front/image_raw/ffmpeg`` (FFMPEGPacket, ffmpeg_image_transport's). Each has its own encoder, made
when its first subscriber comes, so each stream starts with a keyframe; a client that joins a running
stream waits for the next one, as on a real robot.

Encoder settings (:class:`VideoSettings`): 640x360 (the raw camera is 640x480: a 16:9 picture of the same
scene), ``ultrafast`` preset, ``zerolatency`` tune (no lookahead, no frame delay), no B-frames, a keyframe
every ``keyframe_interval`` seconds (scene cuts do not add any), ``bitrate`` bits per second, 15 frames per
second. The robot node's parameters ``video/keyframe_interval`` and ``video/bitrate`` set the two (a change
starts the streams again, with a keyframe); ``rcon sim --video-bitrate/--video-keyframe-interval`` set
those parameters.

The frames are drawn and encoded in the robot node's camera threads (``RobotNode._render``: one frame of a
topic at a time, so the encoder sees them in order) and published from the loop. Without PyAV the video
topics are not advertised and :func:`video_unavailable` says why (``rcon sim`` prints it).
"""

from __future__ import annotations

import importlib
import math
import time
from fractions import Fraction
from typing import Any

import attrs
import numpy as np

from .encoding import Base64Bytes

__all__ = ["VideoSettings", "H264Encoder", "video_unavailable", "FOXGLOVE_TOPIC", "FFMPEG_TOPIC",
           "compressed_video", "ffmpeg_packet"]

FOXGLOVE_TOPIC = "/camera/front/image_raw/foxglove"
FFMPEG_TOPIC = "/camera/front/image_raw/ffmpeg"
#: a stream nobody took frames of for this many frame periods starts again (with a keyframe)
RESTART_AFTER_PERIODS = 3.0


@attrs.frozen
class VideoSettings:
    """``keyframe_interval``: seconds between keyframes (what a client that joins mid-stream waits at most);
    ``bitrate``: bits per second asked of the encoder; ``fps``: frames per second published."""

    width: int = 640
    height: int = 360
    fps: float = 15.0
    keyframe_interval: float = 1.0
    bitrate: int = 600_000

    def problems(self) -> list[str]:
        out = []
        if not 1 <= self.fps <= 60:
            out.append(f"video fps must be between 1 and 60, not {self.fps:g}")
        if not 0.1 <= self.keyframe_interval <= 60:
            out.append(f"the keyframe interval must be between 0.1 and 60 s, not {self.keyframe_interval:g}")
        if not 20_000 <= self.bitrate <= 50_000_000:
            out.append(f"the video bitrate must be between 20 kbit/s and 50 Mbit/s, not {self.bitrate}")
        if self.width % 2 or self.height % 2 or self.width < 16 or self.height < 16:
            out.append(f"the video size must be even and at least 16x16, not {self.width}x{self.height}")
        return out

    @property
    def gop(self) -> int:
        """Frames from one keyframe to the next."""
        return max(1, round(self.keyframe_interval * self.fps))

    @classmethod
    def from_params(cls, params: Any, base: VideoSettings | None = None) -> VideoSettings:
        """Settings from a parameter dict (``{"keyframe_interval", "bitrate"}``), on top of ``base``; values
        that are not numbers, or out of range, keep the base's."""
        base = base or cls()
        if not isinstance(params, dict):
            return base
        out = base
        for name, kind in (("keyframe_interval", float), ("bitrate", int)):
            value = params.get(name)
            if isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value):
                changes: dict[str, Any] = {name: kind(value)}
                candidate = attrs.evolve(out, **changes)
                if not candidate.problems():
                    out = candidate
        return out


def video_unavailable() -> str | None:
    """Why the sim cannot publish video here (PyAV or its libx264 missing), or None."""
    try:
        av = importlib.import_module("av")
    except ImportError:
        return "PyAV is not installed (pip install av): the sim publishes no video topics"
    if "libx264" not in getattr(av.codec, "codecs_available", ()):
        return "this PyAV has no libx264 encoder: the sim publishes no video topics"
    return None


class H264Encoder:
    """libx264 through PyAV: RGB frames in, one Annex B packet (with SPS/PPS on each keyframe) out.

    One thread at a time; frames in order. :meth:`encode` returns ``(data, keyframe, pts)``.
    """

    def __init__(self, settings: VideoSettings) -> None:
        av = importlib.import_module("av")
        self.settings = s = settings
        ctx = av.CodecContext.create("libx264", "w")
        ctx.width, ctx.height = s.width, s.height
        ctx.pix_fmt = "yuv420p"
        rate = Fraction(s.fps).limit_denominator(1000)
        ctx.time_base = 1 / rate
        ctx.framerate = rate
        ctx.bit_rate = s.bitrate
        ctx.gop_size = s.gop
        ctx.max_b_frames = 0
        # no B-frames, no lookahead, keyframes on the clock only; the SPS/PPS are repeated in front of
        # every keyframe (FFmpeg's libx264 does it when the stream has no global header)
        ctx.options = {"preset": "ultrafast", "tune": "zerolatency",
                       "x264-params": f"scenecut=0:keyint={s.gop}:min-keyint={s.gop}:bframes=0"}
        self._av = av
        self._ctx = ctx
        self.pts = 0
        self.last_used = 0.0

    def encode(self, rgb: np.ndarray) -> tuple[bytes, bool, int] | None:
        """``rgb`` (height x width x 3) as one packet; None if the encoder held it back (it does not)."""
        frame = self._av.VideoFrame.from_ndarray(rgb, format="rgb24")
        frame.pts = self.pts
        self.pts += 1
        self.last_used = time.monotonic()
        out = None
        for packet in self._ctx.encode(frame):
            out = (bytes(packet), bool(packet.is_keyframe), int(packet.pts if packet.pts is not None else self.pts - 1))
        return out


def compressed_video(flavour: Any, data: bytes, stamp: float, text: bool) -> dict[str, Any]:
    """A ``foxglove_msgs/CompressedVideo`` of one H.264 packet."""
    return {"timestamp": flavour.time(stamp), "frame_id": "camera_front_optical",
            "data": Base64Bytes.of(data) if text else data, "format": "h264"}


def ffmpeg_packet(flavour: Any, data: bytes, key: bool, pts: int, stamp: float, size: tuple[int, int],
                  text: bool) -> dict[str, Any]:
    """An ``ffmpeg_image_transport_msgs/FFMPEGPacket`` of one H.264 packet."""
    return {"header": flavour.header("camera_front_optical", stamp), "width": size[0], "height": size[1],
            "encoding": "h264;yuv420p;rgb8;rgb8", "pts": pts, "flags": 1 if key else 0, "is_bigendian": False,
            "data": Base64Bytes.of(data) if text else data}


class FrontVideo:
    """The robot node's video topics: encoders per topic, made on first use, restarted after a pause.

    ``node``: the :class:`~rcon_core.sim.robot_node.RobotNode` (its ``server``, ``fl``, ``ns``, ``node``,
    ``_render``). :meth:`periodic` gives the schedule entries the node adds to its own.
    """

    def __init__(self, node: Any) -> None:
        from .camera import CameraRenderer

        self.node = node
        self.unavailable = video_unavailable()
        self.base = VideoSettings()
        self.settings = self.base
        self._encoders: dict[str, H264Encoder] = {}
        ident = node.identity
        bow = (ident.hull, ident.label) if ident.hull is not None else None
        s = self.base
        self.camera = CameraRenderer("front", width=s.width, height=s.height, sky=ident.sky, bow=bow,
                                     vessel_name=ident.name)
        self.topics = {FOXGLOVE_TOPIC: node.fl.msg("foxglove_msgs", "CompressedVideo"),
                       FFMPEG_TOPIC: node.fl.msg("ffmpeg_image_transport_msgs", "FFMPEGPacket")}
        self.published_bytes: dict[str, int] = {}
        if self.unavailable is None:
            for topic, type_name in self.topics.items():
                node.server.advertise_internal(node.ns(topic), type_name, node.node)
        node.server.params_tree.set(f"{node.node}/video", {"keyframe_interval": s.keyframe_interval,
                                                             "bitrate": s.bitrate})

    def periodic(self) -> list[tuple[str, float, Any]]:
        """``(topic, rate in Hz, fn(now))`` per video topic; none without PyAV."""
        if self.unavailable is not None:
            return []
        return [(topic, self.base.fps, lambda now, t=topic: self.tick(t)) for topic in self.topics]

    def current_settings(self) -> VideoSettings:
        """The settings the node's ``video/*`` parameters ask for now."""
        return VideoSettings.from_params(self.node.server.params_tree.get(f"{self.node.node}/video"), self.base)

    def tick(self, topic: str) -> None:
        node = self.node
        if not node.server.has_subscribers(node.ns(topic)):
            return
        node._render(topic, self.camera, lambda img, stamp, text: self._message(topic, img, stamp, text))

    def _encoder(self, topic: str) -> H264Encoder:
        """The topic's encoder; a new one (its stream starts with a keyframe) after a pause or a change of
        settings (camera thread)."""
        enc = self._encoders.get(topic)
        settings = self.current_settings()
        idle = enc is not None and time.monotonic() - enc.last_used > RESTART_AFTER_PERIODS / enc.settings.fps
        if enc is None or idle or enc.settings != settings:
            enc = self._encoders[topic] = H264Encoder(settings)
        return enc

    def _message(self, topic: str, img: np.ndarray, stamp: float, text: bool) -> dict[str, Any] | None:
        enc = self._encoder(topic)
        out = enc.encode(img)
        if out is None:
            return None
        data, key, pts = out
        self.published_bytes[topic] = self.published_bytes.get(topic, 0) + len(data)
        fl = self.node.fl
        if topic == FOXGLOVE_TOPIC:
            return compressed_video(fl, data, stamp, text)
        return ffmpeg_packet(fl, data, key, pts, stamp, (enc.settings.width, enc.settings.height), text)
