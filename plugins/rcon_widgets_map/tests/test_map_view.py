"""The map view offscreen: offline tiles really painted (pixel colours), the grid fallback, markers,
gestures (drag, wheel, pinch, follow) and the tap -> confirm -> publish path against the sim."""

from __future__ import annotations

import pytest
from map_helpers import make_view
from qtpy import QtCore, QtGui
from rcon_widgets_map import mercator
from rcon_widgets_map.model import MapModel
from rcon_widgets_map.settings import MapPluginSettings, MapSettings

from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import Binding
from rcon_core.sim import Vessel
from rcon_core.testing import flushed_sync

TYPES = TypeRegistry.standard()
Qt = QtCore.Qt
SIM_LAT, SIM_LON = Vessel().origin_lat, Vessel().origin_lon
MAX_TEST_ZOOM = 4  # the deepest zoom of the conftest's MBTiles file


def fix(lat, lon, status=0):
    msg = TYPES.default("sensor_msgs/NavSatFix")
    msg.update(latitude=lat, longitude=lon, position_covariance=[4.0, 0, 0, 0, 4.0, 0, 0, 0, 9.0],
               position_covariance_type=2)
    msg["status"]["status"] = status
    return msg


def offline_model(**settings):
    m = MapModel(MapSettings(**settings), Binding("", "sensor_msgs/NavSatFix", "subscribe"), port=None,
                 types=TYPES, plugin_settings=MapPluginSettings())
    m.start()
    return m


def rgb(img: QtGui.QImage, x: float, y: float) -> tuple[int, int, int]:
    c = img.pixelColor(int(x), int(y))
    return c.red(), c.green(), c.blue()


def close(a, b, tol=4):
    return all(abs(p - q) <= tol for p, q in zip(a, b, strict=True))


def wait_tiles(qtbot, view, count):
    def painted():
        view.repaint()
        return view.tiles_drawn >= count
    qtbot.waitUntil(painted, timeout=10_000)


def plain_spot(view, t) -> tuple[float, float] | None:
    """A screen point well inside tile placement ``t``, away from its border, its label and the overlays."""
    for fx, fy in ((0.15, 0.15), (0.85, 0.2), (0.2, 0.85), (0.8, 0.8)):
        x, y = t.left + fx * t.size, t.top + fy * t.size
        if 60 < x < view.width() - 60 and 60 < y < view.height() - 60 and abs(y - view.height() / 2) > 25:
            return x, y
    return None


def test_offline_tiles_are_painted(qtbot, mbtiles_file, colour_of):
    model = offline_model(mbtiles_path=str(mbtiles_file), zoom=4)
    view = make_view(qtbot, model, size=(700, 560))
    assert view.loader is not None and view.loader.ready.wait(5)
    # no fix yet: the view shows the file's centre (from its metadata)
    qtbot.waitUntil(lambda: (view.viewport.lat, view.viewport.lon) == pytest.approx((SIM_LAT, SIM_LON)))
    placements = view.viewport.tiles(max_tile_zoom=view.loader.max_zoom)
    wait_tiles(qtbot, view, len(placements))
    img = view.grab().toImage()
    checked = 0
    for t in placements:
        spot = plain_spot(view, t)
        if spot is None:
            continue
        assert close(rgb(img, *spot), colour_of(t.z, t.x, t.y)), (t, spot)
        checked += 1
    assert checked >= 4
    view.close_loader()


