"""The Image widget's settings and model (no Qt).

The model never decodes on the bridge loop: ``on_message`` hands the message to a decode worker thread
through a latest-wins slot (a burst of big frames costs the loop nothing and older frames are dropped,
never queued), and the worker publishes a ready :class:`Frame` with ``set_value``. The view tells the
model how big it paints (:meth:`ImageModel.set_display_size`: its size in device pixels, grown by its
zoom) and the worker makes no more pixels than that needs (a reduced JPEG decode, a shrink of raw and
PNG images: :mod:`.decode`; laser scans and occupancy grids are drawn as before); a picture bigger than
that box is made exactly the rectangle it fills there (:func:`.viewport.fitted_pixels`, so a fitted view
draws it 1:1, no scaling on the GUI thread); then it lays them out for Qt's painter (RGB32) on the same
thread; the frame keeps the source picture's size for the overlay and
the zoom arithmetic. The server is asked to send no more than the view can show: ``throttle_rate`` from
``max_fps``, ``queue_length`` 1, CBOR (binary data, no base64) when ``compression`` is ``"auto"``.

Video (``foxglove_msgs/CompressedVideo``, ``ffmpeg_image_transport_msgs/FFMPEGPacket``) takes another
path: every packet is needed, so packets go in order through a bounded queue to a video worker
(:mod:`.video`), which decodes them all and shows the newest picture; the server is asked for every packet
(no ``throttle_rate``) with a short queue (``VIDEO_QUEUE_LENGTH``). While the worker drops packets until a
keyframe, :attr:`ImageModel.notice` says so. Every message's bytes are counted as it arrives
(:attr:`ImageModel.meter`), so the overlay says what the stream costs the link.
"""

from __future__ import annotations

import asyncio
import collections
import math
import sys
import threading
import time
from typing import Any

import attrs
import cv2
import numpy as np

from rcon_core.msgs import time as rtime
from rcon_core.msgs.names import pkg_type
from rcon_core.plugins import WidgetModel
from rcon_core.plugins.paths import PathError, get_path

from .decode import DecodeError, decode_compressed_sized, decode_image, message_kind, resize_exactly
from .rates import RateMeter
from .scan_render import ScanCounts, render_grid, render_scan
from .slots import QueueWorker, SlotWorker
from .transport import Choice, pick
from .video import (
    MAX_BACKLOG,
    VIDEO_TYPES,
    Packet,
    VideoDecoder,
    VideoUnavailable,
    is_video,
    packet_of,
    picture_rgb,
    waiting_text,
)
from .viewport import fitted_pixels

__all__ = ["ImageSettings", "ImageModel", "Frame"]

COMPRESSIONS = ("auto", "none", "cbor", "png")
#: "bound": the topic as bound; "best": the lightest transport the robot offers for the same camera
TRANSPORT_CHOICES = ("bound", "best")
#: the server's queue for a video subscription: a short burst of packets waits instead of being dropped
#: (a dropped packet costs the pictures up to the next keyframe); more would let a slow link's delay grow
VIDEO_QUEUE_LENGTH = 10


def is_video_type(type_name: str) -> bool:
    """Whether ``type_name`` (either spelling) is one of the video message types (:data:`.video.VIDEO_TYPES`)."""
    return pkg_type(type_name) in VIDEO_TYPES


@attrs.define
class ImageSettings:
    """``max_fps``: frames per second asked of the server (0 = every frame; video always gets every packet,
    each one is needed to decode the next). ``compression``: ``auto``
    (CBOR: binary, no base64), ``none``, ``cbor``, ``png``. ``depth_min``/``depth_max``: the depth range
    (in the image's unit) mapped onto the colour map; both 0 = automatic. ``scan_range``: metres shown
    around a laser scan (0 = the scan's range_max). ``show_overlay``: frame rate and age in the corner.
    ``smooth``: smooth scaling (off: sharp pixels, cheaper)."""

    max_fps: float = 30.0
    compression: str = "auto"
    transport: str = attrs.field(
        default="bound", metadata={"label": "Transport", "choices": list(TRANSPORT_CHOICES),
                                   "help": "best: the lightest stream the robot offers for this camera "
                                           "(video, then /compressed, then raw); the overlay says which"})
    depth_min: float = 0.0
    depth_max: float = 0.0
    scan_range: float = 0.0
    show_overlay: bool = True
    smooth: bool = True
    stale_after: float = attrs.field(
        default=3.0, metadata={"label": "Stale after (s)", "min": 0.0,
                               "help": "0 = a static (latched) topic, e.g. a map: never stale once it delivered"})

    def problems(self) -> list[str]:
        out = []
        if not 0 <= self.max_fps <= 120:
            out.append(f"the maximum frame rate must be between 0 (no limit) and 120, not {self.max_fps:g}")
        if self.compression not in COMPRESSIONS:
            out.append(f"compression must be one of {', '.join(COMPRESSIONS)}, not {self.compression!r}")
        if self.transport not in TRANSPORT_CHOICES:
            out.append(f"transport must be one of {', '.join(TRANSPORT_CHOICES)}, not {self.transport!r}")
        if self.depth_min < 0 or self.depth_max < 0:
            out.append("the depth range cannot be negative")
        elif (self.depth_min or self.depth_max) and self.depth_max <= self.depth_min:
            out.append(f"the depth range needs min < max (got {self.depth_min:g} .. {self.depth_max:g}); "
                       "set both to 0 for automatic")
        if self.scan_range < 0:
            out.append("the scan range cannot be negative (0 = the scan's own maximum)")
        if not self.stale_after >= 0:
            out.append("'stale after' cannot be negative (0 = a static topic)")
        return out


