"""Draw a ``sensor_msgs/LaserScan`` top-down and a ``nav_msgs/OccupancyGrid`` as RGB pixels (no Qt).

Scan: the sensor sits in the middle looking up (x forward = up, y left = left), with range rings at a
round spacing labelled in metres. Readings that are NaN/None (no return), below ``range_min`` or above
``range_max`` (out of range, also +inf) are not drawn as obstacles; the counts are returned so the view
can say how many there were.
"""

from __future__ import annotations

import math
from typing import Any

import attrs
import cv2
import numpy as np

from .decode import DecodeError

__all__ = ["ScanCounts", "render_scan", "render_grid", "ring_step"]

BACKGROUND = (18, 22, 28)
RING = (60, 70, 84)
LABEL = (140, 150, 165)
HIT = (90, 230, 140)
BEAM = (40, 70, 55)
SENSOR = (240, 200, 80)


@attrs.frozen
class ScanCounts:
    valid: int = 0
    out_of_range: int = 0  # below range_min, above range_max, or +inf
    invalid: int = 0  # NaN / null: no reading


def ring_step(extent: float) -> float:
    """A round ring spacing (1, 2 or 5 x 10^k m) giving about four rings up to ``extent``."""
    if not extent > 0:
        return 1.0
    raw = extent / 4
    mag = 10 ** math.floor(math.log10(raw))
    for m in (1, 2, 5, 10):
        if m * mag >= raw:
            return m * mag
    return 10 * mag


def _ranges(values: Any) -> np.ndarray:
    if isinstance(values, np.ndarray):
        return values.astype(np.float64, copy=False)
    if values is None:
        return np.zeros(0)
    return np.array([math.nan if v is None else v for v in values], dtype=np.float64)


def _num(msg: dict[str, Any], key: str) -> float:
    v = msg.get(key)
    if v is None:
        raise DecodeError(f"laser scan field {key!r} is missing or not a number")
    return float(v)


def render_scan(msg: dict[str, Any], size: int = 480, max_range: float | None = None) -> tuple[np.ndarray, ScanCounts]:
    """Pixels (``size`` x ``size``) and reading counts for a LaserScan dict.

    ``max_range``: metres from the centre to the edge; default: the scan's ``range_max`` (or the farthest
    valid reading when ``range_max`` is not usable).
    """
    a0, inc = _num(msg, "angle_min"), _num(msg, "angle_increment")
    rmin = float(msg.get("range_min") or 0.0)
    rmax = msg.get("range_max")
    rmax = float(rmax) if rmax is not None and math.isfinite(float(rmax)) and float(rmax) > 0 else math.inf
    r = _ranges(msg.get("ranges"))
    n = r.size
    nan = np.isnan(r)
    out = ~nan & ((r < rmin) | (r > rmax) | np.isinf(r))
    ok = ~nan & ~out
    counts = ScanCounts(valid=int(ok.sum()), out_of_range=int(out.sum()), invalid=int(nan.sum()))
    extent = max_range or (rmax if math.isfinite(rmax) else (float(r[ok].max()) if ok.any() else 10.0))
    extent = max(extent, 1e-3)
    img = np.empty((size, size, 3), np.uint8)
    img[:] = BACKGROUND
    c = size / 2
    scale = (size / 2 - 4) / extent  # pixels per metre
    step = ring_step(extent)
    k = 1
    while k * step <= extent * 1.0001:
        rad = int(round(k * step * scale))
        cv2.circle(img, (int(c), int(c)), rad, RING, 1, cv2.LINE_AA)
        text = f"{k * step:g} m"
        cv2.putText(img, text, (int(c) + 3, int(c - rad) + 12), cv2.FONT_HERSHEY_SIMPLEX, max(0.35, size / 1100), LABEL, 1,
                    cv2.LINE_AA)
        k += 1
    cv2.line(img, (int(c), 0), (int(c), size), RING, 1)
    cv2.line(img, (0, int(c)), (size, int(c)), RING, 1)
    if n:
        ang = a0 + inc * np.arange(n)
        rr = np.where(ok, r, 0.0)
        # x forward -> up; y left -> left
        px = c - np.sin(ang) * rr * scale
        py = c - np.cos(ang) * rr * scale
        pts = np.stack([px, py], axis=1)
        # the swept area: a triangle from the sensor between each two neighbouring returns
        pair = ok[:-1] & ok[1:]
        if pair.any():
            idx = np.nonzero(pair)[0]
            centre = np.full((idx.size, 1, 2), c)
            tris = np.concatenate([centre, pts[idx][:, None, :], pts[idx + 1][:, None, :]], axis=1)
            cv2.fillPoly(img, list(np.round(tris).astype(np.int32)), BEAM)
        hits = pts[ok]
        inside = (hits[:, 0] >= 0) & (hits[:, 0] < size) & (hits[:, 1] >= 0) & (hits[:, 1] < size)
        for x, y in hits[inside].astype(np.int32):
            cv2.circle(img, (int(x), int(y)), 2, HIT, -1, cv2.LINE_AA)
    cv2.drawMarker(img, (int(c), int(c)), SENSOR, cv2.MARKER_TRIANGLE_UP, 10, 2, cv2.LINE_AA)
    return img, counts


def render_grid(msg: dict[str, Any]) -> np.ndarray:
    """An OccupancyGrid dict -> RGB pixels, north up: unknown grey, free white, occupied black
    (in between: shades by probability)."""
    info = msg.get("info") or {}
    try:
        w, h = int(info["width"]), int(info["height"])
    except (KeyError, TypeError, ValueError):
        raise DecodeError("occupancy grid without info.width/height") from None
    data = msg.get("data")
    if isinstance(data, bytes | bytearray):
        cells = np.frombuffer(bytes(data), np.int8).astype(np.int16)
    else:
        cells = np.asarray(data if data is not None else [], dtype=np.int16)
    if w <= 0 or h <= 0:
        raise DecodeError(f"empty occupancy grid ({w}x{h})")
    if cells.size != w * h:
        raise DecodeError(f"occupancy grid has {cells.size} cells, expected width x height = {w * h}")
    grid = cells.reshape(h, w)
    shade = (255 - np.clip(grid, 0, 100) * 255 // 100).astype(np.uint8)
    rgb = np.repeat(shade[:, :, None], 3, axis=2)
    unknown = (grid < 0) | (grid > 100)
    rgb[unknown] = (128, 134, 145)
    return np.ascontiguousarray(rgb[::-1])  # row 0 is the map origin (south): flip so north is up
