"""The Camera widget's settings, capture sources and model (no Qt).

A capture thread (never the GUI thread, never the bridge loop) grabs frames at the chosen rate from this
device's camera (OpenCV ``VideoCapture``) or a synthetic moving test pattern, encodes them (JPEG at the
chosen quality for ``sensor_msgs/CompressedImage``, rgb8 for ``sensor_msgs/Image``; base64, as the
bridge sends JSON), publishes them
through the model (handed to the bridge loop by ``dispatch``) and shows a preview (an image
:class:`~.image.Frame`, painted by the Image view). No camera: a clear error, nothing published.
"""

from __future__ import annotations

import threading
import time
from typing import Any, Protocol

import attrs
import cv2
import numpy as np

from rcon_core.msgs.values import to_base64
from rcon_core.plugins import WidgetModel

from .image import Frame

__all__ = ["CameraSettings", "CameraModel", "TestPattern", "OpenCVCamera", "CameraError", "SOURCES"]

SOURCES = ("device", "test pattern")


class CameraError(RuntimeError):
    """The camera cannot be opened or stopped giving frames."""


@attrs.define
class CameraSettings:
    """``source``: this device's camera or a moving test pattern. ``device_index``: which camera (0 = the
    first). ``fps``: frames published per second. ``quality``: JPEG quality 1-100. ``width``/``height``:
    the size asked of the camera (and of the pattern). ``frame_id``: the header's frame."""

    source: str = "device"
    device_index: int = 0
    fps: float = 10.0
    quality: int = 80
    width: int = 640
    height: int = 480
    frame_id: str = "camera"

    def problems(self) -> list[str]:
        out = []
        if self.source not in SOURCES:
            out.append(f"source must be one of {', '.join(SOURCES)}, not {self.source!r}")
        if not 0 <= self.device_index <= 63:
            out.append(f"the camera index must be between 0 and 63, not {self.device_index}")
        if not 0.2 <= self.fps <= 60:
            out.append(f"the frame rate must be between 0.2 and 60 fps, not {self.fps:g}")
        if not 1 <= self.quality <= 100:
            out.append(f"the JPEG quality must be between 1 and 100, not {self.quality}")
        if not (16 <= self.width <= 4096 and 16 <= self.height <= 4096):
            out.append(f"the size must be between 16 and 4096 pixels a side, not {self.width}x{self.height}")
        return out


class FrameSource(Protocol):
    def read(self) -> np.ndarray: ...  # RGB uint8 H x W x 3; raises CameraError
    def close(self) -> None: ...