def to_rgb32(rgb: np.ndarray) -> np.ndarray:
    """``rgb`` (H x W x 3 uint8) as H x W x 4 uint8 in the memory layout of Qt's ``Format_RGB32`` (each pixel
    the 32-bit word 0xffRRGGBB in native byte order), the format Qt's raster painter scales without a
    conversion: a smooth draw of a 640x480 frame costs about a third of drawing the RGB888 array."""
    if sys.byteorder == "little":  # B, G, R, 0xff in memory
        return cv2.cvtColor(np.ascontiguousarray(rgb), cv2.COLOR_RGB2BGRA)
    out = np.empty((rgb.shape[0], rgb.shape[1], 4), np.uint8)  # 0xff, R, G, B
    out[..., 0], out[..., 1:] = 255, rgb
    return out


@attrs.frozen(eq=False)
class Frame:
    """A decoded frame, ready to paint: ``rgb`` is H x W x 3 uint8, C-contiguous, never modified.
    ``rgb32``: the same pixels laid out for Qt's ``Format_RGB32`` (:func:`to_rgb32`), made where the frame
    is made (a decode or capture thread), so the GUI thread paints without converting the format.

    ``width``/``height``: the SOURCE picture's size (what the overlay says; the view's zoom and pan work in
    these pixels). ``rgb`` may be smaller than that when the model decoded for a smaller display
    (:meth:`ImageModel.set_display_size`): it covers the whole picture, so the view draws the whole array
    into the rectangle the source size would fill (1:1 when the array is exactly that rectangle in device
    pixels, see :mod:`.image_view`). ``pixel_width``/``pixel_height``: the array's size.

    ``stamp``: the message header's time (epoch seconds) or None; ``received``/``decoded``: wall clock
    when it arrived / was ready. ``fps``: frames decoded per second lately. ``dropped``: frames skipped so
    far because a newer one came first. ``kind``: image, compressed, video, scan or grid; ``info``: for
    people (size and encoding; the codec for video).
    """

    rgb: np.ndarray
    kind: str
    info: str
    stamp: float | None
    received: float
    decoded: float
    index: int
    fps: float = 0.0
    dropped: int = 0
    smooth: bool = True
    counts: ScanCounts | None = None
    #: bytes per second the topic's messages brought lately (their ``data``: what the stream costs the link)
    byte_rate: float = 0.0
    source_width: int = attrs.field(default=attrs.Factory(lambda self: int(self.rgb.shape[1]), takes_self=True))
    source_height: int = attrs.field(default=attrs.Factory(lambda self: int(self.rgb.shape[0]), takes_self=True))
    rgb32: np.ndarray = attrs.field(default=attrs.Factory(lambda self: to_rgb32(self.rgb), takes_self=True))

    @property
    def width(self) -> int:
        """The source picture's width (the pixel array may be smaller: :attr:`pixel_width`)."""
        return self.source_width

    @property
    def height(self) -> int:
        return self.source_height

    @property
    def pixel_width(self) -> int:
        """The width of ``rgb``/``rgb32``: at most the source width."""
        return int(self.rgb.shape[1])

    @property
    def pixel_height(self) -> int:
        return int(self.rgb.shape[0])


