"""Tile sources: MBTiles (TMS rows, metadata, bad files), online XYZ tiles from a local http.server with the
disk cache and the failure pause, and the loader threads with their LRU cache (decoded with OpenCV here)."""

from __future__ import annotations

import http.server
import sqlite3
import threading

import cv2
import numpy as np
import pytest
from rcon_widgets_map import mercator
from rcon_widgets_map.http_tiles import (
    HttpTileSource,
    TileAbsent,
    TileUnavailable,
    template_problems,
    tile_url,
)
from rcon_widgets_map.loader import TileLoader
from rcon_widgets_map.mbtiles import MBTilesError, MBTilesReader, write_mbtiles

from rcon_core.testing import until_sync


def decode(data: bytes):
    img = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_COLOR)
    return None if img is None else img


def rgb_at(img, x=20, y=20):
    b, g, r = img[y, x]
    return int(r), int(g), int(b)


class TileServer:
    """A tiny XYZ tile server on 127.0.0.1: PNGs for zoom <= 3, 404 above, 500s when ``failing``."""

    def __init__(self, make_png):
        self.requests: list[str] = []
        self.failing = False
        outer = self

        class Handler(http.server.BaseHTTPRequestHandler):
            def do_GET(self):  # noqa: N802 - http.server API
                outer.requests.append(self.path)
                if outer.failing:
                    self.send_error(503)
                    return
                try:
                    z, x, y = (int(p) for p in self.path.strip("/").removesuffix(".png").split("/"))
                except ValueError:
                    self.send_error(400)
                    return
                if z > 3 or not mercator.valid_tile(z, x, y):
                    self.send_error(404)
                    return
                body = make_png(z, x, y)
                self.send_response(200)
                self.send_header("Content-Type", "image/png")
                self.send_header("Content-Length", str(len(body)))
                self.end_headers()
                self.wfile.write(body)

            def log_message(self, *_a):
                pass

        self.httpd = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        self.thread = threading.Thread(target=self.httpd.serve_forever, daemon=True)
        self.thread.start()
        self.template = f"http://127.0.0.1:{self.httpd.server_address[1]}/{{z}}/{{x}}/{{y}}.png"

    def close(self):
        self.httpd.shutdown()
        self.httpd.server_close()


@pytest.fixture
def tile_server(make_tile_png):
    server = TileServer(make_tile_png)
    yield server
    server.close()


# -- MBTiles -------------------------------------------------------------------------------------------

def test_mbtiles_reads_tiles_with_tms_rows(mbtiles_file, colour_of):
    with MBTilesReader(mbtiles_file) as r:
        assert (r.min_zoom, r.max_zoom) == (0, 4)
        assert r.metadata["name"] == "test harbour"
        lat, lon, zoom = r.center
        assert zoom == 3 and lat == pytest.approx(43.6385) and lon == pytest.approx(-79.379)
        x, y = mercator.tile_for(lat, lon, 4)
        img = decode(r.tile(4, x, y))
        assert rgb_at(img) == pytest.approx(colour_of(4, x, y), abs=2)
        assert r.tile(4, 0, 0) is None  # not in the file
        assert r.tile(4, 99, 0) is None  # not in the world
    # the file really stores TMS rows (0 at the bottom), as other MBTiles tools expect
    db = sqlite3.connect(mbtiles_file)
    rows = {(z, c, row) for z, c, row in db.execute("SELECT zoom_level, tile_column, tile_row FROM tiles")}
    db.close()
    assert (4, x, mercator.tms_row(4, y)) in rows and (4, x, y) not in rows


