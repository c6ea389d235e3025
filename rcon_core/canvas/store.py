"""Saving and loading workspaces: versioned JSON, atomic writes, backups, canvas import/export.

File layout (``version`` 2)::

    {"format": "rcon-workspace", "version": 2, "current": "c-...",
     "robots": [{"id", "name", "url", "ca_file", "client_cert", "client_key", "auth", "view_only",
       "colour", "envelope" (written only when set: {"max_linear", "max_angular"})}],
     "canvases": [{"id", "name", "locked", "view_only" (written only when true), "widgets": [{"id",
       "kind", "title", "binding": {"name", "type", "role", "field_paths", "robot"}, "geometry": {"x",
       "y", "w", "h"}, "settings": {...}}]}],
     "plugin_settings": {"kind": {...}}}

A single canvas exported to a file is ``{"format": "rcon-canvas", "version": 2, "canvas": {...}}``.

Versions: 1 had no ``robots`` and no ``binding.robot`` (one robot, whose URL the app kept). It migrates
to one robot, :data:`~rcon_core.canvas.robots.DEFAULT_ROBOT_ID` named "Robot" with URL ``""`` (the
connection bar's URL), and every binding talks to it (``robot`` ``""`` = the first robot). A version 2
file without robots gets the same one robot.
Keys this version does not know are kept and written back, so a newer minor addition survives a
round trip; a widget whose plugin is missing keeps its settings byte for byte.

Writes are atomic (see :mod:`rcon_core.canvas.files`): a temp file in the same directory, fsync,
``os.replace``; a symlinked layout stays a link and its target is written, keeping its mode. Temp files
left by a writer that died mid-save are removed when a store is opened (only stale, unlocked ones).

A file that cannot be read raises :class:`WorkspaceFileError` -- whatever the reason: corrupt JSON,
nesting deeper than :data:`~rcon_core.canvas.checks.MAX_DEPTH`, a number that is not finite (``NaN``,
``Infinity``, ``1e999``) or a coordinate out of range, a boolean that is not ``true``/``false``, a wrong
type, duplicate ids, a newer format. The message names the canvas, the widget and the key and says what
was found. The file is copied to a backup next to it (one copy per distinct content: reading the same
bad file again keeps no second copy) and the store then refuses to overwrite it (``store.read_only``)
until ``save(force=True)`` or until :meth:`WorkspaceStore.move_aside` moved it out of the way (the
operator chose to start a new layout). A workspace that cannot be written as strict JSON (a non-finite
number or a too deep structure in some settings) is refused by ``save`` with a WorkspaceFileError and
nothing on disk changes.

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

import collections
import contextlib
import gc
import json
import logging
import os
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import attrs
import cattrs
import cattrs.gen
import cattrs.v

from rcon_core.bridge.envelope import Envelope
from rcon_core.plugins.api import Binding, Role

from . import checks
from .files import atomic_write, backup, clean_stale_temps, real_path, same_backup
from .robots import Robot, default_robot
from .workspace import Canvas, Geometry, WidgetInstance, Workspace

log = logging.getLogger(__name__)

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
VERSION = 2


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


def _split_extra(known: frozenset[str], data: Any, where: str) -> tuple[dict[str, Any], dict[str, Any]]:
    if not isinstance(data, dict):
        raise ValueError(f"{where} must be an object, found {checks.found(data)}")
    return {k: v for k, v in data.items() if k in known}, {k: v for k, v in data.items() if k not in known}


_ROLES = {r.value: r for r in Role}  # the saved spelling, looked up without Role.parse (20k widgets)


def _make_converter() -> cattrs.Converter:
    conv = cattrs.Converter(forbid_extra_keys=False)

    def unstructure_binding(b: Binding) -> dict[str, Any]:
        return {"name": b.name, "type": b.type, "role": b.role.value, "field_paths": list(b.field_paths),
                "robot": b.robot}

    def structure_binding(data: Any, _t: Any) -> Binding:
        if not isinstance(data, dict):
            raise ValueError("binding must be an object")
        paths = data.get("field_paths", ())
        if not isinstance(paths, (list, tuple)) or not all(isinstance(p, str) for p in paths):
            raise ValueError(f"binding.field_paths must be a list of strings, found {checks.found(paths)}")
        for key in ("name", "type", "role", "robot"):
            checks.strict_str(data.get(key, ""), f"binding.{key}")
        role: str = data.get("role", "subscribe")  # checked a str above
        return Binding(data.get("name", ""), data.get("type", ""), _ROLES.get(role, role), tuple(paths),
                       data.get("robot", ""))

    conv.register_unstructure_hook(Binding, unstructure_binding)
    conv.register_structure_hook(Binding, structure_binding)

    def structure_geometry(data: Any, _t: Any) -> Geometry:
        if not isinstance(data, dict):
            raise ValueError("geometry must be an object with x, y, w, h")
        default = Geometry()
        vals = {k: checks.coordinate(data.get(k, getattr(default, k)), f"geometry.{k}", size=k in "wh")
                for k in ("x", "y", "w", "h")}
        return Geometry(**vals)

    conv.register_structure_hook(Geometry, structure_geometry)
    # strict scalars: cattrs would turn "no" into True and 5 into "5"
    conv.register_structure_hook(bool, lambda v, _t: checks.strict_bool(v))
    conv.register_structure_hook(str, lambda v, _t: checks.strict_str(v))

    def structure_settings(data: Any, _t: Any) -> dict[str, Any]:
        if not isinstance(data, dict):
            raise ValueError("settings must be an object")
        return data  # kept as-is: only the widget's plugin interprets it

    conv.register_structure_hook_func(lambda t: t == dict[str, Any], structure_settings)

    def structure_envelope(data: Any, _t: Any) -> Envelope | None:
        return None if data is None else Envelope.from_dict(data)  # ValueError says what is wrong

    conv.register_structure_hook(Envelope | None, structure_envelope)
    conv.register_unstructure_hook(Envelope, lambda env: env.to_dict())

    def with_extra(cls: type, order: tuple[str, ...], optional: tuple[str, ...] = ()) -> None:
        # ``optional`` keys are written only when set (a file without them reads the same)
        base_struct: cattrs.SimpleStructureHook[Any, Any] = cattrs.gen.make_dict_structure_fn(cls, conv)

        names = frozenset(a.name for a in attrs.fields(cls)) - {"extra"}
        what = {"WidgetInstance": "a widget", "Canvas": "a canvas", "Robot": "a robot"}.get(cls.__name__, cls.__name__)

        def structure(data: Any, _t: Any) -> Any:
            known, extra = _split_extra(names, data, what)
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
    with_extra(Robot, ("id", "name", "url", "ca_file", "client_cert", "client_key", "auth", "view_only",
                       "colour", "envelope"), optional=("envelope",))

    return conv


_CONV = _make_converter()


def _format_exc(exc: BaseException, type_: Any) -> str:
    if isinstance(exc, ValueError) and str(exc):
        return str(exc)
    return cattrs.v.format_exception(exc, type_)


def _describe(exc: Exception, root: str = "$", data: Any = None) -> str:
    """Problem sentences: where (canvas, widget, key, named from the raw ``data``) and what was found."""
    if not isinstance(exc, cattrs.BaseValidationError):
        return str(exc)
    problems = []
    for line in cattrs.transform_error(exc, path=root, format_exception=_format_exc):
        text, _, path = line.rpartition(" @ ")
        located = checks.where(path, data) if text else None
        if located is None:
            problems.append(f"{text} at {path}" if text else line)
            continue
        place, key = located
        if key and not text.startswith(key.split(".")[0].split("[")[0]):
            text = f"{key} {text}"  # the message does not name the key itself
        problems.append(f"{place}: {text}")
    return checks.summarize(problems)


def _check_header(data: Any, fmt: str, path: Path | None) -> None:
    if not isinstance(data, dict) or data.get("format") != fmt:
        found = checks.found(data.get("format")) if isinstance(data, dict) else type(data).__name__
        raise WorkspaceFileError(
            path, f"not an RCON {fmt.split('-')[1]} file (format is {found}, expected {fmt!r})"
        )
    version = data.get("version")
    if isinstance(version, bool) or not isinstance(version, int) or version < 1:
        raise WorkspaceFileError(path, f"bad format version {checks.found(version)}")
    if version > VERSION:
        raise NewerVersionError(
            path, f"written by a newer RCON (format version {version}; this version reads up to {VERSION})"
        )


def workspace_to_dict(ws: Workspace) -> dict[str, Any]:
    out: dict[str, Any] = {
        "format": FORMAT,
        "version": VERSION,
        "current": ws.current,
        "robots": [_CONV.unstructure(r) for r in ws.robots],
        "canvases": [_CONV.unstructure(c) for c in ws.canvases],
        "plugin_settings": ws.plugin_settings,
    }
    out.update(ws.extra)
    return out


def workspace_from_dict(data: Any, path: Path | None = None) -> Workspace:
    _check_header(data, FORMAT, path)
    body = {k: v for k, v in data.items() if k not in ("format", "version")}
    try:
        # version 1 had no robots: its one robot (the app's URL) becomes the first robot
        robots = _CONV.structure(body.pop("robots", []), list[Robot]) or [default_robot()]
        for i, r in enumerate(robots):
            if not r.id:
                raise ValueError(f"robot #{i + 1} ({r.name!r}) has no id")
    except Exception as exc:
        raise WorkspaceFileError(path, f"invalid workspace: {_describe(exc, 'robots', data)}") from exc
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
        raise WorkspaceFileError(path, f"invalid workspace: {_describe(exc, 'canvases', data)}") from exc
    counts = collections.Counter(c.id for c in canvases)
    counts.update(w.id for c in canvases for w in c.widgets)
    dup = sorted(i for i, n in counts.items() if n > 1)
    if dup:
        shown = ", ".join(checks.found(i) for i in dup[: checks.MAX_PROBLEMS])
        more = f" and {len(dup) - checks.MAX_PROBLEMS} more" if len(dup) > checks.MAX_PROBLEMS else ""
        raise WorkspaceFileError(path, f"invalid workspace: duplicate ids {shown}{more}")
    robot_dups = sorted(i for i, n in collections.Counter(r.id for r in robots).items() if n > 1)
    if robot_dups:
        raise WorkspaceFileError(path, "invalid workspace: duplicate robot ids "
                                 + ", ".join(checks.found(i) for i in robot_dups[: checks.MAX_PROBLEMS]))
    return Workspace(canvases, current, plugin_settings, body, robots)


def _dumps(data: Any, path: Path | None) -> str:
    """Strict JSON text (what :func:`_loads` reads back), or WorkspaceFileError."""
    try:
        checks.check_tree(data)
        return json.dumps(data, indent=2, ensure_ascii=False, allow_nan=False) + "\n"
    except (ValueError, TypeError, RecursionError) as exc:
        reason = str(exc) if len(str(exc)) <= 200 else str(exc)[:197] + "..."
        raise WorkspaceFileError(path, f"cannot be saved: {reason}") from exc


def _loads(text: str | bytes, path: Path | None) -> Any:
    """Parsed and checked JSON (depth, finite numbers), or WorkspaceFileError -- never anything else."""
    try:
        data = json.loads(text)
    except RecursionError as exc:
        raise WorkspaceFileError(path, f"not a layout: nested deeper than {checks.MAX_DEPTH} levels") from exc
    except (ValueError, UnicodeDecodeError) as exc:
        raise WorkspaceFileError(path, f"not valid JSON ({exc})") from exc
    try:
        checks.check_tree(data)
    except checks.TreeProblem as exc:
        raise WorkspaceFileError(path, f"invalid layout: {_place(exc, data)}") from exc
    return data


def _place(problem: checks.TreeProblem, data: Any) -> str:
    """A tree problem's sentence, its place named after the canvas and widget when it is inside one."""
    path = checks.path_text(problem.path)
    located = checks.where(path, data)
    if located is None:
        return f"{path} {problem.problem}"
    place, key = located
    return f"{place}: {key} {problem.problem}" if key else f"{place}: {problem.problem}"


