"""Where the app keeps its state on disk: the workspace file, the URL history, each robot's connection
settings (CA file, client certificate and key paths, whether it uses rosauth; never the secret, which
lives in the OS credential store, see ``secret_store.py``), the operator PIN (hashed, see
:mod:`rcon_core.app.pin`) and which robot URLs are view-only.

Everything lives under one config directory (platformdirs' user config dir by default; tests and the
benchmark pass a temporary one), so a restart of the app finds what the operator left.

Decisions (issues 21.1 and 22.8):

* **A change applies in memory first**, then is saved. A save that fails (a full or read-only disk) never
  raises out of a setter: the setter returns False, :attr:`AppConfig.save_problem` says why, problem
  listeners get one sentence naming what was not saved (the window shows it), and the change is tried
  again with the next save. So ticking View only on a full disk still stops the robot's commands.
* **Saves never lose another writer's change**: each setter records its change as a small function; a save
  takes the folder's save lock (``config_lock.exclusive``), reads the file as it is now, applies this
  instance's pending changes on top and writes it atomically (``canvas.files.atomic_write``, a unique temp
  file: no two savers share one). **One writer per folder**: the window claims the folder
  (:meth:`AppConfig.claim`, ``config_lock.FolderLock``); a second instance finds it taken and runs
  read-only (:attr:`AppConfig.read_only_reason`; nothing it changes is saved, and it says so).
* ``app.json`` holds the PIN's hash and the wrong-PIN lockout: it is written 0600 (an older, wider file is
  narrowed when opened).
"""

from __future__ import annotations

import copy
import json
import logging
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any
from urllib.parse import urlparse

from rcon_core.app.config_lock import FolderLock, exclusive
from rcon_core.canvas.files import atomic_write

log = logging.getLogger(__name__)

DEFAULT_URL = "ws://127.0.0.1:9090"
#: the path settings a robot's connection keeps
ROBOT_PATHS = ("ca_file", "client_cert", "client_key")
HISTORY_LIMIT = 12
#: ports the OS hands out for port 0 (Linux starts at 32768, Windows and macOS at 49152)
EPHEMERAL_PORTS = range(32768, 65536)


#: app.json's layout version: 2 = the URL history holds only URLs the operator chose (no embedded robot's)
CONFIG_VERSION = 2
#: app.json's mode: it holds the operator PIN's hash
FILE_MODE = 0o600

