"""Where the app keeps its state on disk: the workspace file, the URL history, each robot's connection
settings (CA file, client certificate and key paths, whether it uses rosauth; never the secret, which
lives in the OS credential store, see ``secret_store.py``), the operator PIN (hashed, see
:mod:`rcon_core.app.pin`) and which robot URLs are view-only.

Everything lives under one config directory (platformdirs' user config dir by default; tests and the
benchmark pass a temporary one), so a restart of the app finds what the operator left.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any
from urllib.parse import urlparse

DEFAULT_URL = "ws://127.0.0.1:9090"
#: the path settings a robot's connection keeps
ROBOT_PATHS = ("ca_file", "client_cert", "client_key")
HISTORY_LIMIT = 12
#: ports the OS hands out for port 0 (Linux starts at 32768, Windows and macOS at 49152)
EPHEMERAL_PORTS = range(32768, 65536)


#: app.json's layout version: 2 = the URL history holds only URLs the operator chose (no embedded robot's)
CONFIG_VERSION = 2


def looks_embedded(url: str) -> bool:
    """A loopback URL on an OS-assigned port: what ``rcon --demo`` runs of earlier builds left in the
    URL history (their embedded robot's port is gone once they exit). Used once, to clean such a history;
    the demo no longer records its URL at all."""
    try:
        parsed = urlparse(url)
        port = parsed.port
    except ValueError:
        return False
    return parsed.hostname in ("127.0.0.1", "localhost", "::1") and port in EPHEMERAL_PORTS


def default_config_dir() -> Path:
    """The user's config dir for RCON (``RCON_CONFIG_DIR`` overrides it)."""
    env = os.environ.get("RCON_CONFIG_DIR")
    if env:
        return Path(env)
    import platformdirs

    return Path(platformdirs.user_config_dir("rcon", appauthor=False))


class AppConfig:
    """The app's small persisted state: URL history and the path of the saved workspace."""

    def __init__(self, config_dir: Path | str | None = None) -> None:
        self.dir = Path(config_dir) if config_dir is not None else default_config_dir()
        self.dir.mkdir(parents=True, exist_ok=True)
        self._file = self.dir / "app.json"
        self._data: dict = {}
        if self._file.exists():
            try:
                loaded = json.loads(self._file.read_text(encoding="utf-8"))
                if isinstance(loaded, dict):
                    self._data = loaded
            except (OSError, ValueError, RecursionError):
                self._data = {}  # a damaged (or absurdly nested) file must not keep the app from starting
        version = self._data.get("version", 1)
        if self._data and (not isinstance(version, int) or version < CONFIG_VERSION):
            # earlier builds put each demo run's embedded robot first: plain `rcon` then connected to a
            # dead port. Drop those entries once.
            history = self._data.get("url_history", [])
            if isinstance(history, list):
                self._data["url_history"] = [u for u in history if isinstance(u, str) and not looks_embedded(u)]
            self._data["version"] = CONFIG_VERSION
            try:
                self.save()
            except OSError:
                pass
        self._data.setdefault("version", CONFIG_VERSION)

    @property
    def workspace_path(self) -> Path:
        """Where the canvas store keeps the workspace (``rcon_core.canvas.default_path`` when the config
        dir is the default one)."""
        return self.dir / "workspace.json"

    @property
    def url_history(self) -> list[str]:
        """URLs the operator connected to (each once connected; the bar records a URL when its link comes
        up, so a typo or an unreachable robot never enters the history), newest first."""
        history = self._data.get("url_history", [])
        return [u for u in history if isinstance(u, str)] if isinstance(history, list) else []

    @property
    def last_url(self) -> str:
        """What plain ``rcon`` connects to: the newest URL the operator chose (``--demo`` never records its
        embedded robot's URL)."""
        history = self.url_history
        return history[0] if history else DEFAULT_URL

    def remember_url(self, url: str) -> None:
        """Put ``url`` first in the history (no duplicates, bounded) and save."""
        url = url.strip()
        if not url:
            return
        history = [u for u in self.url_history if u != url]
        self._data["url_history"] = [url, *history][:HISTORY_LIMIT]
        self.save()

    def robot_settings(self, url: str) -> dict[str, Any]:
        """The connection settings saved for ``url``: ``ca_file``, ``client_cert``, ``client_key`` (paths or
        "") and ``auth`` (bool)."""
        robots = self._data.get("robots")
        saved = robots.get(url) if isinstance(robots, dict) else None
        saved = saved if isinstance(saved, dict) else {}
        out: dict[str, Any] = {k: str(saved.get(k) or "") for k in ROBOT_PATHS}
        out["auth"] = bool(saved.get("auth", False))
        return out

    def set_robot_settings(self, url: str, settings: dict[str, Any]) -> None:
        """Save ``url``'s connection settings (only the known keys; never a secret)."""
        robots = self._data.get("robots")
        robots = robots if isinstance(robots, dict) else {}
        entry: dict[str, Any] = {k: str(settings.get(k) or "") for k in ROBOT_PATHS}
        entry["auth"] = bool(settings.get("auth", False))
        robots[url] = entry
        self._data["robots"] = robots
        self.save()

    @property
    def pin_record(self) -> dict | None:
        """The operator PIN's stored form (salt and scrypt hash, never the PIN), or None when unset."""
        record = self._data.get("operator_pin")
        return record if isinstance(record, dict) else None

    def set_pin_record(self, record: dict | None) -> None:
        if record is None:
            self._data.pop("operator_pin", None)
        else:
            self._data["operator_pin"] = record
        self.save()

    def is_view_only(self, url: str) -> bool:
        """Whether the robot at ``url`` is marked view-only (its widgets never send anything)."""
        urls = self._data.get("view_only_urls", [])
        return isinstance(urls, list) and url.strip() in urls

    def set_view_only(self, url: str, view_only: bool) -> None:
        url = url.strip()
        saved = self._data.get("view_only_urls")
        urls = [u for u in (saved if isinstance(saved, list) else []) if isinstance(u, str) and u != url]
        self._data["view_only_urls"] = [*urls, url] if view_only else urls
        self.save()

    @property
    def theme(self) -> str:
        """The display theme the operator chose ("sunlight" or "night"; see ``theme.py``)."""
        value = self._data.get("theme")
        return value if isinstance(value, str) else "sunlight"

    @property
    def text_size(self) -> int:
        """The text size the operator chose, in percent (100 to 200)."""
        value = self._data.get("text_size")
        return value if isinstance(value, int) and not isinstance(value, bool) else 100

    def set_display(self, theme: str, text_size: int) -> None:
        """Save the display theme and text size."""
        self._data["theme"], self._data["text_size"] = str(theme), int(text_size)
        self.save()

    def save(self) -> None:
        tmp = self._file.with_suffix(".tmp")
        tmp.write_text(json.dumps(self._data, indent=2), encoding="utf-8")
        tmp.replace(self._file)
