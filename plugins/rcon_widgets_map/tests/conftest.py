"""Fixtures of the map widget's tests: generated PNG tiles and a small MBTiles file around the sim."""

from __future__ import annotations

import colorsys

import cv2
import numpy as np
import pytest
from rcon_widgets_map import mercator
from rcon_widgets_map.mbtiles import write_mbtiles

from rcon_core.sim import Vessel

SIM_LAT, SIM_LON = Vessel().origin_lat, Vessel().origin_lon
MAX_TEST_ZOOM = 4


def tile_colour(z: int, x: int, y: int) -> tuple[int, int, int]:
    """A distinct saturated RGB colour per tile (neighbours differ a lot)."""
    hue = ((x * 0.37 + y * 0.61 + z * 0.13) % 1.0)
    r, g, b = colorsys.hsv_to_rgb(hue, 0.75, 0.9)
    return int(r * 255), int(g * 255), int(b * 255)


def tile_png(z: int, x: int, y: int, rgb: tuple[int, int, int] | None = None) -> bytes:
    """A 256x256 PNG: a flat colour square with a dark border and its ``z/x/y`` written in the middle."""
    r, g, b = rgb or tile_colour(z, x, y)
    img = np.zeros((256, 256, 3), np.uint8)
    img[:] = (b, g, r)
    cv2.rectangle(img, (0, 0), (255, 255), (40, 40, 40), 2)
    text = f"{z}/{x}/{y}"
    (tw, th), _ = cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, 0.8, 2)
    cv2.putText(img, text, ((256 - tw) // 2, (256 + th) // 2), cv2.FONT_HERSHEY_SIMPLEX, 0.8, (20, 20, 20), 2)
    ok, buf = cv2.imencode(".png", img)
    assert ok
    return buf.tobytes()


def tiles_around(lat: float, lon: float, zooms: range, radius: int = 1):
    """``(z, x, y, png)`` for the tiles within ``radius`` of the point at each zoom."""
    for z in zooms:
        cx, cy = mercator.tile_for(lat, lon, z)
        n = 1 << z
        for y in range(max(0, cy - radius), min(n, cy + radius + 1)):
            for x in range(max(0, cx - radius), min(n, cx + radius + 1)):
                yield z, x, y, tile_png(z, x, y)


@pytest.fixture(scope="session")
def mbtiles_file(tmp_path_factory):
    """An MBTiles file with tiles of zoom 0-4 around the sim's position (3x3 per zoom)."""
    path = tmp_path_factory.mktemp("tiles") / "harbour.mbtiles"
    write_mbtiles(path, tiles_around(SIM_LAT, SIM_LON, range(0, MAX_TEST_ZOOM + 1)),
                  {"name": "test harbour", "center": f"{SIM_LON},{SIM_LAT},3"})
    return path


@pytest.fixture(scope="session")
def colour_of():
    return tile_colour


@pytest.fixture(scope="session")
def make_tile_png():
    return tile_png
