"""issue 25.6: `rcon --canvas FILE|TEMPLATE` opens one canvas (headless, for a lab's CI screenshot) and
`--window-size WxH` sizes the window; `--layout` given a canvas file says to use --canvas."""

from __future__ import annotations

import os
import subprocess
import sys

import cv2
import pytest

from rcon_core.app.open_canvas import CanvasOptionError, parse_window_size, resolve_canvas
from rcon_core.canvas import Binding, Canvas, Geometry, WidgetInstance, export_canvas
from rcon_core.cli.main import main
from rcon_core.plugins import PluginManager, hookimpl

pytest.importorskip("rcon_widgets_std")


def canvas_file(path):
    widget = WidgetInstance("w-lights", "std.button", Binding("/lights/set", "std_srvs/SetBool", "call"),
                            Geometry(40, 40, 240, 120), settings={"label": "Lights"}, title="Lights")
    export_canvas(Canvas("c-lab", "Lab bench", widgets=[widget]), path)
    return path


@pytest.mark.parametrize("text, size", [("1024x600", (1024, 600)), (" 800X480 ", (800, 480)), ("320x240", (320, 240))])
def test_window_sizes(text, size):
    assert parse_window_size(text) == size


@pytest.mark.parametrize("text, reason", [
    ("1024", "must look like 1024x600"), ("1024x", "must look like"), ("-5x600", "must look like"),
    ("100x100", "is outside 320x240 .. 10000x10000"), ("20000x600", "is outside"),
])
def test_bad_window_sizes(text, reason):
    with pytest.raises(CanvasOptionError, match=reason):
        parse_window_size(text)


class Templates:
    def __init__(self, path):
        self.path = path

    @hookimpl
    def rcon_canvas_templates(self, registry):
        registry.add("Lab  Bench", self.path)


def test_a_template_is_found_by_its_title_and_a_file_by_its_path(tmp_path):
    path = canvas_file(tmp_path / "bench.json")
    pm = PluginManager(environ={})
    pm.register(Templates(path), name="lab")
    assert resolve_canvas(str(path), pm) == path
    assert resolve_canvas("lab bench", pm) == path  # case and spaces aside
    with pytest.raises(CanvasOptionError, match=r"no such file, and no template of that title \(templates: 'Lab  Bench'\)"):
        resolve_canvas("Gripper station", pm)


def test_option_refusals(tmp_path, capsys):
    path = canvas_file(tmp_path / "bench.json")
    assert main(["--layout", str(path)]) == 2
    assert capsys.readouterr().err.strip() == (f"rcon: {path} is a canvas file (rcon-canvas), not a workspace: "
                                               f"open it with --canvas {path}")
    assert main(["--demo", "--robots", "2", "--canvas", str(path)]) == 2
    assert "not with --layout or --robots" in capsys.readouterr().err
    assert main(["--window-size", "big"]) == 2
    assert "--window-size must look like 1024x600" in capsys.readouterr().err


def test_a_canvas_file_opens_on_the_demo_robot_at_the_size_given_and_nothing_is_saved(tmp_path):
    path = canvas_file(tmp_path / "bench.json")
    before = path.read_bytes()
    shot = tmp_path / "bench.png"
    env = dict(os.environ, QT_QPA_PLATFORM="offscreen", RCON_CONFIG_DIR=str(tmp_path / "cfg"),
               XDG_CONFIG_HOME=str(tmp_path / "xdg"))
    proc = subprocess.run([sys.executable, "-m", "rcon_core", "--demo", "--canvas", str(path), "--window-size",
                           "800x480", "--screenshot", str(shot), "--quit-after", "4"],
                          capture_output=True, text=True, env=env, timeout=120)
    assert proc.returncode == 0, proc.stderr[-2000:]
    picture = cv2.imread(str(shot))
    assert picture.shape[:2] == (480, 800)
    assert path.read_bytes() == before  # only read
    cfg = tmp_path / "cfg"
    assert not (cfg / "workspace.json").exists() and not (cfg / "demo-workspace.json").exists()
    unknown = subprocess.run([sys.executable, "-m", "rcon_core", "--canvas", "No such template"],
                             capture_output=True, text=True, env=env, timeout=120)
    assert unknown.returncode == 2 and "no such file, and no template of that title" in unknown.stderr
