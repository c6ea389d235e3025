"""Web-Mercator maths, the viewport and the scale bar: known values and properties (hypothesis)."""

from __future__ import annotations

import math

import pytest
from hypothesis import assume, example, given, settings
from hypothesis import strategies as st
from rcon_widgets_map import mercator as m
from rcon_widgets_map import scale
from rcon_widgets_map.viewport import Viewport

lats = st.floats(min_value=-85.0, max_value=85.0, allow_nan=False)
lons = st.floats(min_value=-180.0, max_value=179.999999, allow_nan=False)
zooms = st.floats(min_value=0.0, max_value=22.0, allow_nan=False)
izooms = st.integers(min_value=0, max_value=22)


def test_known_values():
    assert m.latlon_to_world(0, 0, 0) == pytest.approx((128.0, 128.0))
    assert m.latlon_to_world(m.MAX_LAT, -180, 1) == pytest.approx((0.0, 0.0), abs=1e-6)
    # the OpenStreetMap wiki's slippy-map formula (asinh(tan(lat))), a second implementation
    for lat, lon, z in ((43.6385, -79.3790, 16), (-33.86, 151.21, 12), (51.5, -0.12, 3)):
        n = 2**z
        x = int((lon + 180) / 360 * n)
        y = int((1 - math.asinh(math.tan(math.radians(lat))) / math.pi) / 2 * n)
        assert m.tile_for(lat, lon, z) == (x, y)
    assert m.metres_per_pixel(0, 0) == pytest.approx(156543.03392, rel=1e-9)
    assert m.metres_per_pixel(60, 1) == pytest.approx(156543.03392 / 4, rel=1e-9)
    assert m.bearing_deg(0, 0, 1, 0) == pytest.approx(0.0)
    assert m.bearing_deg(0, 0, 0, 1) == pytest.approx(90.0)
    assert m.haversine_m(0, 0, 0, 1) == pytest.approx(m.EARTH_CIRCUMFERENCE_M / 360, rel=1e-12)
    assert m.tile_bounds(1, 0, 0) == pytest.approx((m.MAX_LAT, -180.0, 0.0, 0.0), abs=1e-9)


@given(lats, lons, zooms)
def test_world_roundtrip(lat, lon, zoom):
    x, y = m.latlon_to_world(lat, lon, zoom)
    assert 0 <= x <= m.world_size(zoom) and 0 <= y <= m.world_size(zoom)
    lat2, lon2 = m.world_to_latlon(x, y, zoom)
    assert lat2 == pytest.approx(lat, abs=1e-7) and lon2 == pytest.approx(lon, abs=1e-7)


@given(lats, lons, izooms)
def test_tile_holds_its_point(lat, lon, z):
    x, y = m.tile_for(lat, lon, z)
    north, west, south, east = m.tile_bounds(z, x, y)
    eps = 1e-9
    assert south - eps <= lat <= north + eps and west - eps <= lon <= east + eps


@given(izooms, st.data())
def test_tms_flip_is_an_involution(z, data):
    y = data.draw(st.integers(min_value=0, max_value=(1 << z) - 1))
    assert 0 <= m.tms_row(z, y) < (1 << z)
    assert m.tms_row(z, m.tms_row(z, y)) == y


@given(lats, lons, izooms)
def test_metres_per_pixel_matches_distances(lat, lon, z):
    # one pixel east on the map is metres_per_pixel of ground (the scale along a parallel)
    x, y = m.latlon_to_world(lat, lon, z)
    lat2, lon2 = m.world_to_latlon(x + 1, y, z)
    along_parallel = math.radians(abs(lon2 - lon)) * m.EARTH_RADIUS_M * math.cos(math.radians(lat))
    assert along_parallel == pytest.approx(m.metres_per_pixel(lat, z), rel=1e-6)
    # and each zoom level halves it
    assert m.metres_per_pixel(lat, z + 1) == pytest.approx(m.metres_per_pixel(lat, z) / 2)


@given(st.floats(-80, 80), st.floats(-170, 170), st.floats(-500, 500), st.floats(-500, 500))
def test_offset_and_distance_agree(lat, lon, east, north):
    lat2, lon2 = m.offset_m(lat, lon, east, north)
    assert m.haversine_m(lat, lon, lat2, lon2) == pytest.approx(math.hypot(east, north), rel=2e-3, abs=1e-6)
    if math.hypot(east, north) > 1:
        expected = math.degrees(math.atan2(east, north)) % 360
        diff = (m.bearing_deg(lat, lon, lat2, lon2) - expected + 180) % 360 - 180
        assert abs(diff) < 0.5


@settings(max_examples=60)
@given(st.floats(-80, 80), st.floats(-179, 179), st.floats(2, 20), st.integers(50, 1000), st.integers(50, 900),
       st.floats(0, 1), st.floats(0, 1))
def test_viewport_screen_roundtrip_and_zoom_about_a_point(lat, lon, zoom, w, h, fx, fy):
    vp = Viewport(lat, lon, zoom, w, h)
    assert vp.to_screen(lat, lon) == pytest.approx((w / 2, h / 2))
    sx, sy = fx * w, fy * h
    plat, plon = vp.to_latlon(sx, sy)
    assume(abs(plat) < m.MAX_LAT - 1e-6)  # above/below the Mercator square the latitude is clamped
    assert vp.to_screen(plat, plon) == pytest.approx((sx, sy), abs=1e-5)
    vp.zoom_at(zoom + 1.3, sx, sy)  # the point under the fingers stays under them
    assert vp.zoom == pytest.approx(min(21.0, zoom + 1.3))
    assert vp.to_screen(plat, plon) == pytest.approx((sx, sy), abs=1e-3)


