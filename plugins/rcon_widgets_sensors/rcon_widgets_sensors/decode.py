"""Turn image-like ROS messages into RGB pixels (numpy + OpenCV, no Qt).

Every function returns an ``H x W x 3`` C-contiguous ``uint8`` RGB array, or raises :class:`DecodeError`
with a sentence a person can act on. Handled:

* ``sensor_msgs/Image``: rgb8, bgr8, rgba8, bgra8, mono8, mono16, 8UC1/3/4, 16UC1 and 32FC1 depth
  (false colour), the four 8-bit bayer patterns, yuv422 (UYVY) and yuv422_yuy2;
* ``sensor_msgs/CompressedImage``: jpeg, png (also 16-bit png, ``compressedDepth``);
* ``sensor_msgs/LaserScan``: drawn top-down (see :mod:`.scan_render`); ``nav_msgs/OccupancyGrid``.

The kind of message is read from its fields, so a sub-message bound by field path works too.

**Decoding at the displayed size.** ``display`` (optional, ``(w, h)`` in device pixels: the box the view
fits the picture into, already grown by its zoom) caps the pixels made: :func:`paint_scale` is how many
display pixels one source pixel becomes there, and nothing is made bigger than that needs. A JPEG is
decoded with OpenCV's reduced decoding (1/2, 1/4 or 1/8 size, far cheaper than a full decode), the
largest reduction still at least the painted size; anything still more than :data:`SHRINK_ABOVE` times
too big (raw images, PNG, a JPEG between two reductions) is shrunk (:func:`shrink`: area-averaged
halvings, then bilinear for the rest, a factor under 2). Never upscaled; no ``display`` (or a 0 in it) =
full resolution. The 8-bit raw encodings are shrunk before their colour conversion (a per-pixel
conversion commutes with the resize), the others (bayer, yuv, 16-bit, depth) after. The Image model
then makes a picture smaller than its fitted size exactly that size (:func:`resize_exactly`), so the
view draws it 1:1.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import cv2
import numpy as np

from rcon_core.msgs.values import as_bytes

__all__ = ["DecodeError", "Decoded", "decode_image", "decode_compressed", "decode_compressed_sized",
           "depth_to_rgb", "message_kind", "paint_scale", "shrink", "resize_exactly",
           "jpeg_size", "RAW_ENCODINGS", "SHRINK_ABOVE"]

#: a picture more than this many times bigger (per side) than it is painted is shrunk on the decode thread;
#: a smaller excess costs the painter's smooth scaling less than a resize here
SHRINK_ABOVE = 1.2
Display = tuple[int, int] | None


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
#: 8-bit encodings whose colour conversion commutes with an area resize: shrunk before converting
_SHRINK_FIRST = frozenset({"rgb8", "bgr8", "8uc3", "rgba8", "bgra8", "8uc4", "mono8", "8uc1"})
#: JPEG reduced decoding straight to RGB: OpenCV's REDUCED_COLOR_n flags are REDUCED_GRAYSCALE_n | COLOR
#: (BGR); with COLOR_RGB instead of COLOR the channels come out in RGB order
_JPEG_READ = {
    1: cv2.IMREAD_COLOR_RGB,
    2: (cv2.IMREAD_REDUCED_COLOR_2 & ~cv2.IMREAD_COLOR) | cv2.IMREAD_COLOR_RGB,
    4: (cv2.IMREAD_REDUCED_COLOR_4 & ~cv2.IMREAD_COLOR) | cv2.IMREAD_COLOR_RGB,
    8: (cv2.IMREAD_REDUCED_COLOR_8 & ~cv2.IMREAD_COLOR) | cv2.IMREAD_COLOR_RGB,
}


class Decoded(NamedTuple):
    """Pixels made for a display, and the size of the picture they came from."""

    rgb: np.ndarray  #: H x W x 3 uint8, at most what the display needs
    width: int  #: the source picture's width in pixels
    height: int


def paint_scale(width: int, height: int, display: Display) -> float:
    """Display pixels per source pixel when a ``width`` x ``height`` picture is fitted (letterboxed) into
    ``display`` = (w, h), at most 1 (never upscaled); 1 when there is no display size (or a 0 in it)."""
    if not display or display[0] <= 0 or display[1] <= 0 or width <= 0 or height <= 0:
        return 1.0
    return min(1.0, display[0] / width, display[1] / height)


def shrink(rgb: np.ndarray, scale: float) -> np.ndarray:
    """``rgb`` (any channel count) resized by ``scale`` when that makes it more than :data:`SHRINK_ABOVE`
    times smaller per side; else ``rgb`` itself. Sizes round up.

    How, for speed: halvings with area interpolation (each an exact 2x2 mean, OpenCV's fast path: under
    0.1 ms for 640x480) while the result stays at least the target, then, if the rest is still more than
    :data:`SHRINK_ABOVE` too big (a factor under 2), bilinear to the target size. One area resize by a
    factor that is not an integer costs 1.5-2 ms for 640x480 on the development machine (measured), more
    than the painter's smooth scaling it saves; a factor under 2 needs no area average."""
    if scale * SHRINK_ABOVE >= 1.0 - 1e-9:  # exactly 1.2x too big is left alone too
        return rgb
    h, w = rgb.shape[:2]
    tw, th = max(1, math.ceil(w * scale - 1e-9)), max(1, math.ceil(h * scale - 1e-9))
    return _reduce(rgb, tw, th, SHRINK_ABOVE)


