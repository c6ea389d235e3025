"""Video in the Image widget: ``foxglove_msgs/CompressedVideo`` and ``ffmpeg_image_transport_msgs/FFMPEGPacket``
decoded with PyAV in a worker thread (no Qt; never on the GUI thread or the bridge loop).

Decision: every packet is decoded, in order; only the newest picture is shown
    Each packet of a stream refers to earlier ones, so packets are never replaced in a latest-wins slot as
    raw images are: they wait in a bounded queue (:class:`~.slots.QueueWorker`) and the worker decodes all
    that came, then converts only the newest picture to RGB at the view's size (showing may skip, decoding
    keeps up). A queue that overflows (decoding fell behind by ``MAX_BACKLOG`` packets) is emptied: a gap,
    handled as a lost packet. So the backlog never grows.

Decision: a picture is drawn only from a whole chain of packets
    After a join (the first packets of a stream a client subscribed to mid-way), a lost packet, or data the
    decoder refused, packets are dropped until the next keyframe (:mod:`.bitstream` says which is one) and
    the widget says "waiting for a keyframe"; the last good picture stays on screen meanwhile, never a
    smeared one decoded from a broken chain. A loss is seen from the queue overflowing, from H.264's
    ``frame_num`` jumping (:class:`~.bitstream.H264Order`), from FFMPEGPacket's ``pts`` jumping, from the
    decoder raising or marking a picture corrupt. Each keyframe after a wait opens a fresh decoder, so
    garbage fed before can leave nothing behind.

Decision: slice threads and low delay, never frame threads
    Frame threading holds several frames in flight (each a frame of delay) and, in an experiment, hung for
    over 30 s when fed a stream joined mid-GOP. The decoder runs with ``thread_type = SLICE`` and the
    ``LOW_DELAY`` flag, so a packet in is its picture out.

PyAV (``av``) is imported when the first video packet comes; without it, or without a decoder for the
codec, the widget says which and how to install it (:class:`VideoUnavailable`), and nothing else changes.
Nothing here knows the robot link: a message dict with ``data`` bytes (bytes, base64 text or a list of
ints) is all it takes, from rosbridge or any other link.
"""

from __future__ import annotations

import importlib
import logging
import os
import threading
import time
from collections.abc import Callable
from typing import Any

import attrs
import numpy as np

from rcon_core.msgs import time as rtime
from rcon_core.msgs.values import as_bytes

from .bitstream import CODEC_TITLES, H264Order, codec_of, is_keyframe
from .decode import DecodeError

log = logging.getLogger(__name__)

__all__ = ["VideoUnavailable", "Packet", "VideoStream", "packet_of", "is_video", "load_av", "MAX_BACKLOG",
           "VIDEO_TYPES", "INSTALL_HINT"]

#: packets the decoder may fall behind before the queue is emptied and it waits for a keyframe
MAX_BACKLOG = 90
#: the video message types the Image widget takes (both spellings meet in ``names.pkg_type``)
VIDEO_TYPES = ("foxglove_msgs/CompressedVideo", "ffmpeg_image_transport_msgs/FFMPEGPacket")
INSTALL_HINT = "pip install av"
#: FFmpeg's AV_PKT_FLAG_KEY in FFMPEGPacket.flags
PKT_FLAG_KEY = 1


class VideoUnavailable(DecodeError):
    """PyAV, or its decoder for this codec, is not there; ``str()`` says which and how to install it."""


_av_lock = threading.Lock()
_av_module: Any = None


def load_av() -> Any:
    """The ``av`` module, imported once; :class:`VideoUnavailable` when it is not installed."""
    global _av_module
    with _av_lock:
        if _av_module is None:
            try:
                _av_module = importlib.import_module("av")
            except ImportError as exc:
                raise VideoUnavailable(f"video needs PyAV, which is not installed ({INSTALL_HINT}, then "
                                       f"restart RCON): {exc}") from None
        return _av_module


def is_video(body: Any) -> bool:
    """Whether a message is a video packet: CompressedVideo (``format`` a video codec) or FFMPEGPacket."""
    if not isinstance(body, dict) or "data" not in body:
        return False
    if "pts" in body and "flags" in body and "encoding" in body:
        return True
    fmt = body.get("format")
    return isinstance(fmt, str) and codec_of(fmt) is not None


