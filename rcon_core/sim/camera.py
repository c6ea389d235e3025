"""Camera images rendered with OpenCV from the vessel's pose: sky, water, the shore, buoys, a clock.

A pinhole camera at ``height`` metres looks along the hull (front) or backwards (rear). The scene without
the overlay is cached by a quantised pose, so a vessel at rest costs a copy and a line of text per frame.

A new scene is cheap too (the vessel rolls and pitches all the time, so it is the usual case): full-frame sky,
water and shore images are made once, and each column's first shore row and first water row (from the tilted
horizon and the shore's height at that bearing) pick between them. Rows above every column's first shore row
are one copy of the sky, rows below every column's first water row one copy of the water, and only the rows
in between are chosen pixel by pixel, with OpenCV's masked copy. Big copies and OpenCV calls release the GIL,
so the drawing thread leaves the sim's event loop free.

The scene, the frame with its text and the JPEG encoder's BGR copy are drawn into buffers each camera keeps
(``render``), not into new ones: a new megabyte costs its page faults every time (about a millisecond a
buffer in a virtual machine), which was most of a frame once the scene got cheap.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from typing import TypeVar

import cv2
import numpy as np

from .vessel import Vessel
from .world import BUOYS

SHORE_Y = 40.0
SHORE_HEIGHT = 9.0
SHORE_COLOUR = (70, 85, 70)

T = TypeVar("T")


class CameraRenderer:
    """Renders RGB frames for one camera mounted on the vessel."""

    def __init__(self, name: str, width: int = 640, height: int = 480, hfov_deg: float = 90.0,
                 yaw_offset: float = 0.0, mount_height: float = 0.6, *,
                 sky: tuple[tuple[int, int, int], tuple[int, int, int]] = ((120, 170, 225), (200, 225, 245)),
                 bow: tuple[tuple[int, int, int], str] | None = None, vessel_name: str | None = None) -> None:
        self.name = name
        #: (hull colour, painted text): the bow seen at the bottom of the picture (a fleet's vessel)
        self.bow = bow
        self.vessel_name = vessel_name
        self.width = width
        self.height = height
        self.yaw_offset = yaw_offset
        self.mount_height = mount_height
        self.focal = (width / 2) / math.tan(math.radians(hfov_deg) / 2)
        self._cols = np.arange(width, dtype=np.float64)
        self._col_angles = np.arctan((width / 2 - self._cols) / self.focal)  # left of centre is positive
        self._sky = self._full(self._gradient(sky[0], sky[1], height))
        self._water = self._full(self._gradient((60, 110, 140), (20, 55, 80), height))
        self._shore = np.empty_like(self._sky)
        self._shore[:] = SHORE_COLOUR
        self._cache_key: tuple[int, ...] | None = None
        self._cache = np.empty_like(self._sky)  # the scene without the text, for _cache_key
        self._work = np.empty_like(self._sky)  # the frame being handed out by render()
        self._bgr = np.empty_like(self._sky)  # the JPEG encoder's input
        self._lock = threading.Lock()  # one frame at a time in the buffers above
        self.renders = 0

    @staticmethod
    def _gradient(top: tuple[int, int, int], bottom: tuple[int, int, int], rows: int) -> np.ndarray:
        t = np.linspace(0.0, 1.0, rows)[:, None]
        return (np.array(top)[None, :] * (1 - t) + np.array(bottom)[None, :] * t).astype(np.uint8)

    def _full(self, gradient: np.ndarray) -> np.ndarray:
        """A (height x width x 3) image of a per-row ``gradient``: every column the same."""
        return np.ascontiguousarray(np.broadcast_to(gradient[:, None, :], (self.height, self.width, 3)))

    def frame(self, vessel: Vessel, stamp: float | None = None) -> np.ndarray:
        """An RGB uint8 image (height x width x 3) of what the camera sees now (a new array)."""
        return self.render(vessel, stamp, np.copy)

    def render(self, vessel: Vessel, stamp: float | None, use: Callable[[np.ndarray], T]) -> T:
        """Draw the frame into this camera's own buffer and return ``use(frame)``; ``use`` must not keep the
        array (copy or encode it: ``ndarray.tobytes``, :meth:`jpeg`). One caller at a time draws."""
        with self._lock:
            return use(self._draw(vessel, stamp))

    def jpeg(self, rgb: np.ndarray, quality: int = 80) -> bytes:
        """``rgb`` (a frame of this camera's size) as JPEG, converted to BGR in the camera's own buffer."""
        return encode_jpeg(rgb, quality, self._bgr)

    def _draw(self, vessel: Vessel, stamp: float | None) -> np.ndarray:
        heading = vessel.yaw + self.yaw_offset
        key = (round(vessel.x * 10), round(vessel.y * 10), round(heading * 200), round(vessel.roll * 300),
               round(vessel.pitch * 300), int(vessel.lights))
        if key != self._cache_key:
            self._cache_key = None  # a scene that fails half-way is drawn again next time
            self._scene(vessel, heading, self._cache)
            self._cache_key = key
            self.renders += 1
        img = self._work
        np.copyto(img, self._cache)
        stamp = time.time() if stamp is None else stamp
        text = time.strftime("%Y-%m-%d %H:%M:%S", time.gmtime(stamp)) + f".{int(stamp * 10) % 10} UTC"
        camera = f"{self.vessel_name} {self.name}" if self.vessel_name else self.name
        label = f"{camera}  {math.degrees(heading) % 360:05.1f} deg  {vessel.surge:+.2f} m/s"
        for y, line in ((self.height - 32, label), (self.height - 12, text)):
            cv2.putText(img, line, (10, y), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (0, 0, 0), 3, cv2.LINE_AA)
            cv2.putText(img, line, (10, y), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (255, 255, 255), 1, cv2.LINE_AA)
        return img

    def _scene(self, vessel: Vessel, heading: float, img: np.ndarray) -> None:
        """Draw what the camera sees, without the text, into ``img``."""
        w, h, f = self.width, self.height, self.focal
        sign = 1.0 if self.yaw_offset == 0.0 else -1.0
        pitch = vessel.pitch * sign
        roll = vessel.roll * sign
        # horizon row per column, tilted by roll and shifted by pitch
        horizon = h / 2 + f * math.tan(pitch) + (self._cols - w / 2) * math.tan(roll)
        # the shore: a band above the horizon where a column's ray meets the line y = SHORE_Y
        theta = heading + self._col_angles
        s = np.sin(theta)
        with np.errstate(divide="ignore", invalid="ignore"):
            dist = np.where(s > 1e-3, (SHORE_Y - vessel.y) / s, np.inf)
        dist = np.where(dist > 0.5, dist, np.inf)
        band = np.where(np.isfinite(dist), np.clip(f * SHORE_HEIGHT / np.maximum(dist, 1.0), 0, h), 0.0)
        # a row r is water where r >= horizon, shore where horizon - band <= r < horizon (if band > 0.5):
        # as whole rows, water from ceil(horizon) and shore from ceil(horizon - band)
        water_from = np.clip(np.ceil(horizon), 0, h).astype(np.intp)
        shore_from = np.where(band > 0.5, np.clip(np.ceil(horizon - band), 0, h).astype(np.intp), water_from)
        top, bottom = int(shore_from.min()), int(water_from.max())
        img[:bottom] = self._sky[:bottom]
        img[bottom:] = self._water[bottom:]
        if top < bottom:  # the rows where columns differ: sky, then shore, then water
            rows = np.arange(top, bottom)[:, None]
            mixed = img[top:bottom]  # a view: OpenCV's masked copies write into img
            cv2.copyTo(self._shore[top:bottom], (rows >= shore_from).view(np.uint8), mixed)
            cv2.copyTo(self._water[top:bottom], (rows >= water_from).view(np.uint8), mixed)
        # buoys, far to near
        items = []
        for b in BUOYS:
            dx, dy = b.x - vessel.x, b.y - vessel.y
            dist_b = math.hypot(dx, dy)
            rel = (math.atan2(dy, dx) - heading + math.pi) % (2 * math.pi) - math.pi
            if dist_b < 0.5 or abs(rel) > math.radians(60):
                continue
            items.append((dist_b, rel, b))
        for dist_b, rel, b in sorted(items, key=lambda i: -i[0]):
            forward = dist_b * math.cos(rel)
            if forward <= 0.3:
                continue
            u = w / 2 - f * math.tan(rel)
            v_water = h / 2 + f * math.tan(pitch) + (u - w / 2) * math.tan(roll) + f * self.mount_height / forward
            r = max(1, int(f * b.radius / forward))
            cx, cy = int(u), int(v_water)
            color = tuple(int(c) for c in b.color)
            cv2.ellipse(img, (cx, cy), (r, max(1, r // 3)), 0, 0, 360, (30, 50, 60), -1, cv2.LINE_AA)
            cv2.rectangle(img, (cx - r, cy - 2 * r), (cx + r, cy), color, -1, cv2.LINE_AA)
            cv2.circle(img, (cx, cy - 2 * r), r, color, -1, cv2.LINE_AA)
            if vessel.lights and dist_b < 25:
                cv2.circle(img, (cx, cy - 2 * r), max(1, r // 2), (255, 255, 210), -1, cv2.LINE_AA)
        if self.bow is not None:
            self._draw_bow(img, *self.bow)

    def _draw_bow(self, img: np.ndarray, colour: tuple[int, int, int], text: str) -> None:
        """The vessel's own bow, in its hull colour with its name painted on, at the bottom centre."""
        w, h = self.width, self.height
        top, base = int(h * 0.80), h
        pts = np.array([[w // 2, top], [int(w * 0.70), base], [int(w * 0.30), base]], dtype=np.int32)
        cv2.fillConvexPoly(img, pts, colour, cv2.LINE_AA)
        shade = (0, 0, 0) if sum(colour) > 380 else (255, 255, 255)
        scale = 0.6
        (tw, th), _ = cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, scale, 2)
        cv2.putText(img, text, (w // 2 - tw // 2, top + int(0.55 * (base - top))), cv2.FONT_HERSHEY_SIMPLEX, scale, shade, 2,
                    cv2.LINE_AA)


def encode_jpeg(rgb: np.ndarray, quality: int = 80, bgr: np.ndarray | None = None) -> bytes:
    """``rgb`` as JPEG bytes; ``bgr`` (same shape) is a buffer to convert it in, else a new one is made."""
    bgr = cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR, dst=bgr)
    ok, buf = cv2.imencode(".jpg", bgr, [cv2.IMWRITE_JPEG_QUALITY, quality])
    if not ok:
        raise RuntimeError("JPEG encoding failed")
    return buf.tobytes()
