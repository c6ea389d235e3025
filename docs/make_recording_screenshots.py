"""Make the screenshots of docs/recording.md: the app recording the demo robot, then replaying that file.

    python docs/make_recording_screenshots.py [--out docs/screenshots/recording] [--seconds 20]

Starts the embedded robot in a thread, opens the app's window on the demo layout (1280x800, the installed
plugins, a temporary config directory, headless unless QT_QPA_PLATFORM says otherwise), taps ● Rec, drives
the boat with the demo's teleop pad for a while (so the file holds what the operator sent), and saves:

1. ``1-recording.png``: the window while recording (the REC indicator: time and size);
2. ``2-replay.png``: the same layout on that recording played as the robot, seeked to the middle, the
   timeline bar under the connection bar (the teleop controls view-only: commands go nowhere).

The recording itself is kept as ``OUT/demo-run.mcap`` only with ``--keep`` (it is not committed).
"""

from __future__ import annotations

import argparse
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
sys.path.insert(0, str(Path(__file__).resolve().parent))

from make_screenshots import settle, wait_until  # noqa: E402
from qtpy import QtCore, QtWidgets  # noqa: E402
from qtpy.QtTest import QTest  # noqa: E402

SIZE = (1280, 800)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path(__file__).resolve().parent / "screenshots" / "recording")
    parser.add_argument("--seconds", type=float, default=20.0)
    parser.add_argument("--keep", action="store_true")
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    app = QtWidgets.QApplication.instance() or QtWidgets.QApplication(sys.argv[:1])

    from rcon_core.app import theme
    from rcon_core.app.config import AppConfig
    from rcon_core.app.demo import demo_workspace
    from rcon_core.app.main import load_plugins
    from rcon_core.app.main_window import MainWindow
    from rcon_core.bridge import ConnectionState
    from rcon_core.sim import SimServer
    from rcon_core.sim.playback import played_in_thread

    theme.apply(app)
    plugins = load_plugins()
    with tempfile.TemporaryDirectory() as tmp:
        layout = Path(tmp) / "demo.json"
        with SimServer.in_thread(port=0) as sim:
            win = MainWindow(AppConfig(Path(tmp) / "cfg"), plugins, layout_path=layout,
                             demo=lambda: demo_workspace(plugins))
            win.resize(*SIZE)
            win.show()
            win.connect_to(sim.url, remember=False)
            wait_until(lambda: win.connection.state is ConnectionState.CONNECTED, "the demo robot")
            settle(2000)
            control = win.record_control
            control.set_compact(False)  # the offscreen screen is 800 px wide; the picture is of a wide one
            control.directory = Path(tmp) / "rec"
            control.button.click()
            pad = next((h for h in win.host.hosted.values() if h.model.binding.name.endswith("cmd_vel")
                        and h.view is not None), None)
            end = time.monotonic() + args.seconds
            while time.monotonic() < end:  # the operator drives: the pad held to the upper right
                if pad is not None:
                    r = pad.view.rect()
                    QTest.mousePress(pad.view, QtCore.Qt.MouseButton.LeftButton,
                                     pos=QtCore.QPoint(int(r.width() * 0.7), int(r.height() * 0.3)))
                settle(1000)
            settle(300)
            win.grab().save(str(args.out / "1-recording.png"), "PNG")
            if pad is not None:
                QTest.mouseRelease(pad.view, QtCore.Qt.MouseButton.LeftButton)
            settle(300)
            control.button.click()
            files = control.recording.status().files
            win.controller.saver.flush()
            win.shutdown()
            win.deleteLater()
            settle(200)
        recording = files[0]
        print(f"recorded {recording}: {Path(recording).stat().st_size / 1e6:.1f} MB")
        with played_in_thread(recording, paused=True) as (server, player):
            win = MainWindow(AppConfig(Path(tmp) / "cfg2"), plugins, layout_path=layout)
            win.resize(*SIZE)
            win.show()
            bar = win.fleet_ui.recordings.play_first(server, player)
            wait_until(lambda: win.connection.state is ConnectionState.CONNECTED, "the recording's robot")
            settle(1000)
            bar.seek(player.duration / 2)
            bar.player.play()
            settle(3000)
            bar.player.pause()
            settle(500)
            win.grab().save(str(args.out / "2-replay.png"), "PNG")
            print(f"absorbed: {dict(player.absorbed)}")
            win.shutdown()
        if args.keep:
            shutil.copy(recording, args.out / "demo-run.mcap")
    for name in ("1-recording.png", "2-replay.png"):
        print(args.out / name)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
