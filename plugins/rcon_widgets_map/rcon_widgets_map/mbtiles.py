"""MBTiles files (the standard SQLite tile container): read tiles and metadata, write a file.

Layout (MBTiles 1.3): table ``metadata(name, value)`` and table or view
``tiles(zoom_level, tile_column, tile_row, tile_data)``, rows in the TMS scheme (0 at the bottom).
Readers here take and give XYZ rows (0 at the top) and flip them.

A :class:`MBTilesReader` is bound to the thread that opens it (sqlite3's rule); the tile loader opens
one in its worker thread. The file is opened read-only, so a map never changes the operator's file.
"""

from __future__ import annotations

import os
import sqlite3
from collections.abc import Iterable, Mapping
from pathlib import Path

from .mercator import tms_row, valid_tile


class MBTilesError(ValueError):
    """The file is missing, not SQLite, or not an MBTiles file; ``str()`` says which."""


class MBTilesReader:
    """Read-only access to one ``.mbtiles`` file."""

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = Path(path)
        if not self.path.is_file():
            raise MBTilesError(f"MBTiles file {str(self.path)!r} does not exist")
        #: the SQLite URI the file is opened with: ``mode=ro``, SQLite refuses every write through it
        self.uri = f"{self.path.resolve().as_uri()}?mode=ro"
        try:
            self._db = sqlite3.connect(self.uri, uri=True)
            names = {r[0] for r in self._db.execute("SELECT name FROM sqlite_master WHERE type IN ('table','view')")}
        except sqlite3.DatabaseError as exc:
            raise MBTilesError(f"{str(self.path)!r} is not an SQLite file: {exc}") from exc
        missing = {"tiles", "metadata"} - names
        if missing:
            self._db.close()
            raise MBTilesError(
                f"{str(self.path)!r} is not an MBTiles file: no {' or '.join(sorted(missing))} table"
            )
        self.metadata: dict[str, str] = {
            str(k): str(v) for k, v in self._db.execute("SELECT name, value FROM metadata")
        }
        row = self._db.execute("SELECT MIN(zoom_level), MAX(zoom_level) FROM tiles").fetchone()
        self.min_zoom: int = int(self.metadata.get("minzoom", row[0] if row[0] is not None else 0))
        self.max_zoom: int = int(self.metadata.get("maxzoom", row[1] if row[1] is not None else 0))

    def tile(self, z: int, x: int, y: int) -> bytes | None:
        """The encoded image (PNG/JPEG/WebP bytes) of XYZ tile ``(z, x, y)``, or None if the file lacks it."""
        if not valid_tile(z, x, y):
            return None
        row = self._db.execute(
            "SELECT tile_data FROM tiles WHERE zoom_level=? AND tile_column=? AND tile_row=?",
            (z, x, tms_row(z, y)),
        ).fetchone()
        return bytes(row[0]) if row is not None and row[0] is not None else None

    @property
    def center(self) -> tuple[float, float, int] | None:
        """``(lat, lon, zoom)`` from the ``center`` metadata (``lon,lat,zoom``), else the middle of ``bounds``."""
        try:
            if "center" in self.metadata:
                lon, lat, zoom = (float(v) for v in self.metadata["center"].split(","))
                return lat, lon, int(zoom)
            if "bounds" in self.metadata:
                w, s, e, n = (float(v) for v in self.metadata["bounds"].split(","))
                return (s + n) / 2, (w + e) / 2, self.min_zoom
        except ValueError:
            return None
        return None

    def close(self) -> None:
        self._db.close()

    def __enter__(self) -> MBTilesReader:
        return self

    def __exit__(self, *_exc: object) -> None:
        self.close()


def write_mbtiles(
    path: str | os.PathLike[str],
    tiles: Iterable[tuple[int, int, int, bytes]],
    metadata: Mapping[str, str] | None = None,
) -> int:
    """Write an MBTiles file from XYZ ``(z, x, y, data)`` tiles (replacing ``path``); returns the count.

    ``metadata`` gets ``name``/``format``/``minzoom``/``maxzoom`` filled in when absent.
    """
    path = Path(path)
    if path.exists():
        path.unlink()
    db = sqlite3.connect(path)
    try:
        db.execute("CREATE TABLE metadata (name TEXT, value TEXT)")
        db.execute("CREATE TABLE tiles (zoom_level INTEGER, tile_column INTEGER, tile_row INTEGER, tile_data BLOB)")
        db.execute("CREATE UNIQUE INDEX tile_index ON tiles (zoom_level, tile_column, tile_row)")
        zooms: list[int] = []
        count = 0
        for z, x, y, data in tiles:
            if not valid_tile(z, x, y):
                raise MBTilesError(f"tile ({z}, {x}, {y}) is outside the world at zoom {z}")
            db.execute("INSERT INTO tiles VALUES (?, ?, ?, ?)", (z, x, tms_row(z, y), sqlite3.Binary(data)))
            zooms.append(z)
            count += 1
        meta = {"name": path.stem, "format": "png", "type": "baselayer", "version": "1.0"}
        if zooms:
            meta.update(minzoom=str(min(zooms)), maxzoom=str(max(zooms)))
        meta.update(metadata or {})
        db.executemany("INSERT INTO metadata VALUES (?, ?)", list(meta.items()))
        db.commit()
    finally:
        db.close()
    return count
