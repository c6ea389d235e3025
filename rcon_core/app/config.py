"""Where the app keeps its state on disk: the workspace file and the URL history.

Everything lives under one config directory (platformdirs' user config dir by default; tests and the
benchmark pass a temporary one), so a restart of the app finds what the operator left.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

DEFAULT_URL = "ws://127.0.0.1:9090"
HISTORY_LIMIT = 12


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
            except (OSError, ValueError):
                self._data = {}  # a damaged file must not keep the app from starting

    @property
    def workspace_path(self) -> Path:
        """Where the canvas store keeps the workspace (``rcon_core.canvas.default_path`` when the config
        dir is the default one)."""
        return self.dir / "workspace.json"

    @property
    def url_history(self) -> list[str]:
        history = self._data.get("url_history", [])
        return [u for u in history if isinstance(u, str)]

    @property
    def last_url(self) -> str:
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

    def save(self) -> None:
        tmp = self._file.with_suffix(".tmp")
        tmp.write_text(json.dumps(self._data, indent=2), encoding="utf-8")
        tmp.replace(self._file)
