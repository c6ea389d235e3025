"""Saving and loading workspaces: versioned JSON, atomic writes, backups, canvas import/export.

File layout (``version`` 1)::

    {"format": "rcon-workspace", "version": 1, "current": "c-...",
     "canvases": [{"id", "name", "locked", "view_only" (written only when true), "widgets": [{"id",
       "kind", "title", "binding": {"name", "type", "role", "field_paths"}, "geometry": {"x", "y", "w",
       "h"}, "settings": {...}}]}],
     "plugin_settings": {"kind": {...}}}

A single canvas exported to a file is ``{"format": "rcon-canvas", "version": 1, "canvas": {...}}``.
Keys this version does not know are kept and written back, so a newer minor addition survives a
round trip; a widget whose plugin is missing keeps its settings byte for byte.

Writes are atomic: a temp file in the same directory, fsync, ``os.replace``. A file that cannot be read
(corrupt, or written by a newer RCON) raises :class:`WorkspaceFileError`; it is copied to a backup
next to it (one copy per distinct content: reading the same bad file again keeps no second copy) and the
store then refuses to overwrite it (``store.read_only``) until ``save(force=True)`` or until
:meth:`WorkspaceStore.move_aside` moved it out of the way (the operator chose to start a new layout).

Changing the saved shape
------------------------
Any change to what is written (a key renamed, moved, or given another meaning) must bump :data:`VERSION`
and add a migration from the previous version in :func:`workspace_from_dict`, with a test that a file
of the previous version still loads (``tests/test_canvas_store.py`` keeps a version 1 file for that).
Adding a key that older versions may ignore needs no bump: unknown keys are kept and written back.
Never change the shape under the same version number: files written by earlier builds would become
unreadable (they are then reported, never overwritten, but the operator's layout is gone from view).
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import tempfile
import time
from pathlib import Path
from typing import Any

import attrs
import cattrs
import cattrs.gen
import cattrs.v

from rcon_core.plugins.model import Binding

from .model import Canvas, Geometry, WidgetInstance, Workspace

__all__ = [
    "FORMAT",
    "CANVAS_FORMAT",
    "VERSION",
    "WorkspaceStore",
    "WorkspaceFileError",
    "NewerVersionError",
    "default_path",
    "dumps_workspace",
    "loads_workspace",
    "export_canvas",
    "import_canvas",
    "atomic_write",
]

FORMAT = "rcon-workspace"
CANVAS_FORMAT = "rcon-canvas"
VERSION = 1


class WorkspaceFileError(ValueError):
    """A layout file cannot be used; the message says which file and why."""

    def __init__(self, path: str | os.PathLike[str] | None, reason: str, backup: Path | None = None) -> None:
        self.path = Path(path) if path is not None else None
        self.reason = reason
        self.backup = backup
        where = f"{self.path}: " if self.path else ""
        kept = f" (a copy was kept at {backup})" if backup else ""
        super().__init__(f"{where}{reason}{kept}")


class NewerVersionError(WorkspaceFileError):
    """The file was written by a newer RCON (a higher format version)."""


def default_path() -> Path:
    """``<user config dir>/rcon/workspace.json`` (platformdirs); ``RCON_CONFIG_DIR`` overrides the dir."""
    override = os.environ.get("RCON_CONFIG_DIR")
    if override:
        return Path(override) / "workspace.json"
    import platformdirs

    return Path(platformdirs.user_config_dir("rcon", appauthor=False)) / "workspace.json"


# -- the private converter -------------------------------------------------------------------------


def _split_extra(cls: type, data: Any, where: str) -> tuple[dict[str, Any], dict[str, Any]]:
    if not isinstance(data, dict):
        raise ValueError(f"{where} must be an object, got {type(data).__name__}")
    known = {a.name for a in attrs.fields(cls)} - {"extra"}
    return {k: v for k, v in data.items() if k in known}, {k: v for k, v in data.items() if k not in known}


def _make_converter() -> cattrs.Converter:
    conv = cattrs.Converter(forbid_extra_keys=False)

    def unstructure_binding(b: Binding) -> dict[str, Any]:
        return {"name": b.name, "type": b.type, "role": b.role.value, "field_paths": list(b.field_paths)}

    def structure_binding(data: Any, _t: Any) -> Binding:
        if not isinstance(data, dict):
            raise ValueError("binding must be an object")
        paths = data.get("field_paths", ())
        if not isinstance(paths, (list, tuple)) or not all(isinstance(p, str) for p in paths):
            raise ValueError("binding.field_paths must be a list of strings")
        for key in ("name", "type"):
            if not isinstance(data.get(key, ""), str):
                raise ValueError(f"binding.{key} must be a string")
        return Binding(
            data.get("name", ""), data.get("type", ""), data.get("role", "subscribe"), tuple(paths)
        )

    conv.register_unstructure_hook(Binding, unstructure_binding)
    conv.register_structure_hook(Binding, structure_binding)

    def structure_geometry(data: Any, _t: Any) -> Geometry:
        if not isinstance(data, dict):
            raise ValueError("geometry must be an object with x, y, w, h")
        vals = {}
        for k in ("x", "y", "w", "h"):
            v = data.get(k, getattr(Geometry(), k))
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                raise ValueError(f"geometry.{k} must be a number, got {v!r}")
            vals[k] = float(v)
        return Geometry(**vals)

    conv.register_structure_hook(Geometry, structure_geometry)

    def structure_settings(data: Any, _t: Any) -> dict[str, Any]:
        if not isinstance(data, dict):
            raise ValueError("settings must be an object")
        return data  # kept as-is: only the widget's plugin interprets it

    conv.register_structure_hook_func(lambda t: t == dict[str, Any], structure_settings)

    def with_extra(cls: type, order: tuple[str, ...], optional: tuple[str, ...] = ()) -> None:
        # ``optional`` keys are written only when set (a file without them reads the same)
        base_struct: cattrs.SimpleStructureHook[Any, Any] = cattrs.gen.make_dict_structure_fn(cls, conv)

        def structure(data: Any, _t: Any) -> Any:
            known, extra = _split_extra(cls, data, cls.__name__)
            obj = base_struct(known, cls)
            obj.extra = extra
            return obj

        def unstructure(obj: Any) -> dict[str, Any]:
            out = {k: conv.unstructure(getattr(obj, k)) for k in order
                   if k not in optional or getattr(obj, k)}
            out.update(obj.extra)
            return out

        conv.register_structure_hook(cls, structure)
        conv.register_unstructure_hook(cls, unstructure)

    with_extra(WidgetInstance, ("id", "kind", "title", "binding", "geometry", "settings"))
    with_extra(Canvas, ("id", "name", "locked", "view_only", "widgets"), optional=("view_only",))

    return conv


_CONV = _make_converter()


def _format_exc(exc: BaseException, type_: Any) -> str:
    if isinstance(exc, ValueError) and str(exc):
        return str(exc)
    return cattrs.v.format_exception(exc, type_)


def _describe(exc: Exception, root: str = "$") -> str:
    if isinstance(exc, cattrs.BaseValidationError):
        return "; ".join(cattrs.transform_error(exc, path=root, format_exception=_format_exc))
    return str(exc)


def _check_header(data: Any, fmt: str, path: Path | None) -> None:
    if not isinstance(data, dict) or data.get("format") != fmt:
        found = data.get("format") if isinstance(data, dict) else type(data).__name__
        raise WorkspaceFileError(
            path, f"not an RCON {fmt.split('-')[1]} file (format is {found!r}, expected {fmt!r})"
        )
    version = data.get("version")
    if isinstance(version, bool) or not isinstance(version, int) or version < 1:
        raise WorkspaceFileError(path, f"bad format version {version!r}")
    if version > VERSION:
        raise NewerVersionError(
            path, f"written by a newer RCON (format version {version}; this version reads up to {VERSION})"
        )


def workspace_to_dict(ws: Workspace) -> dict[str, Any]:
    out: dict[str, Any] = {
        "format": FORMAT,
        "version": VERSION,
        "current": ws.current,
        "canvases": [_CONV.unstructure(c) for c in ws.canvases],
        "plugin_settings": ws.plugin_settings,
    }
    out.update(ws.extra)
    return out


def workspace_from_dict(data: Any, path: Path | None = None) -> Workspace:
    _check_header(data, FORMAT, path)
    body = {k: v for k, v in data.items() if k not in ("format", "version")}
    try:
        canvases = _CONV.structure(body.pop("canvases", []), list[Canvas])
        current = body.pop("current", "")
        plugin_settings = body.pop("plugin_settings", {})
        if not isinstance(current, str):
            raise ValueError("current must be a canvas id")
        if not isinstance(plugin_settings, dict) or not all(
            isinstance(v, dict) for v in plugin_settings.values()
        ):
            raise ValueError("plugin_settings must map widget kinds to objects")
    except Exception as exc:
        raise WorkspaceFileError(path, f"invalid workspace: {_describe(exc, 'canvases')}") from exc
    ids = [c.id for c in canvases] + [w.id for c in canvases for w in c.widgets]
    dup = sorted({i for i in ids if ids.count(i) > 1})
    if dup:
        raise WorkspaceFileError(path, f"invalid workspace: duplicate ids {dup}")
    return Workspace(canvases, current, plugin_settings, body)


def dumps_workspace(ws: Workspace) -> str:
    return json.dumps(workspace_to_dict(ws), indent=2, ensure_ascii=False) + "\n"


def loads_workspace(text: str | bytes, path: Path | None = None) -> Workspace:
    try:
        data = json.loads(text)
    except (ValueError, UnicodeDecodeError) as exc:
        raise WorkspaceFileError(path, f"not valid JSON ({exc})") from exc
    return workspace_from_dict(data, path)


def atomic_write(path: str | os.PathLike[str], text: str) -> None:
    """Replace ``path`` with ``text`` atomically: temp file in the same directory, fsync, os.replace.

    If anything fails (including a crash before the replace), the old file is untouched.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline="\n") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
    if hasattr(os, "O_DIRECTORY"):  # make the rename itself durable (POSIX)
        with contextlib.suppress(OSError):
            dfd = os.open(path.parent, os.O_DIRECTORY)
            try:
                os.fsync(dfd)
            finally:
                os.close(dfd)


