"""``rcon plugins`` (installed widget packages and their widgets) and ``rcon match`` (which widgets fit).

``rcon plugins install WHEEL`` / ``rcon plugins remove NAME`` / ``rcon plugins folder``: a lab's widget
package in the app's plugins folder (the installed one-folder app has no pip; see
:mod:`rcon_core.plugins.folder`)."""

from __future__ import annotations

import argparse
import asyncio
import json
import sys
from typing import Any

from rcon_core.plugins.manager import PluginStatus
from rcon_core.plugins.spec import Role


def configure(name: str, parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--json", action="store_true", help="print JSON instead of text")
    parser.add_argument(
        "--disable", action="append", default=[], metavar="NAME", help="do not load this plugin (repeatable)"
    )
    if name == "plugins":
        parser.add_argument("--check", action="store_true",
                            help="exit 1 when a plugin failed, naming each and why (for a package's CI)")
        parser.add_argument("action", nargs="?", choices=["install", "remove", "folder"],
                            help="install WHEEL into the app's plugins folder, remove NAME from it, or print "
                            "where the folder is (the installed app, or RCON_PLUGINS_DIR)")
        parser.add_argument("target", nargs="?", metavar="WHEEL|NAME")
    if name == "match":
        parser.add_argument("type", help="message or service type, e.g. sensor_msgs/BatteryState")
        parser.add_argument(
            "--role",
            default=None,
            choices=[r.value for r in Role],
            help="how the widget is bound (default: subscribe for messages, call for services)",
        )
        parser.add_argument("--url", help="fetch the type's definition from this rosbridge server (rosapi)")
        parser.add_argument("--ros2", action="store_true", help="use ROS 2 standard definitions")
        parser.add_argument("--timeout", type=float, default=5.0, help="seconds to wait for the server")


def run(name: str, args: argparse.Namespace) -> int:
    from rcon_core.plugins import PluginManager

    if name == "plugins" and args.action:
        return _folder_action(args)
    pm = PluginManager(disabled=args.disable)
    pm.load_entry_points()
    if name == "plugins":
        return _plugins(pm, args)
    return _match(pm, args)


def _plugins(pm: Any, args: argparse.Namespace) -> int:
    from rcon_core.msgs import TypeRegistry

    types = TypeRegistry.standard()
    pm.apply_types(types)  # a contributed definition that does not parse fails its plugin
    infos = pm.plugins
    status = _check(pm, types) if args.check else 0
    if args.json:
        print(json.dumps({"plugins": [i.to_dict() for i in infos]}, indent=2))
        return status
    if not infos:
        print("no widget plugins installed (entry-point group 'rcon.widgets')")
        return status
    for info in infos:
        head = f"{info.dist or info.name} {info.version}".strip()
        origin = f"(entry point {info.name!r} -> {info.value})"
        if info.status is PluginStatus.FAILED:
            print(f"{head} {origin}: FAILED: {info.error}")
            continue
        if info.status is PluginStatus.DISABLED:
            print(f"{head} {origin}: disabled")
            continue
        print(f"{head} {origin}: {len(info.widgets)} widget(s)")
        for spec in info.widgets:
            roles = ",".join(sorted(r.value for r in spec.roles))
            accepts = " ".join(spec.accepts.describe()) or "-"
            print(f"  {spec.kind:<24} {spec.title:<20} {roles:<28} {accepts}")
        for d in info.types:
            print(f"  type {d.name} ({d.kind})")
        for t in info.templates:
            print(f"  template {t.title!r} ({t.path.name})")
        for problem in info.problems:
            print(f"  problem: {problem}")
    return status


def _folder_action(args: argparse.Namespace) -> int:
    from pathlib import Path

    from rcon_core.plugins import folder

    root = folder.plugins_dir()
    if root is None:
        print("rcon plugins: this RCON is a pip installation, which has no plugins folder: `pip install WHEEL` "
              f"adds a widget package (or set {folder.ENV} to use a folder)", file=sys.stderr)
        return 2
    if args.action == "folder":
        print(root)
        return 0
    if not args.target:
        print(f"rcon plugins {args.action}: give the {'wheel file' if args.action == 'install' else 'name'}",
              file=sys.stderr)
        return 2
    if args.action == "remove":
        try:
            gone = folder.remove(args.target, root)
        except KeyError:
            print(f"rcon plugins remove: {args.target} is not in {root}", file=sys.stderr)
            return 1
        print(f"rcon plugins: removed {gone.name} {gone.version}; restart RCON")
        return 0
    try:
        done = folder.install(Path(args.target), root)
    except folder.PluginInstallError as exc:
        print(f"rcon plugins install: {exc}", file=sys.stderr)
        return 1
    folder.activate(root)  # load it now, the way the app will: a plugin that fails is said at once
    from rcon_core.plugins import PluginManager

    pm = PluginManager(disabled=args.disable)
    pm.load_entry_points()
    mine = [i for i in pm.plugins if i.dist and folder.canonical(i.dist) == done.path.name]
    print(f"rcon plugins: installed {done.name} {done.version} into {done.path}")
    for info in mine:
        if info.status is PluginStatus.FAILED:
            print(f"rcon plugins install: it is installed but fails to load: {info.error}", file=sys.stderr)
            return 1
        kinds = ", ".join(s.kind for s in info.widgets) or "no widgets"
        print(f"  {info.name}: {kinds}; restart RCON to use it")
    return 0


def _check(pm: Any, types: Any) -> int:
    """``--check``: each failed plugin and why on stderr (also a contributed type that does not resolve);
    1 if any failed, else 0."""
    unresolved = pm.type_problems(types)
    for info in pm.plugins:  # withdrawn parts of a loaded plugin (a template file the wheel lacks)
        if info.problems:
            unresolved.setdefault(info.name, []).extend(info.problems)
    for template in pm.canvas_templates():  # a template file must be a usable canvas
        from rcon_core.cli.layout_cmd import check_layout

        problems, _ = check_layout(template.path, pm)
        if problems:
            name = next(i.name for i in pm.plugins if i.package == template.package)
            unresolved.setdefault(name, []).extend(f"template {template.title!r}: {p}" for p in problems)
    failed = [i for i in pm.plugins if i.status is PluginStatus.FAILED or i.name in unresolved]
    for info in failed:
        where = f"{info.dist} {info.version}".strip() or info.value
        why = [info.error] if info.status is PluginStatus.FAILED else unresolved[info.name]
        for reason in why:
            print(f"rcon plugins: plugin {info.name!r} ({where}) failed: {reason}", file=sys.stderr)
    if failed:
        print(f"rcon plugins: {len(failed)} plugin(s) failed", file=sys.stderr)
    return 1 if failed else 0


def _match(pm: Any, args: argparse.Namespace) -> int:
    from rcon_core.matcher import match
    from rcon_core.msgs import TypeRegistry, names

    try:
        names.split(args.type)
    except ValueError as exc:
        print(f"rcon match: {exc}", file=sys.stderr)
        return 2
    types = TypeRegistry.standard(ros2=args.ros2)
    pm.apply_types(types)
    is_service = "/srv/" in args.type or types.has_service(args.type)
    role = Role.parse(args.role) if args.role else (Role.CALL if is_service else Role.SUBSCRIBE)
    if args.url:
        try:
            asyncio.run(_fetch(args.url, args.type, role, types, args.timeout, args.ros2))
        except Exception as exc:
            print(f"rcon match: could not get the definition of {args.type} from {args.url}: {exc}", file=sys.stderr)
            return 1
    if role.is_service and not types.has_service(args.type):
        known = "" if args.url else " (give --url to ask the robot)"
        print(f"rcon match: note: service type {args.type} is unknown{known}", file=sys.stderr)
    elif not role.is_service and not types.has(args.type):
        known = "" if args.url else " (give --url to ask the robot)"
        print(f"rcon match: note: {args.type} is unknown{known}; only name-based matches", file=sys.stderr)
    found = match(args.type, role, types, pm)
    if args.json:
        print(json.dumps({"type": args.type, "role": role.value, "matches": [m.to_dict() for m in found]}, indent=2))
        return 0
    if not found:
        print(f"no installed widget fits {args.type} ({role.value})")
        return 0
    for m in found:
        path = m.field_path or "(whole message)"
        others = f"  [also: {', '.join(m.field_paths[1:4])}]" if len(m.field_paths) > 1 else ""
        print(f"{m.rank.name.lower():<10} {m.spec.kind:<24} {m.spec.title:<20} {path}{others}")
    return 0


async def _fetch(url: str, type_name: str, role: Role, types: Any, timeout: float, ros2: bool) -> None:
    from rcon_core.bridge import BridgeClient
    from rcon_core.msgs import names

    client = BridgeClient(url, reconnect=False, call_timeout=timeout)
    await asyncio.wait_for(client.connect(), timeout)
    spell = names.normalize if ros2 else names.to_ros1
    try:
        pkg, _kind, typ = names.split(type_name)
        if role.is_service:
            for part, fetch in (
                ("Request", client.rosapi.service_request_details),
                ("Response", client.rosapi.service_response_details),
            ):
                tds = await fetch(spell(f"{pkg}/srv/{typ}"))
                if not tds:
                    raise LookupError(f"the server does not know service type {type_name}")
                types.add_typedefs(tds, root=f"{pkg}/srv/{typ}_{part}")
        else:
            tds = await client.rosapi.message_details(spell(f"{pkg}/msg/{typ}"))
            if not tds:
                raise LookupError(f"the server does not know {type_name}")
            types.add_typedefs(tds, root=f"{pkg}/msg/{typ}")
    finally:
        await client.close()
