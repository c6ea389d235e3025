"""The harbour around the vessel: buoys and a pier in world coordinates, water depth, lidar, map."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Buoy:
    x: float
    y: float
    radius: float
    color: tuple[int, int, int]  # RGB
    name: str


#: channel markers and a few other objects, metres in the local ENU frame
BUOYS: tuple[Buoy, ...] = (
    Buoy(12.0, 6.0, 0.4, (220, 40, 30), "red-1"),
    Buoy(14.0, -4.0, 0.4, (40, 170, 60), "green-1"),
    Buoy(28.0, 10.0, 0.4, (220, 40, 30), "red-2"),
    Buoy(30.0, 0.0, 0.4, (40, 170, 60), "green-2"),
    Buoy(-10.0, 15.0, 0.6, (250, 200, 20), "yellow-swim"),
    Buoy(5.0, -18.0, 0.5, (250, 120, 20), "orange-mooring"),
    Buoy(-20.0, -8.0, 1.5, (90, 90, 95), "rock"),
    Buoy(45.0, 25.0, 2.5, (120, 100, 80), "breakwater-end"),
)
#: the pier: wall segments (x1, y1, x2, y2)
WALLS: tuple[tuple[float, float, float, float], ...] = (
    (-6.0, -3.0, -6.0, 3.0),
    (-6.0, 3.0, -3.0, 3.0),
    (-6.0, -3.0, -3.0, -3.0),
    (-40.0, 40.0, 60.0, 40.0),  # the shore to the north
)


def depth_at(x: float, y: float) -> float:
    """Water depth in metres: shallow near the shore (y = 40) and the pier, deeper in the channel."""
    base = 2.0 + 6.0 * (1.0 - math.exp(-max(0.0, 40.0 - y) / 25.0))
    return max(0.4, base + 0.8 * math.sin(x / 9.0) * math.cos(y / 13.0))


class Lidar:
    """A planar 2D lidar: ranges to the buoys' circles and the walls, +inf beyond ``range_max``."""

    def __init__(self, rays: int = 360, range_min: float = 0.2, range_max: float = 30.0) -> None:
        self.rays = rays
        self.range_min = range_min
        self.range_max = range_max
        self.angle_min = -math.pi
        self.angle_increment = 2 * math.pi / rays
        self.angle_max = self.angle_min + self.angle_increment * (rays - 1)
        self._angles = self.angle_min + self.angle_increment * np.arange(rays)
        bx = np.array([b.x for b in BUOYS])
        by = np.array([b.y for b in BUOYS])
        br = np.array([b.radius for b in BUOYS])
        self._buoys = (bx, by, br)
        self._walls = np.array(WALLS, dtype=np.float64)

    def scan(self, x: float, y: float, yaw: float) -> np.ndarray:
        """float32 ranges for a sensor at (x, y) facing ``yaw``."""
        theta = self._angles + yaw
        dx, dy = np.cos(theta), np.sin(theta)
        best = np.full(self.rays, np.inf)
        bx, by, br = self._buoys
        ox, oy = bx - x, by - y  # (B,)
        proj = dx[:, None] * ox[None, :] + dy[:, None] * oy[None, :]  # (R, B)
        dist2 = (ox**2 + oy**2)[None, :] - proj**2
        disc = (br**2)[None, :] - dist2
        hit = (disc >= 0) & (proj > 0)
        t = np.where(hit, proj - np.sqrt(np.clip(disc, 0, None)), np.inf)
        best = np.minimum(best, t.min(axis=1))
        w = self._walls
        ex, ey = w[:, 2] - w[:, 0], w[:, 3] - w[:, 1]  # (W,)
        sx, sy = w[:, 0] - x, w[:, 1] - y
        denom = dx[:, None] * ey[None, :] - dy[:, None] * ex[None, :]  # (R, W)
        with np.errstate(divide="ignore", invalid="ignore"):
            tr = (sx[None, :] * ey[None, :] - sy[None, :] * ex[None, :]) / denom
            us = (sx[None, :] * dy[:, None] - sy[None, :] * dx[:, None]) / denom
        ok = (np.abs(denom) > 1e-9) & (tr > 0) & (us >= 0) & (us <= 1)
        best = np.minimum(best, np.where(ok, tr, np.inf).min(axis=1))
        best[(best > self.range_max) | (best < self.range_min)] = np.inf
        return best.astype(np.float32)


def occupancy_grid(resolution: float = 0.5, size_m: float = 100.0, origin: tuple[float, float] = (-40.0, -50.0)
                   ) -> tuple[np.ndarray, int, int]:
    """int8 occupancy (0 free water, 100 obstacle or land, -1 unknown), row-major from ``origin``."""
    cells = int(round(size_m / resolution))
    xs = origin[0] + (np.arange(cells) + 0.5) * resolution
    ys = origin[1] + (np.arange(cells) + 0.5) * resolution
    gx, gy = np.meshgrid(xs, ys)
    grid = np.zeros((cells, cells), dtype=np.int8)
    for b in BUOYS:
        grid[(gx - b.x) ** 2 + (gy - b.y) ** 2 <= (b.radius + resolution / 2) ** 2] = 100
    for x1, y1, x2, y2 in WALLS:
        length = math.hypot(x2 - x1, y2 - y1)
        for s in np.linspace(0.0, 1.0, max(2, int(length / (resolution / 2)))):
            px, py = x1 + s * (x2 - x1), y1 + s * (y2 - y1)
            i, j = int((py - origin[1]) / resolution), int((px - origin[0]) / resolution)
            if 0 <= i < cells and 0 <= j < cells:
                grid[i, j] = 100
    grid[gy > 40.0 + resolution] = 100  # land beyond the shore
    grid[(gy > 44.0) & (((gx * 7 + gy * 3).astype(int) % 5) == 0)] = -1  # unsurveyed patches inland
    return grid.reshape(-1), cells, cells
