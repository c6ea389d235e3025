"""Files on disk for the store: atomic writes, stale temp files, backup copies. No JSON, no model.

Atomic writes
    A temp file ``.NAME.XXXXXXXX.tmp`` in the directory of the file, written, fsynced, then
    ``os.replace``\\ d over it. A symlinked layout is resolved first: the link stays a link and its
    target is replaced (in the target's directory). The new file keeps the mode of the one it replaces
    (a new file is 0600). While it writes, the writer holds an exclusive ``flock`` on its temp file.

Stale temp files
    A writer killed between creating its temp file and the rename leaves the temp file behind.
    :func:`clean_stale_temps` removes them: only names of exactly that pattern for that file, only when
    older than :data:`STALE_AFTER_S` seconds *and* not locked by a live writer -- another RCON saving the
    same layout right now holds the lock on its temp file, so two instances on one layout never delete
    each other's writes in progress. (Where ``flock`` does not exist, the age alone decides.)
"""

from __future__ import annotations

import contextlib
import logging
import os
import re
import shutil
import tempfile
import time
from pathlib import Path

try:
    import fcntl
except ImportError:  # pragma: no cover - not POSIX
    fcntl = None  # type: ignore[assignment]

log = logging.getLogger(__name__)

__all__ = ["atomic_write", "clean_stale_temps", "real_path", "backup", "same_backup", "STALE_AFTER_S"]

#: a temp file younger than this is never removed (its writer may not hold its lock yet)
STALE_AFTER_S = 5.0


def real_path(path: str | os.PathLike[str]) -> Path:
    """``path`` with every symlink resolved (a dangling link: the path it points to)."""
    return Path(os.path.realpath(path))


def _temp_pattern(name: str) -> re.Pattern[str]:
    # tempfile.mkstemp(prefix=".NAME.", suffix=".tmp"): 8 characters from [a-z0-9_] in between
    return re.compile(rf"\.{re.escape(name)}\.[a-z0-9_]{{8}}\.tmp")


def _lock(fd: int, *, wait: bool) -> bool:
    """An exclusive flock on ``fd``; False when another process holds one (and ``wait`` is False)."""
    if fcntl is None:
        return True
    try:
        fcntl.flock(fd, fcntl.LOCK_EX if wait else fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        return False
    except OSError:  # a file system without locks: the age decides
        return True
    return True


def atomic_write(path: str | os.PathLike[str], text: str, *, mode: int | None = None) -> None:
    """Replace ``path`` with ``text`` atomically: temp file in the same directory, fsync, os.replace.

    A symlink is resolved and its target written; the target keeps its mode (``mode``: this mode
    instead, e.g. 0o600 for a file holding a secret's hash). If anything fails (including a crash before
    the replace), the old file is untouched.
    """
    target = real_path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    if mode is None:
        try:
            mode = target.stat().st_mode & 0o7777
        except FileNotFoundError:
            mode = None
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline="\n") as f:
            _lock(f.fileno(), wait=True)  # held until closed: a cleaner never takes a live write
            if mode is not None and hasattr(os, "fchmod"):
                os.fchmod(f.fileno(), mode)
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
            if fcntl is not None:  # POSIX: rename while still holding the lock
                os.replace(tmp, target)
        if fcntl is None:  # elsewhere an open file cannot be renamed over
            os.replace(tmp, target)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
    if hasattr(os, "O_DIRECTORY"):  # make the rename itself durable (POSIX)
        with contextlib.suppress(OSError):
            dfd = os.open(target.parent, os.O_DIRECTORY)
            try:
                os.fsync(dfd)
            finally:
                os.close(dfd)


def clean_stale_temps(path: str | os.PathLike[str], *, older_than: float = STALE_AFTER_S) -> list[Path]:
    """Remove temp files left by writers of ``path`` that died mid-save; returns what was removed."""
    target = real_path(path)
    pattern = _temp_pattern(target.name)
    removed: list[Path] = []
    try:
        names = [n for n in os.listdir(target.parent) if pattern.fullmatch(n)]
    except OSError:
        return removed
    now = time.time()
    for name in names:
        tmp = target.parent / name
        try:
            fd = os.open(tmp, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0))
        except OSError:  # gone (its writer finished), a symlink, or not ours to read
            continue
        try:
            st = os.fstat(fd)
            if now - st.st_mtime < older_than or not _lock(fd, wait=False):
                continue  # young, or a live writer holds it
            with contextlib.suppress(OSError):
                current = os.stat(tmp, follow_symlinks=False)
                if (current.st_ino, current.st_dev) == (st.st_ino, st.st_dev):  # still the file we locked
                    os.unlink(tmp)
                    removed.append(tmp)
        finally:
            os.close(fd)
    return removed


def same_backup(path: Path, tag: str, content: bytes) -> Path | None:
    """An existing backup of ``path`` with exactly ``content``, if any."""
    for old in sorted(path.parent.glob(f"{glob_escape(path.name)}.{tag}-*")):
        with contextlib.suppress(OSError):
            if old.stat().st_size == len(content) and old.read_bytes() == content:
                return old
    return None


def glob_escape(name: str) -> str:
    return re.sub(r"([*?\[])", r"[\1]", name)


def backup(path: Path, tag: str) -> Path | None:
    """Copy ``path`` next to itself (``NAME.TAG-STAMP``), unless a copy with the same content exists.
    None when there is nothing to copy or the copy failed (never raises)."""
    try:
        content = path.read_bytes()
    except OSError:
        return None
    same = same_backup(path, tag, content)
    if same is not None:
        return same
    stamp = time.strftime("%Y%m%d-%H%M%S")
    dest = path.with_name(f"{path.name}.{tag}-{stamp}")
    n = 1
    while dest.exists():
        n += 1
        dest = path.with_name(f"{path.name}.{tag}-{stamp}-{n}")
    try:
        shutil.copy2(path, dest)
    except OSError as exc:  # a full disk, a read-only directory: no copy (the caller says so)
        log.error("could not copy %s to %s: %s", path, dest, exc)
        with contextlib.suppress(OSError):
            dest.unlink()
        return None
    return dest
