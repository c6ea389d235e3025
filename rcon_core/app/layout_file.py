"""The layout file's messages on the notice bar: a layout that cannot be read, the way out of it, a save
that failed (kept out of ``main_window.py``).

A layout file that cannot be read is left as it is and never overwritten (the store turns read-only);
the notice says so and offers *Start a new layout*, which moves the file aside (its content kept) and
saves from then on. The demo's own layout (``rcon --demo``) is moved aside once and built afresh instead.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from pathlib import Path

from rcon_core.app.notice_bar import NoticeBar
from rcon_core.canvas import Workspace, WorkspaceFileError, WorkspaceStore

__all__ = ["LayoutFile"]

log = logging.getLogger(__name__)


class LayoutFile:
    """The workspace file at ``path`` (its :attr:`store`), reporting on ``notice``."""

    def __init__(self, path: Path, notice: NoticeBar, demo: Callable[[], Workspace] | None,
                 flush: Callable[[], object]) -> None:
        self.path = path
        self.store = WorkspaceStore(path)
        self.notice = notice
        self.demo = demo
        self.flush = flush  #: saves the workspace now (the window's saver)
        self.demo_rebuilt = False  #: the demo layout was unreadable and built afresh (save it at once)

    def load(self) -> Workspace:
        """The saved workspace; a file that cannot be read is reported on the notice bar and left alone
        (the demo's own layout is moved aside once and built afresh instead)."""
        try:
            return self.store.load()
        except WorkspaceFileError as exc:
            if self.demo is not None:
                try:
                    kept = self.store.move_aside()
                except WorkspaceFileError as aside:  # no copy could be kept: leave it, say so
                    self.show_problem(f"{exc}; {aside.reason}")
                    return Workspace.new()
                log.warning("demo layout unreadable (%s); moved to %s, building a fresh one", exc.reason, kept)
                self.demo_rebuilt = True
                self.notice.show_notice(
                    f"ℹ The saved demo layout could not be read ({exc.reason}). It was moved to {kept} and "
                    "a fresh demo layout was built.", kind="info")
                return self.demo()
            log.error("%s; starting with an empty workspace", exc)
            self.show_problem(str(exc))
            return Workspace.new()

    def show_problem(self, text: str) -> None:
        self.notice.show_notice(
            f"⚠ The layout could not be opened: {text}.\nThe file is left as it is and will not be "
            "overwritten: changes made now are not saved. Start a new layout to move the file aside "
            "(its content is kept) and save again.",
            actions=[("Start a new layout", self.start_new)],
        )

    def start_new(self) -> None:
        """The way out of an unreadable layout: move the file aside explicitly and save from now on."""
        try:
            kept = self.store.move_aside()
        except WorkspaceFileError as exc:
            self.show_problem(str(exc))
            return
        self.flush()
        where = f" The old file was kept as {kept}." if kept is not None else ""
        self.notice.show_notice(f"ℹ New layout started: it is saved to {self.path}.{where}", kind="info")

    def save_failed(self, text: str) -> None:
        if self.store.read_only:
            return  # the notice already says why nothing is saved
        self.notice.show_notice(f"⚠ The layout could not be saved: {text}")
