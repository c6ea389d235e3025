"""Loads map tiles off the GUI thread and keeps the decoded ones in a bounded LRU memory cache.

The view calls :meth:`TileLoader.get` while painting: it returns the decoded tile at once when cached,
else queues a request and returns None; when the tile arrives, ``on_ready`` is called (from a worker
thread: the view turns it into a queued Qt signal and repaints). Nothing here imports Qt: the view
passes ``decode(bytes) -> image`` (a QImage), called on the worker threads.

Two workers: the *local* one reads the MBTiles file and the disk cache (fast); misses that an online
source could fill go to the *network* one, so a slow or absent uplink never delays offline tiles.
Requests are served newest first (what the operator looks at now), and old queued requests are
dropped when the queue grows past ``max_pending``.
"""

from __future__ import annotations

import collections
import logging
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from .http_tiles import HttpTileSource, TileAbsent, TileUnavailable
from .mbtiles import MBTilesError, MBTilesReader

log = logging.getLogger(__name__)

TileKey = tuple[int, int, int]
#: how long a tile the network could not deliver is left alone before asking again
RETRY_AFTER_S = 30.0


class _Queue:
    """A LIFO request queue with a bound, closed by :meth:`close`."""

    def __init__(self, bound: int) -> None:
        self._items: collections.deque[TileKey] = collections.deque()
        self._cond = threading.Condition()
        self._bound = bound
        self._closed = False

    def put(self, key: TileKey) -> TileKey | None:
        """Add a request; returns a dropped (oldest) request when over the bound."""
        with self._cond:
            self._items.append(key)
            dropped = self._items.popleft() if len(self._items) > self._bound else None
            self._cond.notify()
            return dropped

    def take(self) -> TileKey | None:
        """The newest request, waiting for one; None once closed."""
        with self._cond:
            while not self._items and not self._closed:
                self._cond.wait()
            if self._closed:
                return None
            return self._items.pop()

    def close(self) -> None:
        with self._cond:
            self._closed = True
            self._cond.notify_all()