class TestPattern:
    """A moving pattern: colour bars, a sweeping bar, a bouncing disc, the frame number and the time."""

    __test__ = False  # not a pytest class

    def __init__(self, width: int = 640, height: int = 480) -> None:
        self.width, self.height = width, height
        bars = np.array([(235, 235, 235), (235, 235, 16), (16, 235, 235), (16, 235, 16), (235, 16, 235),
                         (235, 16, 16), (16, 16, 235), (40, 40, 40)], np.uint8)
        cols = (np.arange(width) * len(bars) // width)
        self._base = np.ascontiguousarray(np.broadcast_to(bars[cols][None, :, :], (height, width, 3)))
        self.count = 0

    def read(self) -> np.ndarray:
        w, h, i = self.width, self.height, self.count
        img = self._base.copy()
        x = (i * 8) % w
        img[:, x:x + max(2, w // 80)] = 0
        t = i / 15.0
        cy = int(h / 2 + h / 4 * np.sin(t))
        cx = int(w / 2 + w / 3 * np.cos(t * 0.7))
        cv2.circle(img, (cx, cy), max(4, h // 10), (255, 255, 255), -1, cv2.LINE_AA)
        text = f"RCON test pattern  #{i}  {time.strftime('%H:%M:%S')}"
        cv2.putText(img, text, (10, h - 14), cv2.FONT_HERSHEY_SIMPLEX, max(0.4, w / 1400), (0, 0, 0), 3, cv2.LINE_AA)
        cv2.putText(img, text, (10, h - 14), cv2.FONT_HERSHEY_SIMPLEX, max(0.4, w / 1400), (255, 255, 255), 1,
                    cv2.LINE_AA)
        self.count += 1
        return img

    def close(self) -> None:
        pass


class OpenCVCamera:
    """This device's camera through OpenCV."""

    def __init__(self, index: int, width: int, height: int) -> None:
        self.index = index
        cap = cv2.VideoCapture(index)
        if not cap.isOpened():
            cap.release()
            raise CameraError(f"no camera at index {index} on this device (or it is in use by another program)")
        cap.set(cv2.CAP_PROP_FRAME_WIDTH, width)
        cap.set(cv2.CAP_PROP_FRAME_HEIGHT, height)
        self._cap = cap

    def read(self) -> np.ndarray:
        ok, bgr = self._cap.read()
        if not ok or bgr is None:
            raise CameraError(f"camera {self.index} stopped giving frames")
        return cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)

    def close(self) -> None:
        self._cap.release()


def open_source(settings: CameraSettings) -> FrameSource:
    if settings.source == "test pattern":
        return TestPattern(settings.width, settings.height)
    return OpenCVCamera(settings.device_index, settings.width, settings.height)


def pace(due: float, period: float, now: float) -> tuple[float, float]:
    """After a frame due at ``due``: (when the next one is due, how long to wait for it). Steady at
    ``period``; a capture that fell behind starts again from ``now`` (frames are skipped, never burst)."""
    due += period
    wait = due - now
    if wait < 0:
        return now, 0.0
    return due, wait


class CameraModel(WidgetModel):
    """Captures, encodes and publishes on its own thread; the preview is a :class:`Frame`."""

    stale_after = None

    def __init__(self, settings: Any, binding: Any, port: Any, **kwargs: Any) -> None:
        super().__init__(settings if settings is not None else CameraSettings(), binding, port, **kwargs)
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.sent = 0
        self.source_factory = open_source  # tests may replace it

    @property
    def capturing(self) -> bool:
        """True while the capture thread runs (from start until stop)."""
        thread = self._thread
        return thread is not None and thread.is_alive()

    @property
    def raw(self) -> bool:
        """True when bound to ``sensor_msgs/Image`` (rgb8), False for ``CompressedImage`` (jpeg)."""
        return self.binding.canonical_type == "sensor_msgs/msg/Image"

    def encode(self, rgb: np.ndarray, stamp: float) -> dict[str, Any]:
        """The message for one frame."""
        ns = int(stamp * 1e9)
        header = {"seq": 0, "stamp": {"secs": ns // 1_000_000_000, "nsecs": ns % 1_000_000_000},
                  "frame_id": self.settings.frame_id}
        if self.types is not None:
            try:
                default_stamp = self.types.default(self.binding.type)["header"]["stamp"]
                if "sec" in default_stamp:
                    header["stamp"] = {"sec": ns // 1_000_000_000, "nanosec": ns % 1_000_000_000}
                    header.pop("seq")
            except Exception:  # noqa: BLE001 - keep the ROS 1 shape
                pass
        h, w = rgb.shape[:2]
        if self.raw:
            return {"header": header, "height": h, "width": w, "encoding": "rgb8", "is_bigendian": 0,
                    "step": w * 3, "data": to_base64(rgb.tobytes())}
        ok, buf = cv2.imencode(".jpg", cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR),
                               [cv2.IMWRITE_JPEG_QUALITY, int(self.settings.quality)])
        if not ok:
            raise CameraError("JPEG encoding failed")
        # base64 here, on the capture thread: the bridge sends JSON text
        return {"header": header, "format": "jpeg", "data": to_base64(buf.tobytes())}

    # -- lifecycle ------------------------------------------------------------------------------------
    def on_start(self) -> None:
        if self._pub is None:
            return
        self._stop.clear()
        self._thread = threading.Thread(target=self._run, name="rcon-camera", daemon=True)
        self._thread.start()

    def on_stop(self) -> None:
        self._stop.set()
        thread, self._thread = self._thread, None
        if thread is not None and thread is not threading.current_thread():
            thread.join(2.0)

    def _run(self) -> None:
        s = self.settings
        try:
            source = self.source_factory(s)
        except Exception as exc:  # noqa: BLE001 - CameraError or a driver problem: say it
            self.set_error(str(exc))
            return
        period = 1.0 / s.fps
        due = time.monotonic()
        index = 0
        times: list[float] = []
        try:
            while not self._stop.is_set():
                try:
                    rgb = source.read()
                except Exception as exc:  # noqa: BLE001
                    self.set_error(str(exc))
                    return
                stamp = time.time()
                msg = self.encode(rgb, stamp)
                if self._stop.is_set():
                    return
                self.publish(msg)
                self.sent += 1
                index += 1
                now = time.monotonic()
                times = [t for t in times if now - t < 2.0] + [now]
                fps = (len(times) - 1) / (times[-1] - times[0]) if len(times) > 1 else 0.0
                kind = "raw rgb8" if self.raw else f"jpeg q{s.quality}, {len(msg['data']) * 3 // 4096} KiB"
                info = f"{rgb.shape[1]}×{rgb.shape[0]} {kind} → {self.binding.name} · {self.sent} sent"
                self.set_value(Frame(rgb=rgb, kind="camera", info=info, stamp=stamp, received=stamp,
                                     decoded=time.time(), index=index, fps=fps))
                due, wait = pace(due, period, time.monotonic())
                self._stop.wait(wait)
        finally:
            source.close()