def _fit_exactly(rgb: np.ndarray, display: tuple[int, int], src_w: int, src_h: int) -> np.ndarray:
    """``rgb`` (a ``src_w`` x ``src_h`` picture, maybe already reduced) made exactly the rectangle it fills
    fitted into ``display`` (:func:`.viewport.fitted_pixels`: the view then draws it 1:1) when that is no
    bigger than the source; a picture smaller than its display stays as it is (never upscaled here)."""
    _x, _y, w, h = fitted_pixels(display, src_w, src_h)
    if w > src_w or h > src_h or w > rgb.shape[1] or h > rgb.shape[0]:
        return rgb
    return resize_exactly(rgb, w, h)


def _stamp(msg: dict[str, Any]) -> float | None:
    header = msg.get("header")
    if not isinstance(header, dict):
        return None
    stamp = header.get("stamp")
    if not rtime.is_time(stamp):
        return None
    try:
        value = rtime.to_float(stamp)
    except (TypeError, ValueError):
        return None
    return value if value > 0 else None


def _meta(msg: dict[str, Any]) -> dict[str, Any]:
    """The message without its bulk (kept as ``state.message``)."""
    return {k: v for k, v in msg.items() if k not in ("data", "ranges", "intensities")}


class ImageModel(WidgetModel):
    """Decodes images, compressed images, laser scans and occupancy grids into :class:`Frame` values."""

    stale_after = 3.0

    def __init__(self, settings: Any, binding: Any, port: Any, **kwargs: Any) -> None:
        super().__init__(settings if settings is not None else ImageSettings(), binding, port, **kwargs)
        self._worker: SlotWorker | None = None
        self._worker_lock = threading.Lock()
        self._frames = 0
        self._times: collections.deque[float] = collections.deque(maxlen=90)
        self._frame_cond = threading.Condition()
        self._display_lock = threading.Lock()
        self._display: tuple[int, int] | None = None
        self._video_worker: QueueWorker | None = None
        self._video_decoder: VideoDecoder | None = None
        self._video_broken: str | None = None  # why video cannot be shown here (PyAV or a codec missing)
        self._notice: str | None = None
        #: with ``transport = "best"``: the transport picked (None until the robot answered)
        self.transport: Choice | None = None
        #: what the overlay says of the transport ("via video: /cam/image_raw/foxglove (offered: ...)")
        self.transport_note: str | None = None
        #: bytes and messages per second as they arrive (the overlay's link cost)
        self.meter = RateMeter()

    # -- server options ---------------------------------------------------------------------------------
    def subscribe_options(self) -> dict[str, Any]:
        return self.options_for(self.binding.type)

    def options_for(self, type_name: str) -> dict[str, Any]:
        """What the server is asked for a topic of ``type_name``: video every packet with a short queue;
        images at most ``max_fps`` with a queue of one (a slow link gets the latest frame, not a queue)."""
        s = self.settings
        comp = s.compression
        if is_video_type(type_name):
            # never throttled: a skipped packet would break the chain up to the next keyframe
            return {"queue_length": VIDEO_QUEUE_LENGTH, "compression": "cbor" if comp == "auto" else comp}
        opts: dict[str, Any] = {"queue_length": 1}
        if s.max_fps > 0:
            # 90% of the frame period: a stream at exactly max_fps is not halved by arrival jitter
            opts["throttle_rate"] = int(900 / s.max_fps)
        opts["compression"] = "cbor" if comp == "auto" else comp
        return opts

    # -- lifecycle ------------------------------------------------------------------------------------
    def on_start(self) -> None:
        self._ensure_worker()
        self.transport_note = None
        if self.settings.transport == "best" and not self.binding.problems():
            try:
                loop = asyncio.get_running_loop()
            except RuntimeError:  # started off the bridge loop (a bare test): the topic as bound
                self.transport_note = "as bound (no robot link to ask for the camera's transports)"
                return
            task = loop.create_task(self._pick_transport(), name="image-transport")
            self._tasks.add(task)
            task.add_done_callback(self._tasks.discard)

    async def _pick_transport(self) -> None:
        """Ask the robot's topic list and move the subscription to the camera's best transport (loop)."""
        b = self.binding
        try:
            answer = await self.port.call_service("/rosapi/topics", {})
            topics = dict(zip(answer.get("topics") or [], answer.get("types") or [], strict=False))
        except Exception as exc:  # noqa: BLE001 - no list: the topic as bound, and the overlay says why
            self.transport_note = f"as bound (the robot's topic list: {type(exc).__name__}: {exc})"[:160]
            self.announce()
            return
        choice = pick(b.name, b.type, topics)
        self.transport = choice
        self.transport_note = choice.note()
        if choice.topic != b.name and self.running:
            old, self._sub = self._sub, None
            if old is not None:
                old.unsubscribe()
            self._sub = self.port.subscribe(choice.topic, self._receive, type=choice.type_name,
                                            **self.options_for(choice.type_name))
        self.replace_value(self.state.value)

    def on_stop(self) -> None:
        with self._worker_lock:
            worker, self._worker = self._worker, None
            video, self._video_worker = self._video_worker, None
        if worker is not None:
            worker.close(timeout=0.5)
        if video is not None:
            video.close(timeout=0.5)

    def _ensure_worker(self) -> SlotWorker:
        with self._worker_lock:
            if self._worker is None:
                self._worker = SlotWorker("rcon-image-decode", self._decode, self._decode_failed)
            return self._worker

    # -- incoming (bridge loop: cheap) ----------------------------------------------------------------
    def on_message(self, msg: dict[str, Any]) -> None:
        received = time.time()
        path = self.binding.field_path
        try:
            body = get_path(msg, path) if path else msg
        except PathError:
            body = None  # the decode worker says what is wrong with the path
        data = body.get("data") if isinstance(body, dict) else None
        self.meter.add(len(data) if isinstance(data, bytes | bytearray | str | list) else 0)
        if is_video(body):
            if self._video_broken is None:
                self._ensure_video_worker().submit((body, received))
            return
        self._ensure_worker().submit((msg, received))

    def _ensure_video_worker(self) -> QueueWorker:
        with self._worker_lock:
            if self._video_worker is None:
                self._video_decoder = VideoDecoder(self._show_video)
                self._video_worker = QueueWorker("rcon-video-decode", self._decode_video, self._video_failed,
                                                 max_items=MAX_BACKLOG)
            return self._video_worker

    @property
    def video_worker(self) -> QueueWorker | None:
        """The video decoding thread's worker once a video packet came (None before, and once stopped)."""
        return self._video_worker

    @property
    def video(self) -> VideoDecoder | None:
        """The video decoder once a video packet came (its ``stream`` and ``info``: tests, the overlay)."""
        return self._video_decoder

    @property
    def notice(self) -> str | None:
        """What the widget says besides its picture: "waiting for a keyframe (...)" while video packets are
        dropped until one; None otherwise."""
        return self._notice

    def _set_notice(self, text: str | None) -> None:
        if text != self._notice:
            self._notice = text
            self.replace_value(self.state.value)  # the view repaints with it (seq moves)

    @property
    def worker(self) -> SlotWorker | None:
        """The decoding thread's worker while the model runs (None once stopped)."""
        return self._worker

    @property
    def dropped(self) -> int:
        w = self._worker
        return w.slot.dropped if w is not None else 0

    # -- display size (any thread) --------------------------------------------------------------------
    def set_display_size(self, width: float, height: float) -> None:
        """The box, in device pixels, the view fits the picture into (its size x device pixel ratio, times
        its zoom when zoomed in). Frames decoded from now on carry no more pixels than a picture fitted
        there needs (a picture bigger than the fitted rectangle is made exactly that rectangle's size:
        :func:`.viewport.fitted_pixels`); a 0 (or less) = full resolution. Thread-safe, cheap, no Qt: the
        view calls it on resize and zoom; the next frame comes at the new size."""
        w, h = math.ceil(width), math.ceil(height)
        with self._display_lock:
            self._display = (w, h) if w > 0 and h > 0 else None

    @property
    def display_size(self) -> tuple[int, int] | None:
        """What :meth:`set_display_size` set last, or None (full resolution)."""
        with self._display_lock:
            return self._display

    # -- decoding (worker thread) ---------------------------------------------------------------------
    def _decode_failed(self, exc: BaseException) -> None:
        self.set_error(str(exc) if isinstance(exc, DecodeError | PathError) else f"{type(exc).__name__}: {exc}")

    def _video_failed(self, exc: BaseException) -> None:
        if isinstance(exc, VideoUnavailable):
            self._video_broken = str(exc)  # said once; later packets are not even queued
        self._decode_failed(exc)

    def _decode_video(self, items: list[tuple[dict[str, Any], float]], overflowed: bool) -> None:
        """The video worker: every queued packet in order (see :mod:`.video`)."""
        decoder = self._video_decoder
        if decoder is None:
            return
        packets: list[Packet] = []
        bad: DecodeError | None = None
        for body, received in items:
            try:
                packets.append(packet_of(body, received))
            except DecodeError as exc:
                bad = exc
        decoder.handle(packets, overflowed)
        self._set_notice(waiting_text(decoder.info.waiting) or None)
        if bad is not None:
            self.set_error(str(bad))
        with self._frame_cond:
            self._frame_cond.notify_all()

    def _show_video(self, picture: Any, pkt: Packet) -> None:
        """The newest decoded picture of a batch, made a :class:`Frame` at the view's size (worker thread)."""
        src_w, src_h = int(picture.width), int(picture.height)
        display = self.display_size
        w, h = src_w, src_h
        if display is not None:
            _x, _y, fw, fh = fitted_pixels(display, src_w, src_h)
            if fw <= src_w and fh <= src_h:
                w, h = fw, fh
        rgb = picture_rgb(picture, w, h)
        decoder = self._video_decoder
        title = decoder.info.title if decoder is not None else pkt.codec
        info = f"{title} {src_w}×{src_h}"
        frame = self._make_frame(rgb, "video", info, pkt.stamp, pkt.received, src_w, src_h, self.settings.smooth)
        self.set_value(frame, message=None)

    def _make_frame(self, rgb: np.ndarray, kind: str, info: str, stamp: float | None, received: float,
                    src_w: int, src_h: int, smooth: bool, counts: ScanCounts | None = None) -> Frame:
        now = time.time()
        with self._frame_cond:
            self._frames += 1
            self._times.append(now)
            index = self._frames
            fps = 0.0
            if len(self._times) > 1 and self._times[-1] > self._times[0]:
                fps = (len(self._times) - 1) / (self._times[-1] - self._times[0])
        return Frame(rgb=rgb, kind=kind, info=info, stamp=stamp, received=received, decoded=now,
                     index=index, fps=fps, dropped=self.dropped, smooth=smooth, counts=counts,
                     byte_rate=self.meter.rates()[0],
                     source_width=src_w or int(rgb.shape[1]), source_height=src_h or int(rgb.shape[0]))

    def decode(self, msg: dict[str, Any], received: float | None = None) -> Frame:
        """Turn one message into a :class:`Frame` (any thread; the worker calls it)."""
        received = time.time() if received is None else received
        path = self.binding.field_path
        body = get_path(msg, path) if path else msg
        s = self.settings
        if is_video(body):
            raise DecodeError("video packets are decoded in order by the video worker, not one at a time")
        kind = message_kind(body)
        depth = (s.depth_min, s.depth_max) if s.depth_max > s.depth_min else None
        counts = None
        smooth = s.smooth
        display = self.display_size
        src_w = src_h = 0
        if kind == "image":
            rgb = decode_image(body, depth, display)
            src_w, src_h = int(body["width"]), int(body["height"])  # decode_image checked them
            info = f"{src_w}×{src_h} {body.get('encoding')}"
        elif kind == "compressed":
            rgb, src_w, src_h = decode_compressed_sized(body, depth, display)
            info = f"{src_w}×{src_h} {body.get('format') or 'compressed'}"
        elif kind == "scan":
            rgb, counts = render_scan(body, max_range=s.scan_range or None)
            info = f"{counts.valid} hits, {counts.out_of_range} out of range, {counts.invalid} no return"
        elif kind == "grid":
            rgb = render_grid(body)
            res = (body.get("info") or {}).get("resolution")
            info = f"{rgb.shape[1]}×{rgb.shape[0]} cells" + (f" at {float(res):g} m" if res else "")
            smooth = False
        else:
            raise DecodeError("this message is not an image, compressed image, laser scan or occupancy grid")
        if display is not None and kind in ("image", "compressed"):
            rgb = _fit_exactly(rgb, display, src_w, src_h)
        return self._make_frame(rgb, kind, info, _stamp(body), received, src_w, src_h, smooth, counts)

    def _decode(self, item: tuple[dict[str, Any], float]) -> None:
        msg, received = item
        frame = self.decode(msg, received)
        self.set_value(frame, message=_meta(msg))
        with self._frame_cond:
            self._frame_cond.notify_all()

    def wait_frame(self, after: int = 0, timeout: float = 5.0) -> Frame:
        """Block until a frame with ``index > after`` is ready (tests, benchmarks); TimeoutError if not."""
        deadline = time.monotonic() + timeout
        with self._frame_cond:
            while True:
                value = self.state.value
                if isinstance(value, Frame) and value.index > after:
                    return value
                left = deadline - time.monotonic()
                if left <= 0:
                    err = self.state.error
                    raise TimeoutError(f"no frame within {timeout} s" + (f" (error: {err})" if err else ""))
                self._frame_cond.wait(min(left, 0.1))
