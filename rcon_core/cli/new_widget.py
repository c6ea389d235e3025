"""``rcon new-widget PACKAGE --kind NAME [--type pkg/Msg]``: start a widget package in one command.

Writes a complete distribution into ``./PACKAGE`` (or ``--dir``): ``pyproject.toml`` with the
``rcon.widgets`` entry point, ``plugin.py`` (the hooks; the type's definition when it is not a standard
type), settings and model without Qt, a Qt view, tests against the embedded robot and of the view, and a
README. It installs and its tests pass as generated; the command then prints the next three commands.
The files are :mod:`rcon_core.cli.scaffold`'s templates.
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

DIST_RE = re.compile(r"[a-z][a-z0-9]*(-[a-z0-9]+)*")


def configure(name: str, parser: argparse.ArgumentParser) -> None:
    parser.add_argument("package", metavar="PACKAGE", help="distribution name, e.g. rcon-lab-winch")
    parser.add_argument("--kind", required=True, metavar="NAME", help="widget kind, e.g. lab.winch")
    parser.add_argument("--type", dest="msg_type", default="std_msgs/Float64", metavar="pkg/Msg",
                        help="the message type it shows (default std_msgs/Float64); a type RCON does not "
                        "ship gets a definition to fill in")
    parser.add_argument("--dir", metavar="DIR", help="where to write the package (default ./PACKAGE)")


def run(name: str, args: argparse.Namespace) -> int:
    problem = _check(args)
    if problem:
        print(f"rcon new-widget: {problem}", file=sys.stderr)
        return 2
    target = Path(args.dir) if args.dir else Path(args.package)
    if target.exists() and any(target.iterdir()):
        print(f"rcon new-widget: {target} exists and is not empty; nothing was written", file=sys.stderr)
        return 1
    written = write_package(target, args.package, args.kind, args.msg_type)
    print(f"rcon new-widget: wrote {len(written)} files of {args.package} in {target}")
    print("next:")
    print(f"  cd {target} && pip install -e \".[test]\"")
    print("  pytest")
    print(f"  rcon plugins --check && rcon match {args.msg_type}")
    return 0


def _check(args: argparse.Namespace) -> str:
    from rcon_core.msgs import names
    from rcon_core.plugins import Accepts, SpecError, WidgetSpec

    if not DIST_RE.fullmatch(args.package):
        return f"PACKAGE {args.package!r} must be a lowercase distribution name like rcon-lab-winch"
    try:
        WidgetSpec(kind=args.kind, title="x", model="x:y", accepts=Accepts(types=[args.msg_type]))
        names.split(args.msg_type)
    except (SpecError, ValueError) as exc:
        return str(exc)
    if "/srv/" in args.msg_type or "/action/" in args.msg_type:
        return f"--type must be a message type, got {args.msg_type!r}"
    if _is_standard(args.msg_type) and not _numeric_path(args.msg_type):
        return f"{args.msg_type} has no numeric field: this template shows a number (pick another --type)"
    return ""


def _is_standard(type_name: str) -> bool:
    from rcon_core.bridge.typecheck import is_standard

    return is_standard(type_name)


def _numeric_path(type_name: str) -> str:
    from rcon_core.matcher import candidate_paths
    from rcon_core.msgs import TypeRegistry
    from rcon_core.plugins import Accepts, Role, WidgetSpec

    spec = WidgetSpec(kind="new.widget", title="x", model="x:y", accepts=Accepts(fields=["numeric"]))
    paths = candidate_paths(spec, Role.SUBSCRIBE, type_name, TypeRegistry.standard())
    return paths[0] if paths else ""


def write_package(target: Path, dist: str, kind: str, msg_type: str) -> list[Path]:
    """Write the package's files under ``target``; returns them."""
    from . import scaffold

    module = dist.replace("-", "_")
    last = kind.split(".")[-1]
    cls = "".join(p.capitalize() for p in re.split(r"[_-]", last) if p) or "My"
    standard = _is_standard(msg_type)
    values = {
        "dist": dist, "module": module, "kind": kind, "cls": cls, "title": cls, "type": msg_type,
        "ep": module,
        "types_hook": "" if standard else scaffold.TYPES_HOOK.format(type=msg_type),
        "types_note": "" if standard else f" and the definition of `{msg_type}` (fill in your own)",
    }
    written = []
    for rel, text in scaffold.FILES.items():
        path = target / rel.format(**values)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text.format(**values), encoding="utf-8")
        written.append(path)
    return written