@settings(max_examples=60)
@given(st.floats(-80, 80), st.floats(-170, 170), st.floats(3, 20), st.floats(-300, 300), st.floats(-300, 300))
@example(79.0, 0.0, 3.0, 0.0, 262.0)  # found once: the centre would pass the top edge (clamped, skipped)
def test_pan_moves_content_with_the_finger(lat, lon, zoom, dx, dy):
    vp = Viewport(lat, lon, zoom, 640, 480)
    px, py = 100.0, 200.0
    plat, plon = vp.to_latlon(px, py)
    assume(abs(plat) < m.MAX_LAT - 1e-6)
    # a drag that would take the centre past the Mercator square's edge is clamped there on purpose
    clat, _ = vp.to_latlon(320.0 - dx, 240.0 - dy)
    assume(abs(clat) < m.MAX_LAT - 1e-6)
    vp.pan(dx, dy)
    assert vp.to_screen(plat, plon) == pytest.approx((px + dx, py + dy), abs=1e-4)


@settings(max_examples=80)
@given(st.floats(-70, 70), st.floats(-180, 180), st.lists(st.tuples(st.floats(-3000, 3000), st.floats(-3000, 3000)),
                                                         min_size=1, max_size=6),
       st.integers(200, 900), st.integers(200, 700), st.tuples(*[st.integers(0, 60)] * 4), st.floats(12, 19))
@example(10.0, 179.99, [(0.0, 0.0), (800.0, 0.0)], 400, 300, (0, 0, 0, 0), 18.0)  # across the antimeridian
def test_fit_shows_every_point_inside_the_inset_as_close_as_it_can(lat, lon, offsets, w, h, inset, max_zoom):
    points = [m.offset_m(lat, lon, east, north) for east, north in offsets]
    vp = Viewport(0.0, 0.0, 3.0, w, h)
    vp.fit(points, inset, max_zoom=max_zoom)
    assert vp.zoom <= max_zoom
    left, top, right, bottom = inset
    xs, ys = zip(*(vp.to_screen(*p) for p in points), strict=True)
    assert min(xs) >= left - 1e-3 and max(xs) <= w - right + 1e-3, (xs, inset)
    assert min(ys) >= top - 1e-3 and max(ys) <= h - bottom + 1e-3, (ys, inset)
    # the group sits in the middle of the room the inset leaves...
    assert (min(xs) + max(xs)) / 2 == pytest.approx((left + w - right) / 2, abs=1e-3)
    assert (min(ys) + max(ys)) / 2 == pytest.approx((top + h - bottom) / 2, abs=1e-3)
    # ...and fills it one way unless the zoom is at its most (no zooming out further than it must)
    if vp.zoom < max_zoom:
        assert max(max(xs) - min(xs) - (w - left - right), max(ys) - min(ys) - (h - top - bottom)) == pytest.approx(
            0.0, abs=1e-3)
    assert all(vp.shows(*p, inset=(left - 1e-3, top - 1e-3, right - 1e-3, bottom - 1e-3)) for p in points)
    if len(set(offsets)) == 1:  # one place: centred there at the most zoom
        assert vp.zoom == max_zoom


@settings(max_examples=60)
@given(st.floats(-80, 80), st.floats(-179, 179), st.floats(1, 21), st.integers(1, 19))
def test_tiles_cover_the_screen_exactly_once(lat, lon, zoom, max_tile_zoom):
    vp = Viewport(lat, lon, zoom, 300, 200)
    tiles = vp.tiles(max_tile_zoom=max_tile_zoom)
    tz = vp.tile_zoom(max_tile_zoom)
    assert tz <= max_tile_zoom and all(t.z == tz for t in tiles)
    assert all(0 <= t.x < (1 << tz) and 0 <= t.y < (1 << tz) for t in tiles)
    # sample pixels: each on-world pixel is inside exactly one tile square
    for sx in (0.5, 150.5, 299.5):
        for sy in (0.5, 100.5, 199.5):
            inside = [t for t in tiles if t.left <= sx < t.left + t.size and t.top <= sy < t.top + t.size]
            plat, _ = vp.to_latlon(sx, sy)
            if abs(plat) < m.MAX_LAT - 1e-6:
                assert len(inside) == 1
                # and that tile is the one holding the point
                tile_lat, tile_lon = vp.to_latlon(sx, sy)
                t = inside[0]
                n, w_, s, e = m.tile_bounds(t.z, t.x, t.y)
                assert s - 1e-6 <= tile_lat <= n + 1e-6
    # nearest the centre first
    d = [(t.left + t.size / 2 - 150) ** 2 + (t.top + t.size / 2 - 100) ** 2 for t in tiles]
    assert d == sorted(d)


@given(st.floats(1e-3, 1e6))
def test_nice_lengths(limit):
    v = scale.nice_length(limit)
    assert v <= limit * (1 + 1e-9) and v > limit / 5.0001
    mant = v / 10 ** math.floor(math.log10(v) + 1e-12)
    assert round(mant, 6) in (1.0, 2.0, 5.0)


def test_scale_bar_and_labels():
    metres, px, text = scale.scale_bar(0.5, 120)
    assert (metres, px, text) == (50.0, 100.0, "50 m")
    assert scale.scale_bar(20.0, 120)[2] == "2 km"
    assert scale.scale_bar(0.001, 120)[2] == "10 cm"
    with pytest.raises(ValueError, match="positive"):
        scale.scale_bar(0, 100)
    assert scale.grid_lines(0.05, 0.31, 0.1) == [0.1, 0.2, 0.3]
    assert scale.format_degrees(43.6385, 0.001, "N", "S") == "43.639°N"
    assert scale.format_degrees(-79.5, 0.5, "E", "W") == "79.5°W"