@attrs.frozen(eq=False)
class Packet:
    """One message's video packet: ``codec`` is FFmpeg's decoder name; ``key`` whether it starts a picture
    on its own; ``pts`` FFMPEGPacket's (None for CompressedVideo); ``stamp`` the capture time (epoch s)."""

    data: bytes
    codec: str
    key: bool
    stamp: float | None
    received: float
    pts: int | None = None


def _time(value: Any) -> float | None:
    if not rtime.is_time(value):
        return None
    try:
        t = rtime.to_float(value)
    except (TypeError, ValueError):
        return None
    return t if t > 0 else None


def packet_of(body: dict[str, Any], received: float) -> Packet:
    """A :class:`Packet` from a CompressedVideo or FFMPEGPacket dict; :class:`DecodeError` when it is neither
    or names a codec this widget does not know."""
    if "encoding" in body and "pts" in body:  # FFMPEGPacket
        name = str(body.get("encoding", ""))
        header = body.get("header")
        stamp = _time(header.get("stamp")) if isinstance(header, dict) else None
        flags = body.get("flags")
        pts = body.get("pts")
    else:
        name = str(body.get("format", ""))
        stamp = _time(body.get("timestamp"))
        flags = pts = None
    codec = codec_of(name)
    if codec is None:
        raise DecodeError(f"video format {name!r} is not one the Image widget decodes "
                          f"(h264, h265, vp9, av1)")
    try:
        data = as_bytes(body.get("data"))
    except ValueError as exc:
        raise DecodeError(f"video data: {exc}") from None
    key = is_keyframe(codec, data) or (isinstance(flags, int) and bool(flags & PKT_FLAG_KEY) and bool(data))
    return Packet(data, codec, key, stamp, received, pts if isinstance(pts, int) else None)


#: FFmpeg decoders to try per codec, best first. FFmpeg's own "av1" decodes only through a GPU
#: (software: "Function not implemented"), so AV1 takes dav1d.
DECODERS: dict[str, tuple[str, ...]] = {"h264": ("h264",), "hevc": ("hevc",), "vp9": ("vp9", "libvpx-vp9"),
                                        "av1": ("libdav1d", "libaom-av1")}
#: per decoder: no frames held back (dav1d keeps frames in flight for its frame threads by default)
_DECODER_OPTIONS: dict[str, dict[str, str]] = {"libdav1d": {"max_frame_delay": "1"}}


def _decoder_name(av: Any, codec: str) -> str | None:
    """The first of :data:`DECODERS` for ``codec`` that this PyAV has (a codec not listed: its own name)."""
    for name in DECODERS.get(codec, (codec,)):
        try:
            av.codec.Codec(name, "r")
        except Exception:  # noqa: BLE001 - PyAV raises its own errors for an unknown codec
            continue
        return name
    return None


def _decoder_threads() -> int:
    return max(1, min(4, os.cpu_count() or 1))