def resize_exactly(rgb: np.ndarray, width: int, height: int) -> np.ndarray:
    """``rgb`` (any channel count) made exactly ``width`` x ``height`` pixels, which must be no bigger
    than it (a picture the view then draws 1:1): ``rgb`` itself when it is that size already, else the
    same halvings as :func:`shrink`, then one bilinear (area when still 2x or more) resize to the size."""
    h, w = rgb.shape[:2]
    if width > w or height > h or width < 1 or height < 1:
        raise ValueError(f"resize_exactly makes pictures smaller: {w}x{h} cannot become {width}x{height}")
    if (w, h) == (width, height):
        return rgb
    return _reduce(rgb, width, height, 1.0)


def _reduce(rgb: np.ndarray, tw: int, th: int, slack: float) -> np.ndarray:
    """Halvings (area) while the result stays at least ``tw`` x ``th``, then a resize to that size unless
    what is left is within ``slack`` times it per side."""
    out = _contig(rgb)
    while out.shape[1] % 2 == 0 and out.shape[0] % 2 == 0 and out.shape[1] // 2 >= tw and out.shape[0] // 2 >= th:
        out = cv2.resize(out, (out.shape[1] // 2, out.shape[0] // 2), interpolation=cv2.INTER_AREA)
    ow, oh = out.shape[1], out.shape[0]
    if ow <= tw * slack + 1e-9 and oh <= th * slack + 1e-9:
        return out
    # odd sides stop the halving early: a rest of 2x or more still needs the area average
    interp = cv2.INTER_AREA if ow >= 2 * tw or oh >= 2 * th else cv2.INTER_LINEAR
    return cv2.resize(out, (tw, th), interpolation=interp)


_SOF_MARKERS = frozenset(range(0xC0, 0xD0)) - {0xC4, 0xC8, 0xCC}  # DHT, JPG and DAC are no frame headers


def jpeg_size(data: bytes) -> tuple[int, int] | None:
    """(width, height) from a JPEG's frame header (its SOF segment), or None if none is found before the
    image data starts. Reads the segment headers only: a few dozen bytes of Python per image."""
    i, n = 2, len(data)
    while i + 4 <= n:
        if data[i] != 0xFF:
            return None
        marker = data[i + 1]
        if marker == 0xFF:  # fill byte
            i += 1
            continue
        if marker == 0x01 or 0xD0 <= marker <= 0xD8:  # segments without a length
            i += 2
            continue
        if marker in _SOF_MARKERS:
            if i + 9 > n:
                return None
            height = int.from_bytes(data[i + 5:i + 7], "big")
            width = int.from_bytes(data[i + 7:i + 9], "big")
            return (width, height) if width and height else None
        length = int.from_bytes(data[i + 2:i + 4], "big")
        if marker == 0xDA or length < 2:  # start of scan (or garbage) before any frame header
            return None
        i += 2 + length
    return None


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


def decode_image(msg: dict[str, Any], depth_range: tuple[float, float] | None = None,
                 display: Display = None) -> np.ndarray:
    """A ``sensor_msgs/Image`` dict -> RGB pixels, no bigger than ``display`` needs (the source size is the
    message's ``width`` x ``height``)."""
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
    scale = paint_scale(width, height, display)
    if enc in _SHRINK_FIRST:
        pix = shrink(pix, scale)
        return _convert(pix, enc, depth_range)
    return shrink(_convert(pix, enc, depth_range), scale)


def _convert(pix: np.ndarray, enc: str, depth_range: tuple[float, float] | None) -> np.ndarray:
    """Raw pixels of encoding ``enc`` (lower case) -> RGB."""
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


def decode_compressed(msg: dict[str, Any], depth_range: tuple[float, float] | None = None,
                      display: Display = None) -> np.ndarray:
    """A ``sensor_msgs/CompressedImage`` dict (jpeg or png, incl. ``compressedDepth``) -> RGB pixels, no
    bigger than ``display`` needs."""
    return decode_compressed_sized(msg, depth_range, display).rgb


def decode_compressed_sized(msg: dict[str, Any], depth_range: tuple[float, float] | None = None,
                            display: Display = None) -> Decoded:
    """:func:`decode_compressed` with the size of the source picture (a reduced JPEG decode does not show it)."""
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
        return _decode_jpeg(buf, data, fmt, display)
    img = cv2.imdecode(buf, cv2.IMREAD_UNCHANGED)
    if img is None:
        kind = "PNG" if data.startswith(_PNG_SIGNATURE) else ("JPEG" if looks_jpeg else fmt or "unknown")
        raise DecodeError(f"could not decode the {kind} image ({len(data)} bytes; format {fmt!r})")
    height, width = img.shape[:2]
    scale = paint_scale(width, height, display)
    if img.ndim == 2:
        if img.dtype != np.uint8 or "16uc1" in fmt or "32fc1" in fmt:
            lo, hi = depth_range if depth_range else (None, None)
            return Decoded(shrink(depth_to_rgb(img, lo, hi), scale), width, height)
        return Decoded(cv2.cvtColor(shrink(img, scale), cv2.COLOR_GRAY2RGB), width, height)
    if img.dtype != np.uint8:
        img = (img.astype(np.uint16) >> 8).astype(np.uint8)
    img = shrink(img, scale)
    code = cv2.COLOR_BGRA2RGB if img.shape[2] == 4 else cv2.COLOR_BGR2RGB
    return Decoded(cv2.cvtColor(img, code), width, height)


def _decode_jpeg(buf: np.ndarray, data: bytes, fmt: str, display: Display) -> Decoded:
    """A JPEG at the largest reduction (1, 1/2, 1/4, 1/8) still at least as big as it is painted."""
    size = jpeg_size(data) if display else None
    reduce = 1
    if size is not None:
        # a JPEG turned by its EXIF orientation swaps its sides: take the larger of both fits (never too small)
        scale = max(paint_scale(size[0], size[1], display), paint_scale(size[1], size[0], display))
        reduce = next((r for r in (8, 4, 2) if r * scale <= 1.0 + 1e-9), 1)
    img = cv2.imdecode(buf, _JPEG_READ[reduce])
    if img is None:
        raise DecodeError(f"could not decode the JPEG image ({len(data)} bytes; format {fmt!r})")
    h, w = img.shape[:2]
    if size is None:
        width, height = w, h
    else:
        width, height = size
        if (w, h) != (math.ceil(width / reduce), math.ceil(height / reduce)):
            width, height = height, width  # turned by its EXIF orientation
    return Decoded(shrink(img, paint_scale(width, height, display) * width / w), width, height)
