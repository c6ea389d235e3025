"""``rcon --canvas FILE|TEMPLATE`` and ``--window-size WxH``: open one canvas, headless if need be.

A lab checks its widget in CI the way an operator sees it: ``rcon --demo --canvas "Gripper station"
--window-size 1024x600 --screenshot gripper.png`` opens the plugin's template (or any canvas file in
the ``rcon-canvas`` format, as *Export canvas…* writes it) on the embedded robot and writes the picture.

The canvas is opened in a workspace of its own, in a temporary folder removed when the app ends: the
file given is only read, and the operator's saved workspace is neither read nor changed. Qt-free, so
the argument checks are tested without a display.
"""

from __future__ import annotations

import json
import re
import tempfile
from pathlib import Path
from typing import Any

__all__ = ["CanvasOptionError", "parse_window_size", "resolve_canvas", "canvas_workspace", "layout_is_canvas"]

SIZE_RE = re.compile(r"(\d{1,5})[xX×](\d{1,5})")
#: the smallest window the app lays out (a 7" tablet in portrait is 600 wide) and a sane largest
MIN_SIZE, MAX_SIZE = (320, 240), (10_000, 10_000)


class CanvasOptionError(ValueError):
    """A ``--canvas`` or ``--window-size`` that cannot be used; the message says why."""


def parse_window_size(text: str) -> tuple[int, int]:
    """``"1024x600"`` -> ``(1024, 600)``; refuses another shape and sizes outside 320x240..10000x10000."""
    found = SIZE_RE.fullmatch(text.strip())
    if found is None:
        raise CanvasOptionError(f"--window-size must look like 1024x600 (width x height in pixels), got {text!r}")
    w, h = int(found[1]), int(found[2])
    if not (MIN_SIZE[0] <= w <= MAX_SIZE[0] and MIN_SIZE[1] <= h <= MAX_SIZE[1]):
        raise CanvasOptionError(f"--window-size {w}x{h} is outside {MIN_SIZE[0]}x{MIN_SIZE[1]} .. "
                                f"{MAX_SIZE[0]}x{MAX_SIZE[1]}")
    return w, h


def resolve_canvas(what: str, plugins: Any) -> Path:
    """The canvas file ``--canvas`` names: an existing file, else the title of a template an installed
    plugin offers (case and spaces aside). Raises :class:`CanvasOptionError` listing the templates."""
    path = Path(what)
    if path.is_file():
        return path
    templates = plugins.canvas_templates()
    key = " ".join(what.split()).casefold()
    for template in templates:
        if " ".join(template.title.split()).casefold() == key:
            return Path(template.path)
    titles = ", ".join(repr(t.title) for t in templates) or "none: no installed plugin offers a template"
    raise CanvasOptionError(f"--canvas {what!r}: no such file, and no template of that title (templates: {titles})")


def canvas_workspace(path: Path, stack: Any) -> Path:
    """A workspace file holding only the canvas at ``path``, in a temporary folder that ``stack`` (an
    ExitStack) removes; raises :class:`CanvasOptionError` with the reason when the file is not a canvas."""
    from rcon_core.canvas import Workspace, WorkspaceFileError, WorkspaceStore, import_canvas

    try:
        canvas = import_canvas(path)
    except WorkspaceFileError as exc:
        raise CanvasOptionError(f"--canvas {path}: {exc.reason}") from None
    folder = Path(stack.enter_context(tempfile.TemporaryDirectory(prefix="rcon-canvas-")))
    layout = folder / "workspace.json"
    WorkspaceStore(layout).save(Workspace([canvas], canvas.id))
    return layout


def layout_is_canvas(path: Path) -> bool:
    """Whether a ``--layout`` file is a canvas file (``rcon-canvas``), which ``--canvas`` opens."""
    try:
        head = json.loads(path.read_bytes())
    except (OSError, ValueError, RecursionError):
        return False
    return isinstance(head, dict) and head.get("format") == "rcon-canvas"
