"""``rcon`` without a subcommand: open the app (``--url``, ``--layout``, ``--demo``, ``--screenshot``)."""

from __future__ import annotations

import contextlib
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


def run_app(args: Any) -> int:
    """Open the window; returns the process exit code."""
    from qtpy import QtCore, QtWidgets

    from rcon_core.app import theme
    from rcon_core.app.config import AppConfig
    from rcon_core.app.link import BadUrl, check_url
    from rcon_core.app.main_window import MainWindow

    url = getattr(args, "url", None)
    if url:
        try:
            check_url(url)
        except BadUrl as exc:
            print(f"rcon: {exc}", file=sys.stderr)
            return 2
    # a layout file that cannot be read is reported in the window (and never overwritten)
    layout = Path(args.layout) if getattr(args, "layout", None) else None
    existing = QtWidgets.QApplication.instance()
    app = existing if isinstance(existing, QtWidgets.QApplication) else QtWidgets.QApplication(sys.argv[:1])
    app.setApplicationName("RCON")
    theme.apply(app)
    plugins = load_plugins()
    config = AppConfig()
    with contextlib.ExitStack() as stack:
        if getattr(args, "demo", False):
            try:
                from rcon_core.sim import SimServer
            except ImportError:  # older trees: the server module directly
                from rcon_core.sim.server import SimServer

            server = stack.enter_context(SimServer.in_thread(port=0))
            url = server.url
            if layout is None:
                layout = config.dir / "demo-workspace.json"
        window = MainWindow(config, plugins, layout_path=layout)
        if getattr(args, "demo", False):
            from rcon_core.app.demo import demo_workspace

            window.open_workspace(demo_workspace(plugins))
        window.show()
        window.connect_to(url or config.last_url)
        if getattr(args, "screenshot", None):
            path = Path(args.screenshot)

            def shoot() -> None:
                window.grab().save(str(path), "PNG")
                print(f"rcon: screenshot written to {path}")

            delay = max(0.5, (args.quit_after or 3.0) - 0.3)
            QtCore.QTimer.singleShot(int(delay * 1000), shoot)
        if getattr(args, "quit_after", None):
            QtCore.QTimer.singleShot(int(args.quit_after * 1000), app.quit)
        try:
            rc = app.exec()
        finally:
            window.shutdown()
    return int(rc)