def _same_backup(path: Path, tag: str, content: bytes) -> Path | None:
    """An existing backup of ``path`` with exactly ``content``, if any."""
    for old in sorted(path.parent.glob(f"{path.name}.{tag}-*")):
        with contextlib.suppress(OSError):
            if old.stat().st_size == len(content) and old.read_bytes() == content:
                return old
    return None


def _backup(path: Path, tag: str) -> Path | None:
    """Copy ``path`` next to itself (``NAME.TAG-STAMP``), unless a copy with the same content exists."""
    try:
        content = path.read_bytes()
    except OSError:
        return None
    same = _same_backup(path, tag, content)
    if same is not None:
        return same
    stamp = time.strftime("%Y%m%d-%H%M%S")
    dest = path.with_name(f"{path.name}.{tag}-{stamp}")
    n = 1
    while dest.exists():
        n += 1
        dest = path.with_name(f"{path.name}.{tag}-{stamp}-{n}")
    shutil.copy2(path, dest)
    return dest


class WorkspaceStore:
    """Where the workspace lives on disk. ``path`` defaults to :func:`default_path`."""

    def __init__(self, path: str | os.PathLike[str] | None = None) -> None:
        self.path = Path(path) if path is not None else default_path()
        #: set when the file on disk could not be read: saving would destroy it
        self.read_only_reason: str | None = None

    @property
    def read_only(self) -> bool:
        return self.read_only_reason is not None

    def load(self) -> Workspace:
        """The saved workspace, or a new one when there is no file yet.

        Raises :class:`WorkspaceFileError` (after copying the file to a backup and making the store
        read-only) when the file is corrupt or newer.
        """
        try:
            raw = self.path.read_bytes()
        except FileNotFoundError:
            return Workspace.new()
        except OSError as exc:
            self.read_only_reason = str(exc)
            raise WorkspaceFileError(self.path, f"cannot read: {exc.strerror or exc}") from exc
        try:
            return loads_workspace(raw, self.path)
        except WorkspaceFileError as exc:
            backup = _backup(self.path, "unreadable")
            self.read_only_reason = exc.reason
            err_cls = type(exc)
            raise err_cls(self.path, exc.reason, backup) from exc

    def move_aside(self) -> Path | None:
        """Move a file that could not be read out of the way (the operator starts a new layout): it is
        renamed to a backup (or removed when an identical backup already exists), and the store saves
        normally again. Returns where the old content is kept (None when there was no file)."""
        try:
            content = self.path.read_bytes()
        except FileNotFoundError:
            self.read_only_reason = None
            return None
        kept = _same_backup(self.path, "unreadable", content)
        if kept is not None:
            self.path.unlink()
        else:
            kept = _backup(self.path, "unreadable")
            if kept is not None:
                self.path.unlink()
        self.read_only_reason = None
        return kept

    def save(self, ws: Workspace, *, force: bool = False) -> None:
        """Write the workspace atomically. Refuses (WorkspaceFileError) while read-only unless ``force``."""
        if self.read_only and not force:
            raise WorkspaceFileError(
                self.path, f"not saving over a file that could not be read ({self.read_only_reason})"
            )
        atomic_write(self.path, dumps_workspace(ws))
        self.read_only_reason = None


def export_canvas(canvas: Canvas, path: str | os.PathLike[str]) -> None:
    """Write one canvas to its own file (atomically)."""
    data = {"format": CANVAS_FORMAT, "version": VERSION, "canvas": _CONV.unstructure(canvas)}
    atomic_write(path, json.dumps(data, indent=2, ensure_ascii=False) + "\n")


def import_canvas(path: str | os.PathLike[str]) -> Canvas:
    """Read a canvas file written by :func:`export_canvas`. Add it with ``Document.add_canvas``."""
    p = Path(path)
    try:
        data = json.loads(p.read_bytes())
    except FileNotFoundError:
        raise WorkspaceFileError(p, "no such file") from None
    except OSError as exc:  # a directory, no permission...
        raise WorkspaceFileError(p, f"cannot read: {exc.strerror or exc}") from exc
    except (ValueError, UnicodeDecodeError) as exc:
        raise WorkspaceFileError(p, f"not valid JSON ({exc})") from exc
    _check_header(data, CANVAS_FORMAT, p)
    try:
        return _CONV.structure(data.get("canvas"), Canvas)
    except Exception as exc:
        raise WorkspaceFileError(p, f"invalid canvas: {_describe(exc, 'canvas')}") from exc
