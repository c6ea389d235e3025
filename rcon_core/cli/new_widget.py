"""``rcon new-widget PACKAGE --kind NAME [--type pkg/Type] [--role subscribe|publish|call]``: start a
widget package in one command.

Writes a complete distribution into ``./PACKAGE`` (or ``--dir``): ``pyproject.toml`` with the
``rcon.widgets`` entry point, ``plugin.py`` (the hooks; the type's definition when it is not a standard
type; a canvas template shipped as package data), settings and model without Qt, a Qt view, tests against
the embedded robot and of the view, and a README. It installs and its tests pass as generated; the command
then prints the next three commands. The files are :mod:`rcon_core.cli.scaffold`'s templates.

The role: ``subscribe`` shows a number of a message, ``publish`` sends one, ``call`` calls a service with
a request from its settings and shows the answer. Without ``--role`` a service type gets ``call`` (a type
RCON does not ship counts as a service when its package ends in ``_srvs`` or it is spelt ``pkg/srv/X``),
a message type ``subscribe``; a role that does not fit the type is refused, naming the one that does.
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

DIST_RE = re.compile(r"[a-z][a-z0-9]*(-[a-z0-9]+)*")
ROLES = ("subscribe", "publish", "call")


def configure(name: str, parser: argparse.ArgumentParser) -> None:
    parser.add_argument("package", metavar="PACKAGE", help="distribution name, e.g. rcon-lab-winch")
    parser.add_argument("--kind", required=True, metavar="NAME", help="widget kind, e.g. lab.winch")
    parser.add_argument("--type", dest="msg_type", default="std_msgs/Float64", metavar="pkg/Type",
                        help="the message or service type it is bound to (default std_msgs/Float64); a type "
                        "RCON does not ship gets a definition to fill in")
    parser.add_argument("--role", choices=ROLES, default=None,
                        help="subscribe (show a number), publish (send one) or call (call a service and show "
                        "the answer); default: call for a service type, else subscribe")
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
    role = args.role or ("call" if _is_service(args.msg_type) else "subscribe")
    written = write_package(target, args.package, args.kind, args.msg_type, role=role)
    print(f"rcon new-widget: wrote {len(written)} files of {args.package} ({role} {args.msg_type}) in {target}")
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
    if "/action/" in args.msg_type:
        return (f"{args.msg_type} is an action: no template for actions yet (the std package's Action "
                "widget, rcon_widgets_std/action.py, is the worked example)")
    service = _is_service(args.msg_type)
    role = args.role or ("call" if service else "subscribe")
    if service and role != "call":
        return f"{args.msg_type} is a service type: a widget that calls it takes --role call"
    if role == "call" and not service:
        return (f"--role call takes a service type such as std_srvs/SetBool; {args.msg_type} is a message "
                "type (spell a service of your own pkg/srv/Name)")
    if role != "call" and _is_standard(args.msg_type) and not _numeric_path(args.msg_type):
        return f"{args.msg_type} has no numeric field: this template shows a number (pick another --type)"
    return ""


def _is_standard(type_name: str, service: bool = False) -> bool:
    from rcon_core.bridge.typecheck import is_standard

    return is_standard(type_name, service=service)


def _is_service(type_name: str) -> bool:
    """A standard service, one spelt ``pkg/srv/X``, or (neither standard nor spelt) one whose package ends
    in ``_srvs`` (the ROS convention: ``lab_srvs/SetPump`` is a service, ``lab_msgs/Winch`` a message)."""
    if "/srv/" in type_name or _is_standard(type_name, service=True):
        return True
    if "/msg/" in type_name or _is_standard(type_name):
        return False
    return type_name.split("/")[0].endswith("_srvs")


def _numeric_path(type_name: str) -> str:
    from rcon_core.matcher import candidate_paths
    from rcon_core.msgs import TypeRegistry
    from rcon_core.plugins import Accepts, Role, WidgetSpec

    spec = WidgetSpec(kind="new.widget", title="x", model="x:y", accepts=Accepts(fields=["numeric"]))
    paths = candidate_paths(spec, Role.SUBSCRIBE, type_name, TypeRegistry.standard())
    return paths[0] if paths else ""


#: what a widget of each role does, in words (README, spec description)
WHAT = {
    "subscribe": "shows a number of `{type}` (the field RCON binds, or the one the operator picks) with a unit",
    "publish": "sends a number as `{type}` (at the field RCON binds, or the one the operator picks)",
    "call": "calls a `{type}` service with a request from its settings and shows the answer",
}
#: the definition a package contributes for a type RCON does not ship: (kind of type, extension, text)
DEFINITIONS = {
    "msg": ("message", "msg", "float64 value\\n"),
    "srv": ("service", "srv", "float64 value\\n---\\nbool success\\nstring message\\n"),
}


def write_package(target: Path, dist: str, kind: str, msg_type: str, role: str = "subscribe") -> list[Path]:
    """Write the package's files under ``target``; returns them."""
    import json

    from rcon_core.plugins.api import API_VERSION

    from . import scaffold

    module = dist.replace("-", "_")
    last = kind.split(".")[-1]
    cls = "".join(p.capitalize() for p in re.split(r"[_-]", last) if p) or "My"
    call = role == "call"
    standard = _is_standard(msg_type, service=call)
    kind_word, ext, definition = DEFINITIONS["srv" if call else "msg"]
    path = "" if call else (_numeric_path(msg_type) if standard else "value")
    what = WHAT[role].format(type=msg_type)
    values = {
        "dist": dist, "module": module, "kind": kind, "cls": cls, "title": cls, "type": msg_type,
        "ep": module, "role": role, "role_upper": role.upper(), "what": what,
        "what_cap": what[0].upper() + what[1:].replace("`", ""), "path": path,
        "name": f"/{last}/{'set' if call else 'value'}", "field_paths": json.dumps([path] if path else []),
        "accepts": "types=[TYPE]" if call else 'types=[TYPE], fields=["numeric"]',
        "robot_part": "provides the service" if call else ("listens on the topic" if role == "publish"
                                                           else "publishes on the topic"),
        "types_hook": "" if standard else scaffold.TYPES_HOOK.format(type=msg_type, kind_word=kind_word, ext=ext,
                                                                     definition=definition),
        "types_note": "" if standard else f" and the definition of `{msg_type}` (fill in your own)",
        "api_version": API_VERSION,
    }
    written: list[Path] = []
    for rel, text in scaffold.files_for(role).items():
        out = target / rel.format(**values)
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(text.format(**values), encoding="utf-8")
        written.append(out)
    return written
