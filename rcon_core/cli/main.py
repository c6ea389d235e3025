"""The ``rcon`` command: the app by default, plus subcommands over the bridge, the sim and the plugins.

Each subcommand lives in its own module, imported only when that subcommand runs, so ``rcon topics``
never pays for Qt and ``rcon`` (the app) never pays for the CLI helpers.  A command module exposes
``configure(name, parser)`` and ``run(name, args) -> int``.
"""

from __future__ import annotations

import argparse
import importlib
import sys

#: subcommand -> (module, one-line help)
COMMANDS: dict[str, tuple[str, str]] = {
    "sim": ("rcon_core.cli.sim_cmd", "run the embedded simulated robot (a rosbridge v2 server)"),
    "topics": ("rcon_core.cli.bridge_cmds", "list the robot's topics and their types"),
    "services": ("rcon_core.cli.bridge_cmds", "list the robot's services and their types"),
    "type": ("rcon_core.cli.bridge_cmds", "print a message or service type's definition"),
    "echo": ("rcon_core.cli.bridge_cmds", "print messages arriving on a topic"),
    "pub": ("rcon_core.cli.bridge_cmds", "publish a message on a topic"),
    "call": ("rcon_core.cli.bridge_cmds", "call a service"),
    "info": ("rcon_core.cli.info_cmd", "which ROS the robot runs (version, distro) and its rosbridge capabilities"),
    "plugins": ("rcon_core.cli.plugin_cmds", "list installed widget packages and their widgets"),
    "match": ("rcon_core.cli.plugin_cmds", "list the widgets that fit a type and role, ranked"),
    "new-widget": ("rcon_core.cli.new_widget", "write a new widget package (pyproject, plugin, model, view, tests)"),
    "record": ("rcon_core.cli.record_cmd", "record a robot's topics to an MCAP file (or mend one cut short)"),
    "layout": ("rcon_core.cli.layout_cmd", "check a layout file (rcon layout validate FILE) or print its schema"),
}


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="rcon",
        description="RCON: build a robot's operator interface at run time over rosbridge. "
        "Without a subcommand, opens the app.",
    )
    parser.add_argument("--url", help="rosbridge WebSocket URL to connect to (default: last used)")
    parser.add_argument("--layout", help="layout file to open instead of the saved workspace")
    parser.add_argument("--demo", action="store_true", help="start the embedded robot and open the demo layout")
    parser.add_argument("--robots", type=int, metavar="N",
                        help="with --demo: start N embedded vessels (boat1..boatN, each its own sim on its own "
                        "port) and open the fleet canvas: every vessel's camera and teleop pad, one map")
    parser.add_argument("--reset-layout", action="store_true",
                        help="with --demo: replace the saved demo layout by a fresh one")
    parser.add_argument("--locked", action="store_true",
                        help="kiosk: start full screen with the operator lock on (needs an operator PIN)")
    parser.add_argument("--canvas", metavar="FILE|TEMPLATE",
                        help="open this canvas file (rcon-canvas, as Export canvas writes it) or an installed "
                        "plugin's template by its title, in a workspace of its own (nothing is saved)")
    parser.add_argument("--play", metavar="FILE",
                        help="open a recording as the robot (an .mcap file, a rosbag1 .bag or a rosbag2 folder), "
                        "with a timeline to play, pause, change speed and seek; commands go nowhere")
    parser.add_argument("--screenshot", metavar="PATH", help="write a PNG of the window, then exit")
    parser.add_argument("--window-size", metavar="WxH", help="the window's size, e.g. 1024x600 (with --screenshot: "
                        "the picture's size)")
    parser.add_argument("--quit-after", type=float, metavar="SECONDS", help="quit after this many seconds")
    from rcon_core.cli.link_options import add_link_options

    add_link_options(parser)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, (module, help_text) in COMMANDS.items():
        p = sub.add_parser(name, help=help_text, description=help_text)
        try:
            mod = importlib.import_module(module)
        except ImportError as exc:  # a command whose module is missing must not break the others
            p.set_defaults(command_unavailable=f"{name}: unavailable ({exc})")
            continue
        mod.configure(name, p)
    return parser


def main(argv: list[str] | None = None) -> int:
    from rcon_core.plugins.folder import activate

    activate()  # the app's plugins folder (the installed bundle, or RCON_PLUGINS_DIR): its widget packages
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command is None:
        from rcon_core.app.main import run_app

        return run_app(args)
    if getattr(args, "command_unavailable", None):
        print(args.command_unavailable, file=sys.stderr)
        return 2
    module = importlib.import_module(COMMANDS[args.command][0])
    try:
        return int(module.run(args.command, args) or 0)
    except BrokenPipeError:  # the reader went away (`rcon type X | head`): stop quietly, as `head` means
        _silence_stdout()
        return 0


def _silence_stdout() -> None:
    """Point stdout at the null device, so the interpreter's last flush does not fail again."""
    import os

    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, sys.stdout.fileno())
    os.close(devnull)


if __name__ == "__main__":
    raise SystemExit(main())
