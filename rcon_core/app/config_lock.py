"""Who may write a config folder: one RCON at a time, and saves that do not step on each other. No Qt.

Two app instances on one config folder used to erase each other's PIN, view-only marks and layout edits
(each wrote its whole ``app.json`` from memory), and their saves raced on one temp file name (issue 22.8:
``FileNotFoundError`` 64 times in 1,000 concurrent saves). Two locks, both advisory OS locks on small files
in the folder, released by the OS when the process dies (a killed RCON never leaves the folder locked):

- :class:`FolderLock` (``rcon.lock``, held while the window is open): the first instance is the folder's
  writer; a second one learns who holds it (the file says the holder's process id) and opens read-only;
- :func:`exclusive` (``.app.json.lock``, held for one save): ``AppConfig.save`` reads the file, applies its
  own changes on top and writes it under this lock, so a save never loses another writer's change (a
  command-line tool, an old RCON, a second instance that was started with ``--config-dir`` aimed here).

POSIX uses ``flock``; Windows ``msvcrt.locking`` on the first byte.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from pathlib import Path

try:
    import fcntl
except ImportError:  # pragma: no cover - Windows
    fcntl = None  # type: ignore[assignment]
try:
    import msvcrt
except ImportError:
    msvcrt = None  # type: ignore[assignment]

__all__ = ["FolderLock", "exclusive", "LOCK_NAME"]

LOCK_NAME = "rcon.lock"
SAVE_LOCK_NAME = ".app.json.lock"


def _try_lock(fd: int, wait: bool) -> bool:
    """An exclusive lock on ``fd``; False when another holds it (and ``wait`` is False)."""
    if fcntl is not None:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX if wait else fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            return False
        return True
    if msvcrt is not None:  # pragma: no cover - Windows
        os.lseek(fd, 0, os.SEEK_SET)
        try:
            msvcrt.locking(fd, msvcrt.LK_LOCK if wait else msvcrt.LK_NBLCK, 1)
        except OSError:
            return False
        return True
    return True  # pragma: no cover - no locks on this platform: one writer is not enforced


def _unlock(fd: int) -> None:
    if fcntl is not None:
        fcntl.flock(fd, fcntl.LOCK_UN)
    elif msvcrt is not None:  # pragma: no cover - Windows
        os.lseek(fd, 0, os.SEEK_SET)
        with contextlib.suppress(OSError):
            msvcrt.locking(fd, msvcrt.LK_UNLCK, 1)


@contextlib.contextmanager
def exclusive(folder: Path) -> Iterator[None]:
    """Hold the folder's save lock for the ``with`` block (waits for another writer's save to end).
    Raises OSError when the lock file cannot be made (a read-only or full folder)."""
    fd = os.open(folder / SAVE_LOCK_NAME, os.O_RDWR | os.O_CREAT, 0o600)
    try:
        _try_lock(fd, wait=True)
        yield
    finally:
        with contextlib.suppress(OSError):
            _unlock(fd)
        os.close(fd)


class FolderLock:
    """The config folder's writer lock, held from :meth:`acquire` until :meth:`release` (or the process
    ends). ``holder`` says who has it when :meth:`acquire` failed."""

    def __init__(self, folder: Path) -> None:
        self.path = Path(folder) / LOCK_NAME
        self._fd: int | None = None
        #: the other holder's process id as its lock file says it ("" when unknown)
        self.holder = ""

    @property
    def held(self) -> bool:
        return self._fd is not None

    def acquire(self) -> bool:
        """True when this process is now the folder's writer (also when it already was). False when
        another process holds it (``holder`` says which). A folder where no lock file can be made (read-only,
        full) counts as held: nothing can be saved there anyway, and the save says so."""
        if self._fd is not None:
            return True
        try:
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o600)
        except OSError:
            return True
        if not _try_lock(fd, wait=False):
            try:
                self.holder = os.read(fd, 64).decode("ascii", "replace").strip()
            except OSError:
                self.holder = ""
            os.close(fd)
            return False
        with contextlib.suppress(OSError):  # say who holds it (a full disk: the lock holds all the same)
            os.ftruncate(fd, 0)
            os.lseek(fd, 0, os.SEEK_SET)
            os.write(fd, f"{os.getpid()}\n".encode("ascii"))
        self._fd = fd
        return True

    def release(self) -> None:
        fd, self._fd = self._fd, None
        if fd is not None:
            with contextlib.suppress(OSError):
                _unlock(fd)
            os.close(fd)
