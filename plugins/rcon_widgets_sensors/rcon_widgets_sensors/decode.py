"""Turn image-like ROS messages into RGB pixels (numpy + OpenCV, no Qt).

Every function returns an ``H x W x 3`` C-contiguous ``uint8`` RGB array, or raises :class:`DecodeError`
with a sentence a person can act on. Handled:

* ``sensor_msgs/Image``: rgb8, bgr8, rgba8, bgra8, mono8, mono16, 8UC1/3/4, 16UC1 and 32FC1 depth
  (false colour), the four 8-bit bayer patterns, yuv422 (UYVY) and yuv422_yuy2;
* ``sensor_msgs/CompressedImage``: jpeg, png (also 16-bit png, ``compressedDepth``);
* ``sensor_msgs/LaserScan``: drawn top-down (see :mod:`.scan_render`); ``nav_msgs/OccupancyGrid``.

The kind of message is read from its fields, so a sub-message bound by field path works too.
"""

from __future__ import annotations

from typing import Any

import cv2
import numpy as np

from rcon_core.msgs.values import as_bytes

__all__ = ["DecodeError", "decode_image", "decode_compressed", "depth_to_rgb", "message_kind",
           "RAW_ENCODINGS"]


class DecodeError(ValueError):
    """A message could not be turned into pixels; ``str()`` says why."""


# ROS bayer names -> OpenCV codes (OpenCV names a pattern after its second row)
_BAYER = {
    "bayer_rggb8": cv2.COLOR_BayerBG2RGB,
    "bayer_bggr8": cv2.COLOR_BayerRG2RGB,
    "bayer_gbrg8": cv2.COLOR_BayerGR2RGB,
    "bayer_grbg8": cv2.COLOR_BayerGB2RGB,
}
# encoding -> (channels, dtype)
_LAYOUT: dict[str, tuple[int, str]] = {
    "rgb8": (3, "u1"), "bgr8": (3, "u1"), "rgba8": (4, "u1"), "bgra8": (4, "u1"),
    "mono8": (1, "u1"), "8uc1": (1, "u1"), "8uc3": (3, "u1"), "8uc4": (4, "u1"),
    "mono16": (1, "u2"), "16uc1": (1, "u2"), "32fc1": (1, "f4"),
    "yuv422": (2, "u1"), "yuv422_yuy2": (2, "u1"),
    **{name: (1, "u1") for name in _BAYER},
}
RAW_ENCODINGS = tuple(sorted(_LAYOUT))


def message_kind(msg: Any) -> str:
    """``"image"``, ``"compressed"``, ``"scan"``, ``"grid"`` or ``""`` from the fields of ``msg``."""
    if not isinstance(msg, dict):
        return ""
    if "encoding" in msg and "height" in msg and "data" in msg:
        return "image"
    if "format" in msg and "data" in msg:
        return "compressed"
    if "ranges" in msg and "angle_min" in msg:
        return "scan"
    if "info" in msg and "data" in msg and isinstance(msg.get("info"), dict) and "resolution" in msg["info"]:
        return "grid"
    return ""


def _contig(a: np.ndarray) -> np.ndarray:
    return a if a.flags.c_contiguous else np.ascontiguousarray(a)