class TileLoader:
    """Tile cache + worker threads for one map view. Call :meth:`close` when the view goes away."""

    def __init__(
        self,
        decode: Callable[[bytes], Any],
        on_ready: Callable[[TileKey | None], None],
        *,
        mbtiles: str | Path | None = None,
        http: HttpTileSource | None = None,
        memory_tiles: int = 256,
        max_pending: int = 96,
        retry_after: float = RETRY_AFTER_S,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        if memory_tiles < 1:
            raise ValueError("memory_tiles must be at least 1")
        self._decode = decode
        self._on_ready = on_ready
        self.mbtiles_path = Path(mbtiles) if mbtiles else None
        self.http = http
        self.memory_tiles = memory_tiles
        self.retry_after = retry_after
        self._clock = clock
        self._lock = threading.Lock()
        self._images: collections.OrderedDict[TileKey, Any] = collections.OrderedDict()
        self._pending: set[TileKey] = set()
        self._absent: dict[TileKey, float] = {}  # key -> retry time (inf: never)
        self._local_q = _Queue(max_pending)
        self._net_q = _Queue(max_pending)
        self.error: str | None = None  #: the last local problem worth showing (bad MBTiles file...)
        self.net_error: str | None = None  #: why online tiles are not arriving now (None when they are)
        self.max_zoom: int | None = 19 if http is not None else None
        self.min_zoom: int = 0
        self.center: tuple[float, float, int] | None = None
        self.ready = threading.Event()  #: set once the local worker opened its sources
        self.loaded = 0  #: tiles decoded so far
        self._threads = [threading.Thread(target=self._local_worker, name="map-tiles-local", daemon=True)]
        if http is not None:
            self._threads.append(threading.Thread(target=self._net_worker, name="map-tiles-net", daemon=True))
        for t in self._threads:
            t.start()

    # -- GUI side -------------------------------------------------------------------------------------
    def get(self, key: TileKey) -> Any | None:
        """The decoded tile if cached (marks it recently used); else queue it (once) and return None."""
        with self._lock:
            img = self._images.get(key)
            if img is not None:
                self._images.move_to_end(key)
                return img
            if key in self._pending:
                return None
            retry = self._absent.get(key)
            if retry is not None:
                if retry > self._clock():
                    return None
                del self._absent[key]
            self._pending.add(key)
        dropped = self._local_q.put(key)
        if dropped is not None:
            with self._lock:
                self._pending.discard(dropped)
        return None

    def is_absent(self, key: TileKey) -> bool:
        """True when no source has this tile (for now): the view then draws a coarser one."""
        with self._lock:
            retry = self._absent.get(key)
            return retry is not None and retry > self._clock()

    def cached_count(self) -> int:
        with self._lock:
            return len(self._images)

    def close(self) -> None:
        """Stop the workers (they finish the tile in hand) and drop the cache."""
        self._local_q.close()
        self._net_q.close()
        for t in self._threads:
            if t is not threading.current_thread():
                t.join(timeout=2.0)
        with self._lock:
            self._images.clear()

    # -- workers --------------------------------------------------------------------------------------
    def _deliver(self, key: TileKey, data: bytes) -> None:
        try:
            img = self._decode(data)
        except Exception as exc:
            img = None
            self.error = f"tile {key}: cannot decode ({exc})"
        if img is None:
            self._mark_absent(key, float("inf"))
            return
        with self._lock:
            self._pending.discard(key)
            self._images[key] = img
            self._images.move_to_end(key)
            while len(self._images) > self.memory_tiles:
                self._images.popitem(last=False)
            self.loaded += 1
        self._notify(key)

    def _mark_absent(self, key: TileKey, retry_at: float) -> None:
        with self._lock:
            self._pending.discard(key)
            self._absent[key] = retry_at
            if len(self._absent) > 20_000:  # bounded too: forget the oldest half
                for k in list(self._absent)[:10_000]:
                    del self._absent[k]
        self._notify(key)

    def _notify(self, key: TileKey | None) -> None:
        try:
            self._on_ready(key)
        except Exception:  # the view may be gone; never kill the worker
            log.debug("tile on_ready failed", exc_info=True)

    def _local_worker(self) -> None:
        reader: MBTilesReader | None = None
        if self.mbtiles_path is not None:
            try:
                reader = MBTilesReader(self.mbtiles_path)
                self.min_zoom, self.center = reader.min_zoom, reader.center
                self.max_zoom = max(reader.max_zoom, self.max_zoom or 0)
            except MBTilesError as exc:
                self.error = str(exc)
        self.ready.set()
        self._notify(None)
        try:
            while (key := self._local_q.take()) is not None:
                data = None
                if reader is not None:
                    try:
                        data = reader.tile(*key)
                    except Exception as exc:  # a corrupt file: say so once, keep serving the rest
                        self.error = f"MBTiles read failed: {exc}"
                if data is None and self.http is not None:
                    data = self.http.cached(*key)
                    if data is None:
                        dropped = self._net_q.put(key)
                        if dropped is not None:
                            with self._lock:
                                self._pending.discard(dropped)
                        continue
                if data is None:
                    self._mark_absent(key, float("inf"))
                else:
                    self._deliver(key, data)
        finally:
            if reader is not None:
                reader.close()

    def _net_worker(self) -> None:
        assert self.http is not None
        while (key := self._net_q.take()) is not None:
            try:
                data = self.http.fetch(*key)
            except TileAbsent:
                self._mark_absent(key, self._clock() + 3600.0)
                continue
            except TileUnavailable as exc:
                self.net_error = str(exc)
                retry = max(self.retry_after, self.http.paused_for)
                self._mark_absent(key, self._clock() + retry)
                continue
            self.net_error = None
            self._deliver(key, data)
