"""``rcon`` without a subcommand: open the app (``--url``, ``--layout``, ``--canvas``, ``--demo [--robots N]``,
``--locked``, ``--screenshot``, ``--window-size``, and the secure-link options ``--ca-file``, ``--client-cert``/``--client-key``,
``--auth-secret-file``)."""

from __future__ import annotations

import contextlib
import signal
import sys
from pathlib import Path
from typing import Any


def load_plugins() -> Any:
    from rcon_core.plugins import PluginManager

    pm = PluginManager()
    pm.load_entry_points()
    for info in pm.failed:
        print(f"rcon: widget plugin {info.name!r} failed to load: {info.error}", file=sys.stderr)
    return pm


@contextlib.contextmanager
def closing_on_signals(windows: list[Any]) -> Any:
    """SIGINT (Ctrl+C in the terminal) and SIGTERM close the window the normal way (widgets stopped,
    layout saved, link closed). ``windows`` is filled once the window exists: a signal that comes
    earlier closes it as soon as the event loop runs. Python runs its signal handlers only when it has
    control, so a timer hands it control a few times a second while Qt's event loop runs."""
    from qtpy import QtCore

    def close_all() -> None:
        for window in windows:  # a signal from a shell closes even a locked window (close_now)
            getattr(window, "close_now", window.close)()

    def handler(_signum: int, _frame: Any) -> None:
        QtCore.QTimer.singleShot(0, close_all)

    previous = {}
    for sig in (signal.SIGINT, signal.SIGTERM):
        try:
            previous[sig] = signal.signal(sig, handler)
        except (ValueError, OSError):  # not the main thread, or the platform lacks the signal
            pass
    tick = QtCore.QTimer()
    tick.timeout.connect(lambda: None)
    tick.start(200)
    try:
        yield
    finally:
        tick.stop()
        for sig, old in previous.items():
            signal.signal(sig, old)


def link_overrides(args: Any) -> Any:
    """The command line's --ca-file, --client-cert/--client-key and secret (``RCON_AUTH_SECRET`` or
    --auth-secret-file) as :class:`~rcon_core.app.link.LinkSettings`; a file that cannot be used raises
    ``LinkSettingsError`` (a ValueError) naming it."""
    from rcon_core.app.link import LinkSettings
    from rcon_core.bridge.secure import read_secret, ssl_context

    ca_file = getattr(args, "ca_file", None)
    cert, key = getattr(args, "client_cert", None), getattr(args, "client_key", None)
    if ca_file or cert or key:
        ssl_context(ca_file, cert, key)
    return LinkSettings(ca_file=ca_file, client_cert=cert, client_key=key,
                        secret=read_secret(getattr(args, "auth_secret_file", None)))


def run_app(args: Any) -> int:
    """Open the window and run until it closes; returns the process exit code."""
    from qtpy import QtCore, QtWidgets

    with contextlib.ExitStack() as stack:
        window = open_app(args, stack)
        if isinstance(window, int):
            return window
        app = QtWidgets.QApplication.instance()
        assert isinstance(app, QtWidgets.QApplication)
        # --screenshot alone: the picture is taken 0.3 s before the 3 s mark (open_app), then the app quits
        quit_after = getattr(args, "quit_after", None) or (3.0 if getattr(args, "screenshot", None) else None)
        if quit_after:
            def quit_now() -> None:  # Qt's quit asks the windows, and a locked one would refuse
                window.close_now()
                app.quit()

            QtCore.QTimer.singleShot(int(quit_after * 1000), quit_now)
        try:
            rc = app.exec()
        finally:
            window.shutdown()
    return int(rc)


