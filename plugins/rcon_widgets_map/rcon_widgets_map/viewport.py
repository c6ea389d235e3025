"""What part of the world a map view shows: centre, fractional zoom, size in pixels. Pure Python.

The view keeps one :class:`Viewport` and asks it to convert between screen pixels and lat/lon, to pan,
to zoom about a point (mouse wheel, pinch), to show several points at once (:meth:`Viewport.fit`) and
which tiles cover the screen.
"""

from __future__ import annotations

import math

import attrs

from . import mercator as m

MIN_ZOOM = 1.0
MAX_VIEW_ZOOM = 21.0


@attrs.frozen
class TilePlacement:
    """A tile to draw: XYZ key (``x`` already wrapped) and its square on screen (``left``, ``top``, ``size``)."""

    z: int
    x: int
    y: int
    left: float
    top: float
    size: float


@attrs.define
class Viewport:
    """Centre (degrees), zoom (fractional) and pixel size of the view."""

    lat: float = 0.0
    lon: float = 0.0
    zoom: float = 2.0
    width: int = 256
    height: int = 256
    min_zoom: float = MIN_ZOOM
    max_zoom: float = MAX_VIEW_ZOOM

    def __attrs_post_init__(self) -> None:
        self.zoom = self._clamp_zoom(self.zoom)
        self.lat = m.clamp_lat(self.lat)

    def _clamp_zoom(self, zoom: float) -> float:
        return max(self.min_zoom, min(self.max_zoom, zoom))

    # -- conversions ---------------------------------------------------------------------------------
    def _centre_world(self) -> tuple[float, float]:
        return m.latlon_to_world(self.lat, self.lon, self.zoom)

    def to_screen(self, lat: float, lon: float) -> tuple[float, float]:
        """Screen pixel of a point (may lie outside the view); across the antimeridian, the copy of the
        point nearest the centre."""
        cx, cy = self._centre_world()
        x, y = m.latlon_to_world(lat, lon, self.zoom)
        size = m.world_size(self.zoom)
        dx = (x - cx + size / 2.0) % size - size / 2.0
        return dx + self.width / 2.0, y - cy + self.height / 2.0

    def to_latlon(self, sx: float, sy: float) -> tuple[float, float]:
        """Lat/lon under a screen pixel; longitude wrapped to [-180, 180)."""
        cx, cy = self._centre_world()
        lat, lon = m.world_to_latlon(cx + sx - self.width / 2.0, cy + sy - self.height / 2.0, self.zoom)
        return m.clamp_lat(lat), (lon + 180.0) % 360.0 - 180.0

    def metres_per_pixel(self) -> float:
        return m.metres_per_pixel(self.lat, self.zoom)

    # -- moving ------------------------------------------------------------------------------------
    def centre_on(self, lat: float, lon: float) -> None:
        self.lat, self.lon = m.clamp_lat(lat), lon

    def pan(self, dx: float, dy: float) -> None:
        """Move the map content by ``dx``, ``dy`` screen pixels (a drag)."""
        self.lat, self.lon = self.to_latlon(self.width / 2.0 - dx, self.height / 2.0 - dy)

    def zoom_at(self, zoom: float, sx: float | None = None, sy: float | None = None) -> None:
        """Set the zoom keeping the point under screen pixel (``sx``, ``sy``) where it is (default: centre)."""
        zoom = self._clamp_zoom(zoom)
        if sx is None or sy is None:
            self.zoom = zoom
            return
        lat, lon = self.to_latlon(sx, sy)
        self.zoom = zoom
        px, py = self.to_screen(lat, lon)
        self.pan(sx - px, sy - py)

    def fit(self, points: list[tuple[float, float]], inset: tuple[float, float, float, float],
            max_zoom: float) -> None:
        """Centre and zoom so every ``(lat, lon)`` of ``points`` lies inside the screen less ``inset``
        (left, top, right, bottom pixels), at ``max_zoom`` at most (one point: centred there at ``max_zoom``).
        Longitudes are taken nearest the first point's, so a group across the antimeridian stays together."""
        if not points:
            return
        left, top, right, bottom = inset
        lon0 = points[0][1]
        # world pixels at zoom 0 (256 across the world); longitudes unwrapped about the first point's
        xy = [m.latlon_to_world(lat, lon0 + (lon - lon0 + 180.0) % 360.0 - 180.0, 0.0) for lat, lon in points]
        x0, x1 = min(x for x, _ in xy), max(x for x, _ in xy)
        y0, y1 = min(y for _, y in xy), max(y for _, y in xy)
        room_w, room_h = max(1.0, self.width - left - right), max(1.0, self.height - top - bottom)
        zoom = max_zoom
        if x1 > x0:
            zoom = min(zoom, math.log2(room_w / (x1 - x0)))
        if y1 > y0:
            zoom = min(zoom, math.log2(room_h / (y1 - y0)))
        self.zoom = self._clamp_zoom(zoom)
        lat, lon = m.world_to_latlon((x0 + x1) / 2.0, (y0 + y1) / 2.0, 0.0)
        self.centre_on(lat, (lon + 180.0) % 360.0 - 180.0)
        # the group's middle goes to the middle of the room the inset leaves (not of the whole screen)
        self.pan((left - right) / 2.0, (top - bottom) / 2.0)

    def shows(self, lat: float, lon: float, inset: tuple[float, float, float, float] = (0, 0, 0, 0)) -> bool:
        """Whether the point lies on screen, inside ``inset`` (left, top, right, bottom pixels) from the edges."""
        x, y = self.to_screen(lat, lon)
        left, top, right, bottom = inset
        return left <= x <= self.width - right and top <= y <= self.height - bottom

    # -- tiles -------------------------------------------------------------------------------------
    def tile_zoom(self, max_tile_zoom: int = m.MAX_ZOOM, min_tile_zoom: int = 0) -> int:
        """The tile level to draw: the nearest integer zoom, limited to what the source has."""
        return int(max(min_tile_zoom, min(max_tile_zoom, math.floor(self.zoom + 0.5))))

    def tiles(self, max_tile_zoom: int = m.MAX_ZOOM, min_tile_zoom: int = 0) -> list[TilePlacement]:
        """Tiles covering the screen at :meth:`tile_zoom`, nearest the centre first."""
        tz = self.tile_zoom(max_tile_zoom, min_tile_zoom)
        scale = 2.0 ** (self.zoom - tz)
        size = m.TILE_SIZE * scale
        cx, cy = self._centre_world()
        left_world = cx - self.width / 2.0
        top_world = cy - self.height / 2.0
        n = 1 << tz
        x0 = math.floor(left_world / size)
        x1 = math.floor((left_world + self.width) / size)
        y0 = max(0, math.floor(top_world / size))
        y1 = min(n - 1, math.floor((top_world + self.height) / size))
        out = []
        for ty in range(y0, y1 + 1):
            for tx in range(x0, x1 + 1):
                out.append(TilePlacement(tz, tx % n, ty, tx * size - left_world, ty * size - top_world, size))
        mid_x, mid_y = self.width / 2.0, self.height / 2.0
        out.sort(key=lambda t: (t.left + t.size / 2 - mid_x) ** 2 + (t.top + t.size / 2 - mid_y) ** 2)
        return out
