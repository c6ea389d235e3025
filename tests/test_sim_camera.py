"""The camera renderer draws the same picture as the first, straightforward algorithm (a per-pixel choice
of sky, shore and water over the whole frame), for poses with roll, pitch, the shore near and buoys in view."""

from __future__ import annotations

import math
from types import SimpleNamespace

import cv2
import numpy as np
import pytest

from rcon_core.sim.camera import SHORE_HEIGHT, SHORE_Y, CameraRenderer
from rcon_core.sim.world import BUOYS


class ReferenceRenderer(CameraRenderer):
    """The renderer with its background drawn the original way: ``np.where`` over every pixel."""

    def _scene(self, vessel, heading, out):  # type: ignore[no-untyped-def]
        w, h, f = self.width, self.height, self.focal
        sign = 1.0 if self.yaw_offset == 0.0 else -1.0
        pitch = vessel.pitch * sign
        roll = vessel.roll * sign
        cols = np.arange(w, dtype=np.float64)
        rows = np.arange(h, dtype=np.float64)[:, None]
        horizon = h / 2 + f * math.tan(pitch) + (cols - w / 2) * math.tan(roll)
        below = rows >= horizon[None, :]
        sky, water = self._sky[:, :1, :], self._water[:, :1, :]  # the per-row gradients
        img = np.where(below[:, :, None], water, sky).astype(np.uint8)
        theta = heading + np.arctan((w / 2 - cols) / f)
        s = np.sin(theta)
        with np.errstate(divide="ignore", invalid="ignore"):
            dist = np.where(s > 1e-3, (SHORE_Y - vessel.y) / s, np.inf)
        dist = np.where(dist > 0.5, dist, np.inf)
        band = np.where(np.isfinite(dist), np.clip(f * SHORE_HEIGHT / np.maximum(dist, 1.0), 0, h), 0.0)
        shore = (rows >= (horizon - band)[None, :]) & ~below & (band[None, :] > 0.5)
        img[shore] = (70, 85, 70)
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
        out[:] = img


def pose(x=0.0, y=0.0, yaw_deg=30.0, roll=0.0, pitch=0.0, lights=False, surge=0.0):  # type: ignore[no-untyped-def]
    """What the renderer reads of a vessel, with any roll and pitch (the model's own stay small)."""
    return SimpleNamespace(x=x, y=y, yaw=math.radians(yaw_deg), roll=roll, pitch=pitch, lights=lights, surge=surge)


POSES = {
    "level, buoys ahead": pose(yaw_deg=10.0),
    "rolled and pitched, buoys ahead": pose(yaw_deg=5.0, roll=0.25, pitch=0.08, lights=True, surge=1.2),
    "rolled the other way, pitched down": pose(x=4.0, y=-2.0, yaw_deg=-20.0, roll=-0.3, pitch=-0.12),
    "near the shore, looking at it": pose(x=3.0, y=33.0, yaw_deg=80.0, roll=0.05, pitch=0.02),
    "on the shore line, along it": pose(x=0.0, y=39.8, yaw_deg=170.0, roll=-0.1),
    "horizon below the frame": pose(yaw_deg=60.0, pitch=0.9),
    "horizon above the frame": pose(yaw_deg=60.0, pitch=-0.9, roll=0.2),
    "among the buoys at night": pose(x=20.0, y=3.0, yaw_deg=0.0, roll=0.04, pitch=-0.03, lights=True),
}


@pytest.mark.parametrize("name", list(POSES))
@pytest.mark.parametrize("rear", [False, True], ids=["front", "rear"])
def test_frame_equals_the_per_pixel_algorithm(name: str, rear: bool) -> None:
    kwargs = dict(yaw_offset=math.pi) if rear else dict(bow=((200, 40, 40), "BOAT 2"), vessel_name="boat2")
    new = CameraRenderer("rear" if rear else "front", sky=((110, 160, 215), (190, 220, 240)), **kwargs)
    ref = ReferenceRenderer("rear" if rear else "front", sky=((110, 160, 215), (190, 220, 240)), **kwargs)
    v = POSES[name]
    got = new.frame(v, stamp=1_700_000_000.3)
    want = ref.frame(v, stamp=1_700_000_000.3)
    assert got.shape == want.shape == (480, 640, 3) and got.dtype == want.dtype == np.uint8
    diff = np.argwhere(got != want)
    assert diff.size == 0, f"{len(diff)} values differ, first at {diff[:3].tolist()}"


def test_the_poses_show_what_they_claim() -> None:
    """The comparison above covers a tilted horizon, a tall shore band, buoys in view and no horizon at all."""
    cam = CameraRenderer("front")

    def water(img: np.ndarray) -> np.ndarray:  # the water gradient runs from (60,110,140) to (20,55,80)
        return (img[:, :, 0] <= 60) & (img[:, :, 2] >= 80) & (img[:, :, 2] <= 140)

    def first_water_row(img: np.ndarray, col: int) -> int:
        return int(np.argmax(water(img)[:, col]))

    def shore_rows(img: np.ndarray) -> int:
        return int(np.all(img == np.array([70, 85, 70], dtype=np.uint8), axis=2).any(axis=1).sum())

    level = cam.frame(POSES["level, buoys ahead"], stamp=0.0)
    tilted = cam.frame(POSES["rolled and pitched, buoys ahead"], stamp=0.0)
    assert abs(first_water_row(level, 20) - first_water_row(level, 620)) <= 1
    assert abs(first_water_row(tilted, 20) - first_water_row(tilted, 620)) > 100
    assert shore_rows(cam.frame(POSES["near the shore, looking at it"], stamp=0.0)) > 100
    assert np.all(level == np.array([220, 40, 30], dtype=np.uint8), axis=2).sum() > 10  # a red buoy
    assert not water(cam.frame(POSES["horizon below the frame"], stamp=0.0)).any()
    assert water(cam.frame(POSES["horizon above the frame"], stamp=0.0))[:400].all()