def test_mbtiles_errors_are_specific(tmp_path):
    with pytest.raises(MBTilesError, match="does not exist"):
        MBTilesReader(tmp_path / "none.mbtiles")
    junk = tmp_path / "junk.mbtiles"
    junk.write_bytes(b"this is not sqlite at all" * 100)
    with pytest.raises(MBTilesError, match="not an SQLite file"):
        MBTilesReader(junk)
    other = tmp_path / "other.mbtiles"
    sqlite3.connect(other).execute("CREATE TABLE things (a)").connection.commit()
    with pytest.raises(MBTilesError, match="no metadata or tiles table"):
        MBTilesReader(other)
    with pytest.raises(MBTilesError, match="outside the world"):
        write_mbtiles(tmp_path / "bad.mbtiles", [(1, 2, 0, b"x")])


def test_reader_opens_read_only(mbtiles_file):
    before = (mbtiles_file.read_bytes(), mbtiles_file.stat().st_mtime_ns)
    with MBTilesReader(mbtiles_file) as r:
        assert "mode=ro" in r.uri
        assert r.tile(0, 0, 0) is not None and r.metadata["name"] == "test harbour"  # read through it
        other = sqlite3.connect(r.uri, uri=True)  # the reader's URI: SQLite refuses a write through it
        with pytest.raises(sqlite3.OperationalError, match="readonly"):
            other.execute("DELETE FROM tiles")
        other.close()
    assert (mbtiles_file.read_bytes(), mbtiles_file.stat().st_mtime_ns) == before


# -- online tiles --------------------------------------------------------------------------------------

def test_template_checks_and_urls():
    assert template_problems("https://tile.example.org/{z}/{x}/{y}.png") == []
    assert template_problems("") == []
    assert "must start with http" in template_problems("ftp://x/{z}/{x}/{y}")[0]
    assert any("{z}, {x} and {y}" in p for p in template_problems("https://t.example.org/{z}/{x}.png"))
    assert any("{q}" in p for p in template_problems("https://t.example.org/{z}/{x}/{y}/{q}"))
    assert tile_url("https://{s}.t.org/{z}/{x}/{-y}.png", 3, 1, 2) == "https://a.t.org/3/1/5.png"
    with pytest.raises(ValueError, match="must contain"):
        HttpTileSource("https://t.example.org/tiles", "/tmp")


def test_http_fetch_caches_on_disk(tile_server, tmp_path, colour_of):
    src = HttpTileSource(tile_server.template, tmp_path, timeout=5)
    data = src.fetch(2, 1, 1)
    assert rgb_at(decode(data)) == pytest.approx(colour_of(2, 1, 1), abs=2)
    assert src.cached(2, 1, 1) == data and src.cache_path(2, 1, 1).is_file()
    assert tile_server.requests == ["/2/1/1.png"]
    with pytest.raises(TileAbsent):
        src.fetch(5, 1, 1)  # 404: that tile only, no pause
    assert src.paused_for == 0
    # another source on the same template (a new view) finds the tile on disk without the network
    tile_server.close()
    again = HttpTileSource(tile_server.template, tmp_path)
    assert again.cached(2, 1, 1) == data


def test_http_failures_pause_instead_of_storming(tile_server, tmp_path):
    tile_server.failing = True
    now = [100.0]
    src = HttpTileSource(tile_server.template, tmp_path, timeout=5, first_pause=2.0, clock=lambda: now[0])
    with pytest.raises(TileUnavailable, match="HTTP 503"):
        src.fetch(1, 0, 0)
    for _ in range(50):  # a view asking for many tiles while the server is down: none reach it
        with pytest.raises(TileUnavailable, match="next try"):
            src.fetch(1, 1, 0)
    assert len(tile_server.requests) == 1
    now[0] += 2.5
    with pytest.raises(TileUnavailable, match="HTTP 503"):
        src.fetch(1, 1, 0)
    assert src.paused_for == pytest.approx(4.0)  # doubled
    tile_server.failing = False
    now[0] += 4.5
    assert src.fetch(1, 1, 0) and src.paused_for == 0  # back to normal after a success
    assert len(tile_server.requests) == 3