class VideoStream:
    """The decoding state of one stream (one thread at a time: the model's video worker).

    :meth:`feed` takes each packet in order and returns the newest picture it decoded (an ``av.VideoFrame``)
    or None. ``waiting``: why packets are being dropped until a keyframe (``"joined"``, ``"lost packets"``,
    ``"bad data"``), or None while playing. Counters: ``decoded``, ``skipped`` (dropped while waiting),
    ``losses`` (gaps seen), ``errors`` (packets the decoder refused).
    """

    def __init__(self, codec: str, *, threads: int | None = None) -> None:
        self.av = load_av()
        self.codec = codec
        self.decoder = _decoder_name(self.av, codec)
        if self.decoder is None:
            title = CODEC_TITLES.get(codec, codec)
            raise VideoUnavailable(f"this PyAV {getattr(self.av, '__version__', '')} has no {title} decoder "
                                   f"({codec}); install a build that has one ({INSTALL_HINT} --upgrade, or "
                                   f"PyAV built against an FFmpeg with {codec})")
        self.threads = threads or _decoder_threads()
        self.waiting: str | None = "joined"
        self.order = H264Order() if codec == "h264" else None
        self._ctx: Any = None
        self._last_pts: int | None = None
        self.decoded = self.skipped = self.losses = self.errors = 0

    def _open(self) -> Any:
        ctx = self.av.CodecContext.create(self.decoder, "r")
        ctx.thread_type = "SLICE"  # never FRAME: frames of delay, and it hung on a mid-GOP join
        ctx.thread_count = self.threads
        if self.decoder in _DECODER_OPTIONS:
            ctx.options = dict(_DECODER_OPTIONS[self.decoder])
        flags = self.av.codec.context.Flags
        ctx.flags = ctx.flags | flags.low_delay
        return ctx

    def lost(self, why: str = "lost packets") -> None:
        """Packets are missing before the next one (the queue overflowed): wait for a keyframe."""
        if self.waiting is None:
            self.losses += 1
            self.waiting = why

    def feed(self, pkt: Packet) -> Any:
        """Decode ``pkt`` (when the chain is whole); the newest decoded picture or None."""
        gap = self.order.check(pkt.data) if self.order is not None else False
        if pkt.pts is not None:
            if self._last_pts is not None and pkt.pts > self._last_pts + 1 and not pkt.key:
                gap = True
            self._last_pts = pkt.pts
        if gap and not pkt.key:
            self.lost()
        if self.waiting is not None:
            if not pkt.key:
                self.skipped += 1
                return None
            self._ctx = self._open()  # a fresh decoder from each keyframe after a wait
            self.waiting = None
        try:
            frames = self._ctx.decode(self.av.Packet(pkt.data))
        except self.av.FFmpegError as exc:
            self.errors += 1
            self.waiting = "bad data"
            self._ctx = None
            log.debug("video decoder refused a packet: %s", exc)
            return None
        good = [f for f in frames if not getattr(f, "is_corrupt", False)]
        if len(good) < len(frames):
            self.lost("bad data")
            return None
        self.decoded += len(good)
        return good[-1] if good else None


def picture_rgb(frame: Any, width: int, height: int) -> np.ndarray:
    """An ``av.VideoFrame`` as ``height`` x ``width`` x 3 RGB (swscale converts and scales in one pass)."""
    if (width, height) == (frame.width, frame.height):
        out = frame.to_ndarray(format="rgb24")
    else:
        out = frame.reformat(width=width, height=height, format="rgb24", interpolation="AREA").to_ndarray()
    return out if out.flags.c_contiguous else np.ascontiguousarray(out)


@attrs.define
class VideoInfo:
    """What the overlay says of a stream: codec, size, rates, and why it waits."""

    codec: str = ""
    width: int = 0
    height: int = 0
    waiting: str | None = None
    decoded: int = 0
    skipped: int = 0
    losses: int = 0
    errors: int = 0

    @property
    def title(self) -> str:
        return CODEC_TITLES.get(self.codec, self.codec)


def waiting_text(why: str | None) -> str:
    """What the widget says while it drops packets until a keyframe."""
    if why is None:
        return ""
    reason = {"joined": "joined mid-stream", "lost packets": "packets were lost",
              "bad data": "the decoder refused a packet"}.get(why, why)
    return f"waiting for a keyframe ({reason})"


class VideoDecoder:
    """Feeds one widget's packets through a :class:`VideoStream` per codec; used by the video worker.

    ``show(frame, packet)`` is called with the newest picture of each batch. A change of codec (another
    stream on the topic) starts a new stream. ``now`` is injectable for tests.
    """

    def __init__(self, show: Callable[[Any, Packet], None], now: Callable[[], float] = time.time) -> None:
        self._show = show
        self._now = now
        self.stream: VideoStream | None = None
        self.info = VideoInfo()

    def handle(self, packets: list[Packet], overflowed: bool) -> None:
        stream = self.stream
        if overflowed and stream is not None:
            stream.lost()
        newest: tuple[Any, Packet] | None = None
        for pkt in packets:
            if stream is None or stream.codec != pkt.codec:
                stream = self.stream = VideoStream(pkt.codec)
                self.info = VideoInfo(codec=pkt.codec)
            frame = stream.feed(pkt)
            if frame is not None:
                newest = (frame, pkt)
        if stream is not None:
            info = self.info
            info.waiting, info.decoded, info.skipped = stream.waiting, stream.decoded, stream.skipped
            info.losses, info.errors = stream.losses, stream.errors
        if newest is not None:
            frame, pkt = newest
            self.info.width, self.info.height = int(frame.width), int(frame.height)
            self._show(frame, pkt)
