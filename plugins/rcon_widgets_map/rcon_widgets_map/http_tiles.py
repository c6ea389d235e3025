"""Online tiles from an XYZ URL template, with an on-disk cache. Blocking: call from a worker thread only.

``https://tile.example.org/{z}/{x}/{y}.png`` (also ``{-y}`` for TMS servers and ``{s}`` for a, b, c
subdomains). Each tile is fetched once with a timeout and kept on disk under the cache directory, so a
map seen online stays available offline. After a failure (timeout, refused, 5xx) the source pauses,
doubling the pause up to a minute, so a lost uplink never turns into a storm of requests; a ``404`` marks
only that tile as absent.
"""

from __future__ import annotations

import hashlib
import os
import re
import threading
import time
import urllib.error
import urllib.request
from collections.abc import Callable
from pathlib import Path

from .mercator import tms_row, valid_tile

USER_AGENT = "RCON-map/0.1 (robot operator console)"
_FIELD = re.compile(r"\{([^}]*)\}")
_KNOWN = {"z", "x", "y", "-y", "s"}


class TileUnavailable(Exception):
    """The tile could not be fetched now (network down, server error, pausing); try again later."""


class TileAbsent(Exception):
    """The server says the tile does not exist (HTTP 404/410)."""


def template_problems(template: str) -> list[str]:
    """What is wrong with an XYZ URL template, as sentences (``[]`` = usable)."""
    if not template:
        return []
    out = []
    if not re.match(r"https?://[^/{}]+", template):
        out.append(f"tile URL {template!r} must start with http:// or https:// and a host name")
    fields = set(_FIELD.findall(template))
    unknown = fields - _KNOWN
    if unknown:
        out.append(f"tile URL has unknown placeholder(s) {', '.join('{' + f + '}' for f in sorted(unknown))}")
    if not {"z", "x"} <= fields or not fields & {"y", "-y"}:
        out.append("tile URL must contain {z}, {x} and {y} (or {-y})")
    return out


def tile_url(template: str, z: int, x: int, y: int) -> str:
    """The URL of XYZ tile ``(z, x, y)``."""
    sub = "abc"[(x + y) % 3]
    values = {"z": str(z), "x": str(x), "y": str(y), "-y": str(tms_row(z, y)), "s": sub}
    return _FIELD.sub(lambda mt: values.get(mt.group(1), mt.group(0)), template)


class HttpTileSource:
    """Fetches tiles over HTTP(S) with ``urllib`` and keeps them in ``cache_dir``. Thread-safe."""

    def __init__(
        self,
        template: str,
        cache_dir: str | os.PathLike[str],
        *,
        timeout: float = 6.0,
        user_agent: str = USER_AGENT,
        first_pause: float = 2.0,
        max_pause: float = 60.0,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        problems = template_problems(template)
        if not template or problems:
            raise ValueError("; ".join(problems) or "no tile URL given")
        self.template = template
        key = hashlib.sha1(template.encode()).hexdigest()[:16]
        self.cache_dir = Path(cache_dir) / key
        self.timeout = timeout
        self.user_agent = user_agent
        self.first_pause = first_pause
        self.max_pause = max_pause
        self._clock = clock
        self._lock = threading.Lock()
        self._failures = 0
        self._paused_until = 0.0
        self.fetched = 0  #: tiles downloaded so far (for tests and the status line)
        self.last_error: str | None = None

    # -- disk cache ---------------------------------------------------------------------------------
    def cache_path(self, z: int, x: int, y: int) -> Path:
        return self.cache_dir / str(z) / str(x) / f"{y}.tile"

    def cached(self, z: int, x: int, y: int) -> bytes | None:
        """The tile from the disk cache, or None."""
        try:
            return self.cache_path(z, x, y).read_bytes()
        except OSError:
            return None

    def _store(self, z: int, x: int, y: int, data: bytes) -> None:
        path = self.cache_path(z, x, y)
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            tmp = path.with_suffix(f".{threading.get_ident()}.part")
            tmp.write_bytes(data)
            os.replace(tmp, path)
        except OSError as exc:  # a full or read-only disk costs the cache, not the map
            self.last_error = f"tile cache: {exc}"

    # -- network ------------------------------------------------------------------------------------
    @property
    def paused_for(self) -> float:
        """Seconds left before the next network attempt (0 when not pausing)."""
        with self._lock:
            return max(0.0, self._paused_until - self._clock())

    def fetch(self, z: int, x: int, y: int) -> bytes:
        """Download one tile (and cache it). Raises :class:`TileAbsent` or :class:`TileUnavailable`."""
        if not valid_tile(z, x, y):
            raise TileAbsent(f"tile ({z}, {x}, {y}) is outside the world")
        wait = self.paused_for
        if wait > 0:
            raise TileUnavailable(f"tile server unreachable; next try in {wait:.0f} s")
        url = tile_url(self.template, z, x, y)
        request = urllib.request.Request(url, headers={"User-Agent": self.user_agent})
        try:
            with urllib.request.urlopen(request, timeout=self.timeout) as response:  # noqa: S310 - http(s) only
                data = response.read()
        except urllib.error.HTTPError as exc:
            if exc.code in (404, 410, 204):
                self._succeeded()
                raise TileAbsent(f"{url}: HTTP {exc.code}") from None
            self._failed(f"{url}: HTTP {exc.code} {exc.reason}")
            raise TileUnavailable(self.last_error) from None
        except (OSError, ValueError) as exc:  # URLError, timeouts, refused, bad URL
            reason = getattr(exc, "reason", exc)
            self._failed(f"{url}: {reason}")
            raise TileUnavailable(self.last_error) from None
        if not data:
            self._succeeded()
            raise TileAbsent(f"{url}: empty answer")
        self._succeeded()
        self._store(z, x, y, data)
        self.fetched += 1
        return data

    def _failed(self, error: str) -> None:
        with self._lock:
            self._failures += 1
            pause = min(self.max_pause, self.first_pause * 2 ** (self._failures - 1))
            self._paused_until = self._clock() + pause
            self.last_error = error

    def _succeeded(self) -> None:
        with self._lock:
            self._failures = 0
            self._paused_until = 0.0
