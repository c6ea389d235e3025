"""Scale bar and lat/lon grid spacing: "nice" round numbers for what the view shows. Pure Python."""

from __future__ import annotations

import math

_STEPS = (1.0, 2.0, 5.0)
#: grid spacings in degrees, from 1 arc-second-ish upward, all "round" to a person reading them
_DEGREE_STEPS = (
    0.00001, 0.00002, 0.00005, 0.0001, 0.0002, 0.0005, 0.001, 0.002, 0.005, 0.01, 0.02, 0.05,
    0.1, 0.2, 0.5, 1.0, 2.0, 5.0, 10.0, 15.0, 30.0, 45.0, 90.0,
)


def nice_length(limit: float) -> float:
    """The largest 1, 2 or 5 x 10^n that is <= ``limit`` (``limit`` > 0)."""
    if not limit > 0 or math.isinf(limit):
        raise ValueError(f"limit must be a positive finite number, got {limit!r}")
    exp = math.floor(math.log10(limit))
    best = 10.0**exp
    for s in _STEPS:
        v = s * 10.0**exp
        if v <= limit * (1 + 1e-12):
            best = v
    return best


def format_distance(metres: float) -> str:
    """``"200 m"``, ``"1 km"``, ``"50 cm"``."""
    if metres >= 1000:
        km = metres / 1000
        return f"{km:g} km"
    if metres >= 1:
        return f"{metres:g} m"
    return f"{metres * 100:g} cm"


def scale_bar(metres_per_pixel: float, max_px: float) -> tuple[float, float, str]:
    """A scale bar at most ``max_px`` long: ``(metres, pixels, label)``."""
    if not metres_per_pixel > 0:
        raise ValueError(f"metres_per_pixel must be positive, got {metres_per_pixel!r}")
    metres = nice_length(metres_per_pixel * max_px)
    return metres, metres / metres_per_pixel, format_distance(metres)


def grid_step(span_degrees: float, target_lines: int = 5) -> float:
    """A round grid spacing in degrees giving about ``target_lines`` lines over ``span_degrees``."""
    want = span_degrees / max(1, target_lines)
    for s in _DEGREE_STEPS:
        if s >= want:
            return s
    return _DEGREE_STEPS[-1]


def grid_lines(lo: float, hi: float, step: float) -> list[float]:
    """Multiples of ``step`` in [lo, hi]."""
    first = math.ceil(lo / step)
    last = math.floor(hi / step)
    if last - first > 1000:
        raise ValueError("too many grid lines; choose a larger step")
    return [round(k * step, 10) for k in range(first, last + 1)]


def format_degrees(value: float, step: float, positive: str, negative: str) -> str:
    """``43.6385°N`` with as many decimals as the grid step needs."""
    decimals = max(0, -math.floor(math.log10(step) + 1e-9)) if step < 1 else 0
    hemi = positive if value >= 0 else negative
    return f"{abs(value):.{decimals}f}°{hemi}"