def open_app(args: Any, stack: contextlib.ExitStack) -> Any:
    """Everything ``rcon`` does before the event loop runs: check the arguments, build and show the window
    (full screen and locked with ``--locked``), connect. Returns the window, or an exit code (a message was
    printed). What must end with the run (signal handlers, the demo's robot) is entered on ``stack``."""
    from qtpy import QtCore, QtWidgets

    from rcon_core.app import theme
    from rcon_core.app.config import AppConfig
    from rcon_core.app.connection_bar import normalize_url
    from rcon_core.app.link import BadUrl, check_url
    from rcon_core.app.main_window import MainWindow
    from rcon_core.gcpolicy import CollectorPolicy
    from rcon_core.mallocpolicy import keep_big_blocks
    from rcon_core.priority import favour_latency

    url = getattr(args, "url", None)
    if url:
        try:
            url = check_url(normalize_url(url))
        except BadUrl as exc:
            print(f"rcon: {exc}", file=sys.stderr)
            return 2
    try:
        overrides = link_overrides(args)
    except ValueError as exc:
        print(f"rcon: {exc}", file=sys.stderr)
        return 2
    demo = bool(getattr(args, "demo", False))
    if getattr(args, "reset_layout", False) and not demo:
        print("rcon: --reset-layout resets the demo layout; use it with --demo", file=sys.stderr)
        return 2
    robots = getattr(args, "robots", None)
    if robots is not None:
        from rcon_core.app.fleet_demo import check_count

        if not demo:
            print("rcon: --robots starts a fleet of embedded vessels; use it with --demo", file=sys.stderr)
            return 2
        try:
            check_count(robots)
        except ValueError as exc:
            print(f"rcon: {exc}", file=sys.stderr)
            return 2
    # a layout file that cannot be read is reported in the window (and never overwritten)
    layout = Path(args.layout) if getattr(args, "layout", None) else None
    size, canvas = _canvas_options(args, layout)
    if isinstance(size, int):
        return size
    existing = QtWidgets.QApplication.instance()
    if existing is None:  # Qt aborts the process when its platform plugin cannot load: look first
        from rcon_core.app.platform_check import xcb_problem

        problem = xcb_problem()
        if problem:
            print(problem, file=sys.stderr)
            return 1
    app = existing if isinstance(existing, QtWidgets.QApplication) else QtWidgets.QApplication(sys.argv[:1])
    app.setApplicationName("RCON")
    theme.apply(app)
    config = AppConfig()
    locked = bool(getattr(args, "locked", False))
    if locked and config.pin_record is None:
        print("rcon: --locked needs an operator PIN: set one in the app (Canvas ▾ → Operator PIN…) first",
              file=sys.stderr)
        return 2
    plugins = load_plugins()
    if canvas:  # a canvas file or a template (rcon_core/app/open_canvas.py), in a workspace of its own
        from rcon_core.app.open_canvas import CanvasOptionError, canvas_workspace, resolve_canvas

        try:
            layout = canvas_workspace(resolve_canvas(canvas, plugins), stack)
        except CanvasOptionError as exc:
            print(f"rcon: {exc}", file=sys.stderr)
            return 2
    windows: list[Any] = []
    stack.enter_context(closing_on_signals(windows))
    demo_factory = None
    replay: Any = None  # (server, player) of --play FILE
    fleet_urls: list[str] = []
    refit = False  # the fleet demo's layout is new: fill the window's canvas once it is shown
    if demo and robots is not None:
        from rcon_core.app.fleet_demo import connect_fleet, fleet_room, fleet_sims, fleet_workspace

        fleet_urls = [s.url for s in stack.enter_context(fleet_sims(robots))]
        if layout is None:
            layout = config.dir / f"demo-fleet{robots}-workspace.json"
        refit = not layout.exists() or bool(getattr(args, "reset_layout", False))

        def demo_factory() -> Any:
            if not windows:  # built with the window: a tablet's room, laid out again once it is shown
                return fleet_workspace(robots, plugins)
            room, bar = fleet_room(windows[0])  # "Reset demo layout…": the room the window has now
            return fleet_workspace(robots, plugins, room, bar)

    elif getattr(args, "play", None):
        if demo:
            print("rcon: --play opens a recording as the robot; it does not go with --demo", file=sys.stderr)
            return 2
        from rcon_core.record.files import RecordingError
        from rcon_core.sim.playback import played_in_thread

        try:
            replay = stack.enter_context(played_in_thread(args.play))
        except (RecordingError, OSError) as exc:
            print(f"rcon: cannot play {exc}", file=sys.stderr)
            return 2
    elif demo:
        from rcon_core.app.demo import demo_workspace
        from rcon_core.sim import SimServer

        # the embedded robot knows the types installed plugins contribute, as `rcon sim` does: a lab's widget
        # (--canvas its template) is shown on its own type
        server = stack.enter_context(SimServer.in_thread(port=0, plugin_types=True))
        url = server.url
        if getattr(args, "protocol", None) == "foxglove":  # the same vessel over the Foxglove protocol
            from rcon_core.foxglove.gateway import FoxgloveGateway

            url = stack.enter_context(FoxgloveGateway(server.url, name="rcon-demo")).url
        if layout is None:
            layout = config.dir / "demo-workspace.json"

        def demo_factory() -> Any:
            return demo_workspace(plugins)

    favour_latency()  # the GUI thread raised, the GIL's switch interval short (rcon_core/priority.py)
    keep_big_blocks()  # camera frames' pages kept from one frame to the next (rcon_core/mallocpolicy.py)
    # the demo layout is built on its first start only (or when it cannot be read); edits persist
    # the collector's pauses kept short while robots stream (rcon_core/gcpolicy.py)
    # with --canvas: the embedded robot under the canvas given, never the demo's layout
    window = MainWindow(config, plugins, layout_path=layout, demo=None if canvas else demo_factory,
                        collector=CollectorPolicy())
    windows.append(window)
    window.connection.overrides = overrides
    window.link.protocol = getattr(args, "protocol", None)  # --protocol: forced; else found per URL
    if config.read_only_reason:  # one writer per config folder: this one saves nothing (the window says so too)
        print(f"rcon: {config.read_only_reason}: this window opens read-only, nothing changed in it is saved; "
              "set RCON_CONFIG_DIR to another folder to keep separate settings", file=sys.stderr)
    if demo and getattr(args, "reset_layout", False):
        window.reset_demo_layout()
    if locked:  # kiosk: the operator lock on from the start, full screen
        window.operator_lock.engage()
        window.show()  # first shown normally: a first showFullScreen() is not kept on every platform
        window.showFullScreen()
    else:
        if size is not None:
            window.resize(*size)
        window.show()
    if refit:
        window.reset_demo_layout()  # the Fleet canvas fills the screen it opens on
    # the embedded robot's URL is not put in the history: its port is gone after this run. The first robot:
    # --url, else its URL in the layout, else the newest in the history; the others connect to their own
    # URLs (window.fleet_ui)
    if fleet_urls:  # the demo's vessels: run-time URLs, never saved
        connect_fleet(window, fleet_urls)
    elif replay is not None:  # the recording's robot: view-only, its timeline under the connection bar
        window.fleet_ui.recordings.play_first(*replay)
    else:
        window.connect_to(url or window.fleet_ui.first_url() or config.last_url, remember=not demo)
    if getattr(args, "screenshot", None):
        path = Path(args.screenshot)

        def shoot() -> None:
            window.grab().save(str(path), "PNG")
            print(f"rcon: screenshot written to {path}")

        delay = max(0.5, (args.quit_after or 3.0) - 0.3)
        QtCore.QTimer.singleShot(int(delay * 1000), shoot)
    return window


def _canvas_options(args: Any, layout: Path | None) -> tuple[Any, str]:
    """(window size or None, ``--canvas`` or ""), or (an exit code, "") after a line saying why not."""
    from rcon_core.app.open_canvas import CanvasOptionError, layout_is_canvas, parse_window_size

    canvas = getattr(args, "canvas", None) or ""
    if layout is not None and layout_is_canvas(layout):
        print(f"rcon: {layout} is a canvas file (rcon-canvas), not a workspace: open it with --canvas {layout}",
              file=sys.stderr)
        return 2, ""
    if canvas and (layout is not None or getattr(args, "robots", None) is not None):
        print("rcon: --canvas opens one canvas in a workspace of its own: not with --layout or --robots",
              file=sys.stderr)
        return 2, ""
    size = None
    if getattr(args, "window_size", None):
        if getattr(args, "locked", False):
            print("rcon: --locked starts full screen: --window-size does not apply", file=sys.stderr)
            return 2, ""
        try:
            size = parse_window_size(args.window_size)
        except CanvasOptionError as exc:
            print(f"rcon: {exc}", file=sys.stderr)
            return 2, ""
    return size, canvas