def dumps_workspace(ws: Workspace) -> str:
    return _dumps(workspace_to_dict(ws), None)


@contextlib.contextmanager
def _gc_paused() -> Iterator[None]:
    """Pause the cycle collector while a layout is built: every object made is kept, so collecting midway
    is wasted work that grows with the layout (20,000 widgets: about 0.7 s instead of 0.45 s)."""
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was_enabled:
            gc.enable()


def loads_workspace(text: str | bytes, path: Path | None = None) -> Workspace:
    """Read a workspace file's text. Raises WorkspaceFileError, and only that, for anything wrong in it."""
    try:
        with _gc_paused():
            return workspace_from_dict(_loads(text, path), path)
    except WorkspaceFileError:
        raise
    except Exception as exc:  # noqa: BLE001 - a file must never crash the app: whatever it is, report it
        raise WorkspaceFileError(path, f"invalid workspace ({type(exc).__name__}: {checks.found(str(exc))})") \
            from exc


class WorkspaceStore:
    """Where the workspace lives on disk. ``path`` defaults to :func:`default_path`."""

    def __init__(self, path: str | os.PathLike[str] | None = None) -> None:
        self.path = Path(path) if path is not None else default_path()
        #: set when the file on disk could not be read: saving would destroy it
        self.read_only_reason: str | None = None
        #: temp files of writers that died mid-save, removed when the store was opened
        self.cleaned: list[Path] = clean_stale_temps(self.path)
        if self.cleaned:
            log.info("removed %d temp file(s) left by an interrupted save of %s", len(self.cleaned), self.path)

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
        except Exception as exc:  # noqa: BLE001 - loads_workspace raises only WorkspaceFileError; be sure
            reason = exc.reason if isinstance(exc, WorkspaceFileError) else f"cannot be read ({type(exc).__name__})"
            self.read_only_reason = reason
            kept = backup(real_path(self.path), "unreadable")  # next to a symlink's target
            err_cls = type(exc) if isinstance(exc, WorkspaceFileError) else WorkspaceFileError
            raise err_cls(self.path, reason, kept) from exc

    def move_aside(self) -> Path | None:
        """Move a file that could not be read out of the way (the operator starts a new layout): it is
        renamed to a backup (or removed when an identical backup already exists), and the store saves
        normally again. Returns where the old content is kept (None when there was no file). A symlink
        stays: its target is moved aside, and the next save writes a new target through the link.

        Raises WorkspaceFileError, and the store stays read-only, when no copy can be kept (a full disk):
        the file is then left where it is, never overwritten without a copy."""
        target = real_path(self.path)
        try:
            content = target.read_bytes()
        except FileNotFoundError:
            self.read_only_reason = None
            return None
        except OSError as exc:
            raise WorkspaceFileError(target, f"cannot read it to keep a copy: {exc.strerror or exc}") from exc
        kept = same_backup(target, "unreadable", content) or backup(target, "unreadable")
        if kept is None:
            raise WorkspaceFileError(target, "no copy of it could be kept (see the log), so it was not moved aside")
        try:
            target.unlink()
        except OSError as exc:
            raise WorkspaceFileError(target, f"cannot move it aside: {exc.strerror or exc}") from exc
        self.read_only_reason = None
        return kept

    def save(self, ws: Workspace, *, force: bool = False) -> None:
        """Write the workspace atomically. Refuses (WorkspaceFileError) while read-only unless ``force``."""
        if self.read_only and not force:
            raise WorkspaceFileError(
                self.path, f"not saving over a file that could not be read ({self.read_only_reason})"
            )
        atomic_write(self.path, _dumps(workspace_to_dict(ws), self.path))
        self.read_only_reason = None


def export_canvas(canvas: Canvas, path: str | os.PathLike[str]) -> None:
    """Write one canvas to its own file (atomically)."""
    data = {"format": CANVAS_FORMAT, "version": VERSION, "canvas": _CONV.unstructure(canvas)}
    atomic_write(path, _dumps(data, Path(path)))


def import_canvas(path: str | os.PathLike[str]) -> Canvas:
    """Read a canvas file written by :func:`export_canvas`. Add it with ``Document.add_canvas``."""
    p = Path(path)
    try:
        raw = p.read_bytes()
    except FileNotFoundError:
        raise WorkspaceFileError(p, "no such file") from None
    except OSError as exc:  # a directory, no permission...
        raise WorkspaceFileError(p, f"cannot read: {exc.strerror or exc}") from exc
    data = _loads(raw, p)
    _check_header(data, CANVAS_FORMAT, p)
    try:
        return _CONV.structure(data.get("canvas"), Canvas)
    except Exception as exc:
        named = {"canvases": [data.get("canvas")]}  # name the canvas and widgets as in a workspace
        raise WorkspaceFileError(p, f"invalid canvas: {_describe(exc, 'canvases[0]', named)}") from exc
