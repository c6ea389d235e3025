"""Pictures, messages and checks shared by the Image widget's size tests (imported by basename: keep the
name unique)."""

from __future__ import annotations

import time

import cv2
import numpy as np

from rcon_core.sim.camera import CameraRenderer, encode_jpeg
from rcon_core.sim.vessel import Vessel


def picture(name: str = "front") -> np.ndarray:
    """A 640x480 RGB picture from the sim's own camera renderer (sky, water, shore, buoys, clock)."""
    return CameraRenderer(name).frame(Vessel(), time.time())


def grid_picture(w: int = 640, h: int = 480) -> np.ndarray:
    """A 4 x 4 grid of flat, distinct colours: every cell's centre is checkable after any scaling."""
    img = np.zeros((h, w, 3), np.uint8)
    for r in range(4):
        for c in range(4):
            img[r * h // 4:(r + 1) * h // 4, c * w // 4:(c + 1) * w // 4] = (40 + 60 * c, 230 - 60 * r,
                                                                              (70 * (r + c)) % 256)
    return img


def stamp() -> dict:
    now = time.time()
    return {"stamp": {"secs": int(now), "nsecs": int(now % 1 * 1e9)}, "frame_id": "cam"}


def raw_msg(rgb: np.ndarray, encoding: str = "rgb8") -> dict:
    """A sensor_msgs/Image of ``rgb`` (rgb8, bgr8 or mono8: the green channel)."""
    h, w = rgb.shape[:2]
    pix = {"rgb8": rgb, "bgr8": rgb[..., ::-1], "mono8": rgb[..., 1]}[encoding]
    return {"header": stamp(), "height": h, "width": w, "encoding": encoding, "is_bigendian": 0,
            "step": w * (1 if pix.ndim == 2 else 3), "data": np.ascontiguousarray(pix).tobytes()}


def jpeg_msg(rgb: np.ndarray) -> dict:
    return {"header": stamp(), "format": "jpeg", "data": encode_jpeg(rgb)}


def mean_abs_diff(a: np.ndarray, b: np.ndarray) -> float:
    assert a.shape == b.shape, (a.shape, b.shape)
    return float(np.abs(a.astype(np.int16) - b.astype(np.int16)).mean())


def area(rgb: np.ndarray, w: int, h: int) -> np.ndarray:
    return cv2.resize(rgb, (w, h), interpolation=cv2.INTER_AREA)


def feed(view, msg: dict):
    """Hand ``msg`` to the view's model, wait for the decoded frame, refresh the view; the frame."""
    from rcon_widgets_sensors.image import Frame

    model = view.model
    before = model.state.value.index if isinstance(model.state.value, Frame) else 0
    model.on_message(msg)
    frame = model.wait_frame(before, 5.0)
    view.refresh(model.state)
    return frame


def grab_rgb(view) -> np.ndarray:
    """What ``view`` paints, as an H x W x 3 RGB array."""
    from qtpy import QtGui

    img = view.grab().toImage().convertToFormat(QtGui.QImage.Format.Format_RGB888)
    rows = np.frombuffer(img.constBits(), np.uint8, img.sizeInBytes()).reshape(img.height(), img.bytesPerLine())
    return rows[:, :img.width() * 3].reshape(img.height(), img.width(), 3).copy()