def test_unreachable_server_times_out_cleanly(tmp_path):
    import socket

    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()  # nothing listens there: connection refused
    src = HttpTileSource(f"http://127.0.0.1:{port}/{{z}}/{{x}}/{{y}}.png", tmp_path, timeout=2)
    with pytest.raises(TileUnavailable, match="refused|Errno"):
        src.fetch(0, 0, 0)
    assert src.paused_for > 0


# -- loader --------------------------------------------------------------------------------------------

def test_loader_serves_mbtiles_off_the_calling_thread(mbtiles_file, colour_of):
    ready_threads = []
    loader = TileLoader(decode, lambda key: ready_threads.append(threading.current_thread().name),
                        mbtiles=mbtiles_file, memory_tiles=4)
    try:
        assert loader.ready.wait(5) and loader.max_zoom == 4 and loader.error is None
        x, y = mercator.tile_for(43.6385, -79.379, 3)
        assert loader.get((3, x, y)) is None  # queued, not read on this thread
        until_sync(lambda: loader.get((3, x, y)) is not None)
        assert rgb_at(loader.get((3, x, y))) == pytest.approx(colour_of(3, x, y), abs=2)
        assert ready_threads and all(n == "map-tiles-local" for n in ready_threads)
        assert loader.get((3, 0, 0)) is None  # not in the file: absent, never retried
        until_sync(lambda: loader.is_absent((3, 0, 0)))
        # the memory cache is a bounded LRU
        x4, y4 = mercator.tile_for(43.6385, -79.379, 4)
        keys = [(4, x4 + dx, y4 + dy) for dx in (-1, 0, 1) for dy in (-1, 0, 1)]
        for k in keys:
            loader.get(k)
        until_sync(lambda: loader.loaded >= 10)
        assert loader.cached_count() == 4
        assert loader.get((3, x, y)) is None  # evicted: asked again
        until_sync(lambda: loader.get((3, x, y)) is not None)
        assert loader.loaded == 11
    finally:
        loader.close()


def test_loader_reports_a_bad_file(tmp_path):
    bad = tmp_path / "bad.mbtiles"
    bad.write_text("no")
    loader = TileLoader(decode, lambda key: None, mbtiles=bad)
    try:
        assert loader.ready.wait(5)
        assert "not an SQLite file" in loader.error
        loader.get((0, 0, 0))
        until_sync(lambda: loader.is_absent((0, 0, 0)))
    finally:
        loader.close()


def test_loader_online_tiles_and_offline_fallback(tile_server, tmp_path, mbtiles_file, colour_of):
    http = HttpTileSource(tile_server.template, tmp_path / "cache", timeout=5)
    loader = TileLoader(decode, lambda key: None, mbtiles=mbtiles_file, http=http)
    try:
        # in the MBTiles file: never asks the network
        x, y = mercator.tile_for(43.6385, -79.379, 2)
        loader.get((2, x, y))
        until_sync(lambda: loader.get((2, x, y)) is not None)
        assert tile_server.requests == []
        # not in the file: fetched online (the file has 3x3 tiles per zoom), then cached on disk
        loader.get((2, 3, 3))
        until_sync(lambda: loader.get((2, 3, 3)) is not None)
        assert rgb_at(loader.get((2, 3, 3))) == pytest.approx(colour_of(2, 3, 3), abs=2)
        assert tile_server.requests == ["/2/3/3.png"] and http.cached(2, 3, 3)
        loader.get((7, 0, 0))  # 404 online
        until_sync(lambda: loader.is_absent((7, 0, 0)))
    finally:
        loader.close()
    # offline now: a new loader finds the downloaded tile in the disk cache
    tile_server.close()
    loader = TileLoader(decode, lambda key: None, http=HttpTileSource(tile_server.template, tmp_path / "cache"))
    try:
        loader.get((2, 3, 3))
        until_sync(lambda: loader.get((2, 3, 3)) is not None)
        loader.get((1, 1, 1))  # never downloaded: the network is gone, the loader says so and backs off
        until_sync(lambda: loader.is_absent((1, 1, 1)))
        assert loader.net_error
    finally:
        loader.close()
