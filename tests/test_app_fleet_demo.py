"""The fleet demo (``rcon --demo --robots N``): two embedded vessels on their own ports, one window."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from qtpy import QtCore
from qtpy.QtTest import QTest

from rcon_core.app.config import AppConfig
from rcon_core.app.fleet_demo import connect_fleet, fleet_sims, fleet_workspace
from rcon_core.app.main import load_plugins
from rcon_core.app.main_window import MainWindow
from rcon_core.canvas.runtime import MissingWidgetModel

pytestmark = pytest.mark.usefixtures("qapp")
PACKAGES = ("rcon_widgets_std", "rcon_widgets_sensors", "rcon_widgets_map")
TIMEOUT_MS = 20_000


@pytest.fixture(scope="module")
def plugins():
    for name in PACKAGES:
        pytest.importorskip(name, reason=f"the fleet demo needs the {name} widget package installed")
    return load_plugins()


def test_fleet_workspace_binds_each_vessel_to_its_robot(plugins):
    ws = fleet_workspace(3, plugins)
    assert [(r.id, r.name, r.url) for r in ws.robots] == [("r-1", "boat1", ""), ("r-2", "boat2", ""),
                                                          ("r-3", "boat3", "")]
    fleet = ws.canvases[0]
    assert fleet.name == "Fleet" and [c.name for c in ws.canvases[1:]] == [f"Drive · boat{k}" for k in (1, 2, 3)]
    for k in (1, 2, 3):
        mine = [w for w in fleet.widgets if w.binding.robot == f"r-{k}" and w.kind != "map.gps"]
        assert sorted((w.kind, w.binding.name) for w in mine) == [("sensors.image", "/camera/front/image_raw"),
                                                                  ("sensors.teleop", "/cmd_vel")]
    for canvas in ws.canvases[1:]:
        k = canvas.name[-1]
        for w in canvas.widgets:
            assert w.binding.robot == f"r-{k}", w.title
            assert plugins.widget(w.kind).settings_problems(w.settings) == [], w.title
    (fleet_map,) = [w for w in fleet.widgets if w.kind == "map.gps"]
    assert plugins.widget("map.gps").settings_problems(fleet_map.settings) == []
    assert fleet_map.settings["every_robot"] and fleet_map.settings["fit_all"]  # every vessel, all in view
    with pytest.raises(ValueError, match="from 1 to 6"):
        fleet_workspace(0, plugins)


def test_fleet_demo_shows_each_vessels_camera_and_drives_only_the_pressed_vessel(qtbot, tmp_path, plugins):
    with fleet_sims(2, rate_scale=1.0) as sims:
        window = MainWindow(AppConfig(tmp_path), plugins, layout_path=tmp_path / "fleet.json",
                            demo=lambda: fleet_workspace(2, plugins))
        qtbot.addWidget(window)
        window.resize(1400, 800)
        window.show()
        QTest.qWaitForWindowExposed(window)
        try:
            connect_fleet(window, [s.url for s in sims])
            canvas = window.controller.canvas
            assert canvas.name == "Fleet"
            hosted = {(w.kind, w.binding.robot): window.host.hosted[w.id] for w in canvas.widgets}
            qtbot.waitUntil(lambda: all(h.view is not None for h in hosted.values()), timeout=TIMEOUT_MS)
            for h in hosted.values():
                assert not isinstance(h.model, MissingWidgetModel), h.widget.title
            # each camera shows frames from its own vessel: its sky and the hull colour of its bow
            for k, sim in enumerate(sims, start=1):
                cam = hosted[("sensors.image", f"r-{k}")]
                qtbot.waitUntil(lambda cam=cam: cam.model.state.count >= 3, timeout=TIMEOUT_MS)
                frame = cam.model.state.value
                rgb = frame.rgb  # decoded for the view's size: maybe smaller than the 640x480 source

                def at(x, y, frame=frame, rgb=rgb):  # source pixel (x, y) in the (maybe reduced) array
                    return rgb[int(y * rgb.shape[0] / frame.height), int(x * rgb.shape[1] / frame.width)].astype(int)

                sky = np.asarray(sim.identity.sky[0], dtype=int)
                assert np.abs(at(2, 2) - sky).max() <= 3, (k, at(2, 2), sky)
                assert np.abs(at(260, 470) - sim.identity.hull).max() <= 2, (k, at(260, 470), sim.identity.hull)
                assert cam.view.frame is cam.model.state.value or cam.view.frame is not None
            # the one map shows both vessels' fixes, named after them
            fleet_map = hosted[("map.gps", "r-1")]

            def labels():
                value = fleet_map.model.state.value
                return [t.label for t in value.tracks if t.has_position] if value is not None else []

            qtbot.waitUntil(lambda: labels() == ["boat1", "boat2"], timeout=TIMEOUT_MS)
            # on this mixed canvas each vessel's frame names its vessel; the map of every vessel names none
            cam1 = hosted[("sensors.image", "r-1")]
            qtbot.waitUntil(lambda: fleet_map.frame.property("robotMark") in ("", None), timeout=TIMEOUT_MS)
            assert window.host.title_of(fleet_map.widget) == fleet_map.widget.title == "Map of every vessel"
            assert fleet_map.frame.styleSheet() == ""
            assert window.host.title_of(cam1.widget).startswith("boat1 · ")
            assert cam1.frame.property("robotMark")
            # a press on vessel 2's pad drives vessel 2 only
            pad = hosted[("sensors.teleop", "r-2")].view
            centre, radius = pad.pad()
            c = centre.toPoint()
            QTest.mousePress(pad, QtCore.Qt.MouseButton.LeftButton, pos=c)
            QTest.mouseMove(pad, c - QtCore.QPoint(0, int(radius * 0.9)))
            qtbot.waitUntil(lambda: any(m.get("linear", {}).get("x", 0) > 0.5
                                        for m in sims[1].published("/cmd_vel")), timeout=TIMEOUT_MS)
            qtbot.waitUntil(lambda: sims[1].robot.cmd_surge > 0.5, timeout=TIMEOUT_MS)
            QTest.mouseRelease(pad, QtCore.Qt.MouseButton.LeftButton, pos=c)
            qtbot.waitUntil(lambda: sims[1].robot.cmd_surge == 0.0, timeout=TIMEOUT_MS)
            # vessel 1 got nothing that moves it (its pad may only have sent a stop)
            assert not any(m.get("linear", {}).get("x", 0) for m in sims[0].published("/cmd_vel"))
            assert sims[0].robot.cmd_surge == 0.0 and sims[0].robot.surge == 0.0
        finally:
            window.shutdown()


def test_rcon_demo_robots_opens_and_quits(tmp_path):
    shot = tmp_path / "fleet.png"
    code = ("import sys; from rcon_core.cli.main import main; "
            f"sys.exit(main(['--demo', '--robots', '2', '--screenshot', {str(shot)!r}, '--quit-after', '4']))")
    env = {**__import__("os").environ, "QT_QPA_PLATFORM": "offscreen", "XDG_CONFIG_HOME": str(tmp_path),
           "RCON_CONFIG_DIR": str(tmp_path / "cfg")}
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60, env=env)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert shot.exists() and shot.stat().st_size > 10_000


def test_screenshot_alone_writes_the_picture_then_exits(tmp_path):
    """`rcon --demo --screenshot PATH` says "write a PNG of the window, then exit": it kept running until
    killed unless --quit-after was given too (found running it by hand)."""
    shot = tmp_path / "demo.png"
    code = ("import sys; from rcon_core.cli.main import main; "
            f"sys.exit(main(['--demo', '--screenshot', {str(shot)!r}]))")
    env = {**__import__("os").environ, "QT_QPA_PLATFORM": "offscreen", "XDG_CONFIG_HOME": str(tmp_path),
           "RCON_CONFIG_DIR": str(tmp_path / "cfg")}
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=90, env=env)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert shot.exists() and shot.stat().st_size > 10_000


def test_robots_needs_demo_and_a_sane_count(capsys):
    from rcon_core.cli.main import main

    assert main(["--robots", "2"]) == 2
    assert "use it with --demo" in capsys.readouterr().err
    assert main(["--demo", "--robots", "9"]) == 2
    assert "from 1 to 6" in capsys.readouterr().err
