"""``rcon layout validate FILE``: is a layout file (a workspace, or one exported canvas) usable here?

Reads the file with the store's own loaders (``loads_workspace``, ``import_canvas``: exactly what the
app does), then checks each widget against the installed plugins: its kind is installed, it may take its
binding's role, its binding is complete (and names a robot the workspace has) and its settings are
configured. Where the type is known here (a standard type, or one an installed plugin contributes) the
widget must fit it (what ``rcon match`` offers) and each field path must be a field of it that the widget
can show; a type of a package RCON ships that it does not know is a misspelling. A type of another
package cannot be checked without the robot, and is not a problem. Prints one line per problem
and exits 1, or prints a summary and exits 0. The format is described in ``docs/layout-format.md`` and
by the JSON Schema shipped in the package (``rcon layout schema`` prints it).
"""

from __future__ import annotations

import argparse
import json
import sys
from importlib.resources import files
from pathlib import Path
from typing import Any

SCHEMA = "layout.schema.json"


def configure(name: str, parser: argparse.ArgumentParser) -> None:
    actions = parser.add_subparsers(dest="layout_action", metavar="ACTION", required=True)
    validate = actions.add_parser("validate", help="list the problems of a layout file; exit 1 if any")
    validate.add_argument("file", metavar="FILE", help="a workspace (rcon-workspace) or canvas (rcon-canvas) file")
    validate.add_argument("--json", action="store_true", help="print JSON instead of text")
    actions.add_parser("schema", help="print the JSON Schema of layout files")


def schema_text() -> str:
    """The JSON Schema of layout files, as shipped in the package."""
    return files("rcon_core.canvas").joinpath(SCHEMA).read_text(encoding="utf-8")


def run(name: str, args: argparse.Namespace) -> int:
    if args.layout_action == "schema":
        print(schema_text(), end="")
        return 0
    from rcon_core.plugins import PluginManager

    pm = PluginManager()
    pm.load_entry_points()
    path = Path(args.file)
    problems, summary = check_layout(path, pm)
    if args.json:
        print(json.dumps({"file": str(path), "ok": not problems, "problems": problems, "summary": summary},
                         indent=2))
    elif problems:
        for p in problems:
            print(f"{path}: {p}", file=sys.stderr)
    else:
        print(f"{path}: OK ({summary})")
    return 1 if problems else 0


def check_layout(path: Path, pm: Any) -> tuple[list[str], str]:
    """(problems, summary) for the layout file at ``path``; no problems means the app can use it as is."""
    from rcon_core.canvas import WorkspaceFileError, import_canvas, loads_workspace

    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        return ["no such file"], ""
    except OSError as exc:
        return [f"cannot read: {exc.strerror or exc}"], ""
    try:
        head = json.loads(raw)
    except (ValueError, UnicodeDecodeError) as exc:
        return [f"not valid JSON ({exc})"], ""
    except RecursionError:
        return ["not valid JSON (nested too deeply)"], ""
    fmt = head.get("format") if isinstance(head, dict) else None
    try:
        if fmt == "rcon-canvas":
            canvases = [import_canvas(path)]
            current = canvases[0].id
            robot_ids = None  # a canvas file's robots are the workspace's it is added to
        else:
            ws = loads_workspace(raw, path)
            canvases, current = ws.canvases, ws.current
            robot_ids = {r.id for r in ws.robots}
    except WorkspaceFileError as exc:
        return [exc.reason], ""
    except (RecursionError, ValueError) as exc:  # whatever the store lets through is still a problem
        return [f"cannot be read: {type(exc).__name__}: {str(exc)[:200]}"], ""
    problems: list[str] = []
    types = pm.type_registry()
    if fmt != "rcon-canvas" and current and current not in {c.id for c in canvases}:
        problems.append(f"current canvas {current!r} is not one of the canvases")
    widgets = 0
    for canvas in canvases:
        for w in canvas.widgets:
            widgets += 1
            where = f"canvas {canvas.name!r}, widget {w.id} ({w.kind})"
            problems += [f"{where}: {p}" for p in _widget_problems(w, pm, types)]
            if robot_ids is not None and w.binding.robot and w.binding.robot not in robot_ids:
                problems.append(f"{where}: robot {w.binding.robot!r} is not in this workspace")
    summary = f"{len(canvases)} canvas{'es' if len(canvases) != 1 else ''}, {widgets} widget{'s' if widgets != 1 else ''}"
    return problems, summary


def _widget_problems(w: Any, pm: Any, types: Any) -> list[str]:
    from rcon_core.plugins.api import stored_settings_problems

    out: list[str] = []
    g = w.geometry
    if not (g.w > 0 and g.h > 0):
        out.append(f"geometry: width and height must be more than 0 (got {g.w:g} x {g.h:g})")
    if not pm.has_widget(w.kind):
        return [*out, "no installed widget plugin offers this kind (`rcon plugins` lists them)"]
    spec = pm.widget(w.kind)
    if w.binding.role not in spec.roles:
        can = ", ".join(sorted(r.value for r in spec.roles))
        out.append(f"{spec.title} cannot {w.binding.role.value} (it can: {can})")
    out += w.binding.problems()
    if not w.binding.problems() and w.binding.role in spec.roles:
        out += _type_problems(w.binding, spec, pm, types)
    try:
        out += stored_settings_problems(spec, w.settings, pm)
    except Exception as exc:  # a plugin's problems() that raises is reported, not fatal
        out.append(f"settings could not be checked: {type(exc).__name__}: {exc}")
    return out


def _standard_packages() -> set[str]:
    from rcon_core.msgs import TypeRegistry

    return {n.split("/")[0] for ros2 in (False, True) for n in TypeRegistry.standard(ros2=ros2).names()}


def _type_problems(b: Any, spec: Any, pm: Any, types: Any) -> list[str]:
    """Whether the widget fits its binding's type and fields (see the module docstring)."""
    from rcon_core.matcher import match
    from rcon_core.msgs import names
    from rcon_core.plugins import PathError, get_path
    from rcon_core.plugins.paths import split_service_path

    role = b.role
    if role.is_action:
        return []  # actions are matched on the robot's definitions; nothing here to check them against
    try:
        pkg = names.split(b.type)[0]
    except ValueError as exc:
        return [f"type {b.type!r}: {exc}"]
    known = types.has_service(b.type) if role.is_service else types.has(b.type) and not types.has_service(b.type)
    if not known:
        if pkg in _standard_packages():
            what = "service" if role.is_service else "message"
            return [f"unknown {what} type {b.type}: {pkg} has no such {what} (misspelt?)"]
        return []
    fits = [m for m in match(b.type, role, types, pm) if m.kind == spec.kind]
    if not fits:
        return [f"{spec.title} cannot show {b.type} ({role.value}): `rcon match {b.type} --role {role.value}` "
                "lists the widgets that can"]
    out = []
    can = [p for p in fits[0].field_paths if p]
    for path in b.field_paths:
        if not path:
            continue
        try:
            if role.is_service:
                part, rest = split_service_path(path)
                get_path(types.default(types.service_part_name(b.type, part)), rest)
            else:
                get_path(types.default(b.type), path)
        except PathError as exc:
            out.append(f"field {path!r}: {exc}")
            continue
        if can and path not in can:
            listed = ", ".join(can[:6]) + (", ..." if len(can) > 6 else "")
            out.append(f"{spec.title} cannot show field {path!r} of {b.type} (it can: {listed})")
    return out