Change = Callable[[dict[str, Any]], None]


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
    """The app's small persisted state: URL history, robots' connection settings, the operator PIN (hashed)
    and its lockout, view-only robot URLs (see the module docstring for how it is saved)."""

    def __init__(self, config_dir: Path | str | None = None) -> None:
        self.dir = Path(config_dir) if config_dir is not None else default_config_dir()
        self.dir.mkdir(parents=True, exist_ok=True)
        self._file = self.dir / "app.json"
        #: changes not yet on disk (applied to ``_data`` already), in order
        self._pending: list[Change] = []
        #: why the last save failed, in words (None: saved)
        self.save_problem: str | None = None
        #: why nothing is saved at all (another RCON is this folder's writer), or None
        self.read_only_reason: str | None = None
        self._listeners: list[Callable[[str], None]] = []
        #: the last sentence the problem listeners got, until a save succeeds (None: all saved)
        self.problem_text: str | None = None
        self._lock = FolderLock(self.dir)
        loaded = self._read()
        self._data: dict[str, Any] = loaded if loaded is not None else {}
        self._narrow_mode()
        version = self._data.get("version", 1)
        if self._data and (not isinstance(version, int) or version < CONFIG_VERSION):
            # earlier builds put each demo run's embedded robot first: plain `rcon` then connected to a
            # dead port. Drop those entries once.
            self._change(_migrate_history, "the cleaned URL history")
        self._data.setdefault("version", CONFIG_VERSION)

    # ------------------------------------------------------------------------------------ the file
    @property
    def file(self) -> Path:
        return self._file

    def _read(self) -> dict[str, Any] | None:
        """The file's content ({} when there is none), or None when it cannot be read or is damaged (a
        damaged or absurdly nested file must not keep the app from starting)."""
        try:
            loaded = json.loads(self._file.read_text(encoding="utf-8"))
        except FileNotFoundError:
            return {}
        except (OSError, ValueError, RecursionError):
            return None
        return loaded if isinstance(loaded, dict) else None

    def _narrow_mode(self) -> None:
        """An app.json from before (0644) holds the PIN hash readable by every user: narrow it now."""
        try:
            if self._file.stat().st_mode & 0o077:
                os.chmod(self._file, FILE_MODE)
        except OSError:
            pass

    def claim(self) -> bool:
        """Become the config folder's one writer (the window does, for as long as it is open). False when
        another RCON holds it: then this config is read-only (:attr:`read_only_reason` says why) and
        nothing it changes is saved."""
        if self._lock.acquire():
            self.read_only_reason = None
            return True
        who = f"process {self._lock.holder}" if self._lock.holder.isdigit() else "another process"
        self.read_only_reason = f"another RCON ({who}) is using the config folder {self.dir}"
        return False

    def release(self) -> None:
        """Stop being the folder's writer (the window closed)."""
        self._lock.release()

    def add_problem_listener(self, fn: Callable[[str], None]) -> None:
        """``fn(sentence)`` when a change could not be saved (once per distinct problem)."""
        self._listeners.append(fn)

    def _change(self, change: Change, what: str, then: str = "") -> bool:
        """Apply ``change`` in memory now, then save; True when it is on disk. ``what`` names it and
        ``then`` says what not saving it means, for the operator."""
        change(self._data)
        self._pending.append(change)
        if self.save():
            return True
        if self.read_only_reason is None and self.save_problem is not None:
            text = (f"{what[:1].upper()}{what[1:]} could not be saved ({self.save_problem}): "
                    f"{then or 'it applies until RCON quits'}.")
            if text != self.problem_text:
                self.problem_text = text
                for fn in list(self._listeners):
                    try:
                        fn(text)
                    except Exception:
                        log.exception("config problem listener failed")
        return False

    def save(self) -> bool:
        """Write the pending changes on top of the file as it is now (see the module docstring); True
        when written. Never raises for a disk that refuses: :attr:`save_problem` says why."""
        if self.read_only_reason is not None:
            return False
        try:
            with exclusive(self.dir):
                base = self._read()
                if base is None:  # damaged on disk: what this instance holds is the best there is
                    base = copy.deepcopy(self._data)
                else:
                    for change in self._pending:
                        change(base)
                base.setdefault("version", CONFIG_VERSION)
                atomic_write(self._file, json.dumps(base, indent=2), mode=FILE_MODE)
        except OSError as exc:
            self.save_problem = f"{self._file}: {exc.strerror or exc}"
            log.error("saving the app settings failed: %s", self.save_problem)
            return False
        self._data = base
        self._pending.clear()
        self.save_problem = self.problem_text = None
        return True

    # ------------------------------------------------------------------------------------ reading
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

    def remember_url(self, url: str) -> bool:
        """Put ``url`` first in the history (no duplicates, bounded) and save."""
        url = url.strip()
        if not url:
            return True

        def change(data: dict[str, Any]) -> None:
            history = data.get("url_history")
            old = [u for u in history if isinstance(u, str) and u != url] if isinstance(history, list) else []
            data["url_history"] = [url, *old][:HISTORY_LIMIT]

        return self._change(change, "the URL history")

    def robot_settings(self, url: str) -> dict[str, Any]:
        """The connection settings saved for ``url``: ``ca_file``, ``client_cert``, ``client_key`` (paths or
        "") and ``auth`` (bool)."""
        robots = self._data.get("robots")
        saved = robots.get(url) if isinstance(robots, dict) else None
        saved = saved if isinstance(saved, dict) else {}
        out: dict[str, Any] = {k: str(saved.get(k) or "") for k in ROBOT_PATHS}
        out["auth"] = bool(saved.get("auth", False))
        return out

    def set_robot_settings(self, url: str, settings: dict[str, Any]) -> bool:
        """Save ``url``'s connection settings (only the known keys; never a secret)."""
        entry: dict[str, Any] = {k: str(settings.get(k) or "") for k in ROBOT_PATHS}
        entry["auth"] = bool(settings.get("auth", False))

        def change(data: dict[str, Any]) -> None:
            robots = data.get("robots")
            data["robots"] = {**(robots if isinstance(robots, dict) else {}), url: dict(entry)}

        return self._change(change, f"the connection settings of {url}")

    @property
    def pin_record(self) -> dict | None:
        """The operator PIN's stored form (salt and scrypt hash, never the PIN), or None when unset."""
        record = self._data.get("operator_pin")
        return record if isinstance(record, dict) else None

    def set_pin_record(self, record: dict | None) -> bool:
        """Keep (or, None, remove) the PIN's record; False when it could not be saved (it holds for this
        run only: the listeners are told)."""
        def change(data: dict[str, Any]) -> None:
            if record is None:
                data.pop("operator_pin", None)
            else:
                data["operator_pin"] = dict(record)

        return self._change(change, "the operator PIN",
                            "it locks this run only; after a restart no PIN is set and `rcon --locked` will "
                            "not start" if record is not None else "")

    @property
    def pin_lockout(self) -> dict[str, float]:
        """The wrong-PIN lockout kept across restarts: ``wrong`` (tries since the last right one or the last
        wait), ``until`` (wall-clock time of the end of the current wait, 0 for none), ``backoff`` (the
        next wait in seconds, 0 for the first)."""
        saved = self._data.get("pin_lockout")
        saved = saved if isinstance(saved, dict) else {}
        out = {}
        for key in ("wrong", "until", "backoff"):
            value = saved.get(key, 0)
            out[key] = float(value) if isinstance(value, int | float) and not isinstance(value, bool) else 0.0
        return out

    def set_pin_lockout(self, wrong: int, until: float, backoff: float) -> bool:
        state = {"wrong": int(wrong), "until": float(until), "backoff": float(backoff)}

        def change(data: dict[str, Any]) -> None:
            if state["wrong"] or state["until"]:
                data["pin_lockout"] = dict(state)
            else:
                data.pop("pin_lockout", None)

        return self._change(change, "the wrong-PIN count", "a restart forgets it")

    def is_view_only(self, url: str) -> bool:
        """Whether the robot at ``url`` is marked view-only (its widgets never send anything)."""
        urls = self._data.get("view_only_urls", [])
        return isinstance(urls, list) and url.strip() in urls

    def set_view_only(self, url: str, view_only: bool, *, save: bool = True) -> bool:
        """Mark ``url`` view-only (or not), in memory at once; ``save=False`` leaves the save to a later
        :meth:`save` (the window applies the mark to the robot's link first)."""
        url = url.strip()

        def change(data: dict[str, Any]) -> None:
            saved = data.get("view_only_urls")
            urls = [u for u in (saved if isinstance(saved, list) else []) if isinstance(u, str) and u != url]
            data["view_only_urls"] = [*urls, url] if view_only else urls

        if not save:
            change(self._data)
            self._pending.append(change)
            return False
        return self._change(change, f"the view-only mark of {url}")

    def save_view_only(self, url: str) -> bool:
        """Save a view-only mark set with ``save=False``, telling the listeners when it fails."""
        return self._change(lambda _data: None, f"the view-only mark of {url.strip()}")


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

    def set_display(self, theme: str, text_size: int) -> bool:
        """Keep the display theme and text size (in memory at once; False, and the listeners told, when the
        save failed)."""

        def change(data: dict[str, Any]) -> None:
            data["theme"], data["text_size"] = str(theme), int(text_size)

        return self._change(change, "the display settings")


def _migrate_history(data: dict[str, Any]) -> None:
    history = data.get("url_history", [])
    if isinstance(history, list):
        data["url_history"] = [u for u in history if isinstance(u, str) and not looks_embedded(u)]
    data["version"] = CONFIG_VERSION
