"""Save the workspace after every change (optionally debounced)."""

from __future__ import annotations

import sys
import threading
from collections.abc import Callable

from .document import Change, Document
from .store import WorkspaceFileError, WorkspaceStore

__all__ = ["AutoSaver"]


class AutoSaver:
    """Listens to a :class:`Document` and saves it through a :class:`WorkspaceStore`.

    ``debounce`` (seconds) groups bursts of changes (a drag) into one write, from a timer thread;
    ``None`` saves synchronously after each change. Canvas switches are saved too (the current canvas
    is part of the workspace). Errors go to ``on_error`` (default: stderr) and never to the editor.
    Call :meth:`flush` before exiting and :meth:`close` to stop listening.
    """

    def __init__(
        self,
        doc: Document,
        store: WorkspaceStore,
        *,
        debounce: float | None = None,
        on_error: Callable[[Exception], object] | None = None,
    ) -> None:
        self.doc = doc
        self.store = store
        self.debounce = debounce
        self.on_error = on_error or (lambda exc: print(f"rcon: autosave failed: {exc}", file=sys.stderr))
        self.saves = 0
        self._timer: threading.Timer | None = None
        self._lock = threading.Lock()
        self._remove = doc.add_listener(self._changed)

    def _changed(self, _change: Change) -> None:
        if self.debounce is None:
            self.flush()
            return
        with self._lock:
            if self._timer is not None:
                self._timer.cancel()
            self._timer = threading.Timer(self.debounce, self.flush)
            self._timer.daemon = True
            self._timer.start()

    def flush(self) -> bool:
        """Save now (cancelling a pending debounced save). True when written."""
        with self._lock:
            if self._timer is not None:
                self._timer.cancel()
                self._timer = None
            try:
                self.store.save(self.doc.workspace)
            except (WorkspaceFileError, OSError) as exc:
                self.on_error(exc)
                return False
            self.saves += 1
            return True

    def close(self) -> None:
        with self._lock:
            if self._timer is not None:
                self._timer.cancel()
                self._timer = None
        self._remove()