def depth_to_rgb(depth: np.ndarray, lo: float | None = None, hi: float | None = None) -> np.ndarray:
    """False-colour a depth image (any numeric dtype). Zero, NaN and ±inf pixels (no reading) are black.

    ``lo``/``hi``: the range mapped onto the colour map; default: the valid pixels' 1st..99th percentile.
    """
    d = depth.astype(np.float32, copy=False)
    valid = np.isfinite(d) & (d > 0)
    out = np.zeros(d.shape + (3,), np.uint8)
    if not valid.any():
        return out
    vals = d[valid]
    if lo is None or hi is None:
        sample = vals[:: max(1, vals.size // 20000)]
        p_lo, p_hi = np.percentile(sample, (1, 99))
        lo = float(p_lo) if lo is None else lo
        hi = float(p_hi) if hi is None else hi
    span = max(hi - lo, 1e-9)
    scaled = np.clip((np.nan_to_num(d, nan=lo, posinf=hi, neginf=lo) - lo) * (255.0 / span), 0, 255).astype(np.uint8)
    colour = cv2.applyColorMap(scaled, cv2.COLORMAP_TURBO)  # BGR
    cv2.cvtColor(colour, cv2.COLOR_BGR2RGB, dst=colour)
    colour[~valid] = 0
    return colour


def decode_image(msg: dict[str, Any], depth_range: tuple[float, float] | None = None) -> np.ndarray:
    """A ``sensor_msgs/Image`` dict -> RGB pixels."""
    try:
        width, height = int(msg["width"]), int(msg["height"])
        encoding = str(msg.get("encoding", "")).strip()
    except (KeyError, TypeError, ValueError) as exc:
        raise DecodeError(f"not an image message: {exc}") from None
    enc = encoding.lower()
    if enc not in _LAYOUT:
        raise DecodeError(f"image encoding {encoding!r} is not supported (supported: {', '.join(RAW_ENCODINGS)})")
    if width <= 0 or height <= 0:
        raise DecodeError(f"empty image ({width}x{height})")
    channels, kind = _LAYOUT[enc]
    dtype = np.dtype(kind)
    if dtype.itemsize > 1:
        dtype = dtype.newbyteorder(">" if msg.get("is_bigendian") else "<")
    row = width * channels * dtype.itemsize
    step = int(msg.get("step") or row)
    if step < row:
        raise DecodeError(f"image step {step} is less than width x bytes per pixel = {row}")
    try:
        data = as_bytes(msg.get("data"))
    except ValueError as exc:
        raise DecodeError(f"image data: {exc}") from None
    if len(data) < step * height:
        raise DecodeError(f"image data has {len(data)} bytes, expected step x height = {step} x {height} "
                          f"= {step * height}")
    rows = np.frombuffer(data, np.uint8, count=step * height).reshape(height, step)[:, :row]
    pix = rows.view(dtype).reshape(height, width, channels) if channels > 1 else rows.view(dtype).reshape(
        height, width)
    if enc in ("rgb8",):
        return _contig(pix)
    if enc in ("bgr8", "8uc3"):
        return cv2.cvtColor(_contig(pix), cv2.COLOR_BGR2RGB)
    if enc == "rgba8":
        return cv2.cvtColor(_contig(pix), cv2.COLOR_RGBA2RGB)
    if enc in ("bgra8", "8uc4"):
        return cv2.cvtColor(_contig(pix), cv2.COLOR_BGRA2RGB)
    if enc in ("mono8", "8uc1"):
        return cv2.cvtColor(_contig(pix), cv2.COLOR_GRAY2RGB)
    if enc == "mono16":
        return cv2.cvtColor((pix.astype(np.uint16) >> 8).astype(np.uint8), cv2.COLOR_GRAY2RGB)
    if enc in ("16uc1", "32fc1"):
        lo, hi = depth_range if depth_range else (None, None)
        return depth_to_rgb(pix, lo, hi)
    if enc in _BAYER:
        return cv2.cvtColor(_contig(pix), _BAYER[enc])
    if enc == "yuv422":
        return cv2.cvtColor(_contig(pix), cv2.COLOR_YUV2RGB_UYVY)
    return cv2.cvtColor(_contig(pix), cv2.COLOR_YUV2RGB_YUY2)  # yuv422_yuy2


_PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def decode_compressed(msg: dict[str, Any], depth_range: tuple[float, float] | None = None) -> np.ndarray:
    """A ``sensor_msgs/CompressedImage`` dict (jpeg or png, incl. ``compressedDepth``) -> RGB pixels."""
    fmt = str(msg.get("format", "")).lower()
    try:
        data = as_bytes(msg.get("data"))
    except ValueError as exc:
        raise DecodeError(f"compressed image data: {exc}") from None
    if not data:
        raise DecodeError("compressed image has no data")
    if "compresseddepth" in fmt:  # image_transport's compressedDepth: a 12-byte config header, then PNG
        at = data.find(_PNG_SIGNATURE)
        if at < 0:
            raise DecodeError("compressedDepth image without a PNG inside")
        data = data[at:]
    buf = np.frombuffer(data, np.uint8)
    head = data[:4]
    looks_jpeg = head[:3] == b"\xff\xd8\xff"
    if looks_jpeg and "png" not in fmt:
        img = cv2.imdecode(buf, cv2.IMREAD_COLOR_RGB)
        if img is None:
            raise DecodeError(f"could not decode the JPEG image ({len(data)} bytes; format {fmt!r})")
        return img
    img = cv2.imdecode(buf, cv2.IMREAD_UNCHANGED)
    if img is None:
        kind = "PNG" if data.startswith(_PNG_SIGNATURE) else ("JPEG" if looks_jpeg else fmt or "unknown")
        raise DecodeError(f"could not decode the {kind} image ({len(data)} bytes; format {fmt!r})")
    if img.ndim == 2:
        if img.dtype != np.uint8 or "16uc1" in fmt or "32fc1" in fmt:
            lo, hi = depth_range if depth_range else (None, None)
            return depth_to_rgb(img, lo, hi)
        return cv2.cvtColor(img, cv2.COLOR_GRAY2RGB)
    if img.dtype != np.uint8:
        img = (img >> 8).astype(np.uint8)
    if img.shape[2] == 4:
        return cv2.cvtColor(img, cv2.COLOR_BGRA2RGB)
    return cv2.cvtColor(img, cv2.COLOR_BGR2RGB)