def test_overzoom_scales_the_deepest_tile(qtbot, mbtiles_file, colour_of):
    # the file stops at zoom 4; at zoom 6.5 the zoom-4 tile under each point is drawn, magnified
    model = offline_model(mbtiles_path=str(mbtiles_file), zoom=6.5)
    model.on_message(fix(SIM_LAT, SIM_LON))
    view = make_view(qtbot, model)
    assert view.loader.ready.wait(5)
    wait_tiles(qtbot, view, 1)
    assert view.viewport.tile_zoom(view.loader.max_zoom) == MAX_TEST_ZOOM
    img = view.grab().toImage()
    checked = 0
    for sx in range(70, view.width() - 60, 40):
        for sy in (70, 110, view.height() - 80):
            lat, lon = view.viewport.to_latlon(sx, sy)
            wx, wy = mercator.latlon_to_world(lat, lon, MAX_TEST_ZOOM)
            tx, ty = int(wx // 256), int(wy // 256)
            ox, oy = wx - tx * 256, wy - ty * 256
            if min(ox, oy, 256 - ox, 256 - oy) < 8 or (60 < ox < 196 and 100 < oy < 156):
                continue  # the tile's border or its z/x/y label
            assert close(rgb(img, sx, sy), colour_of(MAX_TEST_ZOOM, tx, ty)), (sx, sy, tx, ty)
            checked += 1
    assert checked >= 5
    view.close_loader()


def test_grid_marker_and_states_without_tiles(qtbot):
    clock = [100.0]
    model = MapModel(MapSettings(stale_after=2.0, zoom=18), Binding("", "sensor_msgs/NavSatFix", "subscribe"),
                     port=None, types=TYPES, clock=lambda: clock[0])
    model.start()
    view = make_view(qtbot, model)
    assert view.loader is None
    assert view.status_text()[0].startswith("Waiting")
    model.on_message(fix(SIM_LAT, SIM_LON))
    view.refresh(model.state)
    img = view.grab().toImage()
    cx, cy = view.width() / 2, view.height() / 2  # following: the robot is in the middle
    assert close(rgb(img, cx, cy), (0x00, 0x50, 0xD0), tol=10)  # the blue marker
    # the accuracy circle (2 m at ~0.43 m/px) is tinted around it, the background further out is not
    r_px = 2.0 / view.viewport.metres_per_pixel()
    ring = rgb(img, cx + r_px * 0.75, cy + 1)
    far = rgb(img, cx + r_px * 3, cy + 30)
    assert ring != far and ring[2] > ring[0]
    assert view.status_text() is None
    # scale bar: black pixels at the bottom left
    assert rgb(img, 14, view.height() - 12) == (0, 0, 0)
    clock[0] += 3.0
    view.refresh(model.state)
    assert view.status_text()[0].startswith("STALE")
    img = view.grab().toImage()
    assert close(rgb(img, cx, cy), (0x7A, 0x7A, 0x7A), tol=10)  # greyed out
    model.on_message(fix(None, None, status=-1))
    view.refresh(model.state)
    assert view.status_text()[0] == "NO FIX"
    img = view.grab().toImage()
    assert close(rgb(img, 14, 14), (0xC0, 0, 0), tol=10)  # the red chip


def test_drag_wheel_pinch_and_follow(qtbot):
    model = offline_model(zoom=17)
    model.on_message(fix(SIM_LAT, SIM_LON))
    view = make_view(qtbot, model)
    assert view.following
    centre = QtCore.QPoint(240, 200)
    qtbot.mousePress(view, Qt.MouseButton.LeftButton, pos=centre)
    for dx in (5, 20, 60):
        qtbot.mouseMove(view, centre + QtCore.QPoint(dx, 30))
    qtbot.mouseRelease(view, Qt.MouseButton.LeftButton, pos=centre + QtCore.QPoint(60, 30))
    assert not view.following and view.pending is None  # a drag is not a tap
    sx, sy = view.viewport.to_screen(SIM_LAT, SIM_LON)
    assert (sx, sy) == pytest.approx((300, 230), abs=1.0)  # the map moved with the finger
    model.on_message(fix(SIM_LAT + 0.001, SIM_LON))
    view.refresh(model.state)
    assert view.viewport.to_screen(SIM_LAT, SIM_LON) == pytest.approx((300, 230), abs=1.0)  # not following
    # wheel zoom about the cursor
    lat0, lon0 = view.viewport.to_latlon(100, 100)
    view.zoom_by(1.0, QtCore.QPointF(100, 100))
    assert view.viewport.zoom == 18 and view.viewport.to_screen(lat0, lon0) == pytest.approx((100, 100), abs=1e-3)
    view.pinch(0.5, QtCore.QPointF(100, 100))  # fingers closer: one level out
    assert view.viewport.zoom == pytest.approx(17)
    qtbot.mouseClick(view.follow_button, Qt.MouseButton.LeftButton)
    assert view.following
    assert view.viewport.to_screen(SIM_LAT + 0.001, SIM_LON) == pytest.approx((240, 200), abs=1.0)


def test_escape_and_cancel_send_nothing(qtbot):
    model = offline_model()
    model.on_message(fix(SIM_LAT, SIM_LON))
    view = make_view(qtbot, model)
    qtbot.mouseClick(view, Qt.MouseButton.LeftButton, pos=QtCore.QPoint(120, 150))
    assert view.bubble.isVisible() and view.pending is not None
    qtbot.mouseClick(view.bubble.cancel, Qt.MouseButton.LeftButton)
    assert not view.bubble.isVisible() and view.pending is None
    qtbot.mouseClick(view, Qt.MouseButton.LeftButton, pos=QtCore.QPoint(120, 150))
    qtbot.keyClick(view, Qt.Key.Key_Escape)
    assert view.pending is None and model.state.value.goals_sent == 0


def test_tap_confirm_publishes_to_the_robot(qtbot, sim_thread, threaded_client):
    bt, client = threaded_client
    model = MapModel(MapSettings(zoom=18), Binding("/gps/fix", "sensor_msgs/NavSatFix", "subscribe"),
                     client.node("map-view"), types=TYPES, dispatch=bt.call)
    bt.call(model.start).result(5)
    qtbot.waitUntil(lambda: model.state.count > 0, timeout=10_000)
    view = make_view(qtbot, model)
    main = model.state.value.main
    assert view.viewport.to_screen(main.lat, main.lon) == pytest.approx((240, 200), abs=1.0)
    tap = QtCore.QPoint(330, 120)
    qtbot.mouseClick(view, Qt.MouseButton.LeftButton, pos=tap)
    assert view.bubble.isVisible() and "/goal/fix" in view.bubble.label.text()
    lat, lon = view.pending
    assert (lat, lon) == pytest.approx(view.viewport.to_latlon(330, 120))
    flushed_sync(bt, client, sim_thread, qtbot=qtbot)  # a marker after the tap reached the robot...
    assert sim_thread.published("/goal/fix") == []  # ...and nothing before it: a tap alone sends nothing
    qtbot.mouseClick(view.bubble.send, Qt.MouseButton.LeftButton)
    got = sim_thread.wait_for_published_sync(
        "/goal/fix", lambda m: abs(m["latitude"] - lat) < 1e-9 and abs(m["longitude"] - lon) < 1e-9, timeout=10)
    assert got["header"]["frame_id"] == "map"
    assert not view.bubble.isVisible() and model.state.value.goals_sent == 1
    assert len(sim_thread.published("/goal/fix")) == 1
    bt.call(model.stop).result(5)
