"""Smoke test of the built one-folder app (`tox -e bundle` builds it into dist/rcon and runs this).

It runs the frozen executable as an operator's tablet would, headless (QT_QPA_PLATFORM=offscreen), in a
home of its own: the widget packages are found through their entry points inside the bundle, the demo
opens and draws (camera, pad, connection), a lab's wheel goes into the plugins folder and its template
opens, and the map draws tiles from an offline MBTiles file (sqlite inside the bundle). The figures
(start to screenshot, the bundle's size) are printed; `pytest -s` shows them.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
BUNDLE = Path(os.environ.get("RCON_BUNDLE", ROOT / "dist" / "rcon"))
EXE = BUNDLE / ("rcon.exe" if sys.platform == "win32" else "rcon")


@pytest.fixture(scope="module", autouse=True)
def built():
    assert EXE.is_file(), f"no bundle at {BUNDLE}: build it with `tox -e bundle` (PyInstaller, bundle/rcon.spec)"


@pytest.fixture
def env(tmp_path):
    """A home of its own: no saved workspace, config, plugins folder or keyring of the machine's user."""
    base = {k: v for k, v in os.environ.items() if not k.startswith(("PYTHON", "VIRTUAL_ENV", "RCON_"))}
    return base | {
        "QT_QPA_PLATFORM": "offscreen", "HOME": str(tmp_path / "home"), "XDG_CONFIG_HOME": str(tmp_path / "config"),
        "XDG_DATA_HOME": str(tmp_path / "data"), "XDG_CACHE_HOME": str(tmp_path / "cache"),
        "RCON_CONFIG_DIR": str(tmp_path / "rcon-config"), "PYTHON_KEYRING_BACKEND": "keyring.backends.null.Keyring",
    }


def run(env, *argv, timeout=180):
    return subprocess.run([str(EXE), *argv], capture_output=True, text=True, env=env, cwd=env["HOME"] if
                          Path(env["HOME"]).is_dir() else None, timeout=timeout)


def screenshot(env, path, *argv, quit_after=6.0):
    """Run the app until it wrote ``path``; returns (picture, seconds from start to the file)."""
    start = time.monotonic()
    proc = run(env, *argv, "--screenshot", str(path), "--quit-after", str(quit_after))
    took = time.monotonic() - start
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "failed to load" not in proc.stderr, proc.stderr
    picture = cv2.imread(str(path))
    assert picture is not None, f"no picture at {path}"
    return picture, took


def near(picture, bgr, tolerance=30):
    """How many pixels are within ``tolerance`` of the colour ``bgr``."""
    return int((np.abs(picture.astype(int) - np.array(bgr)).max(axis=2) <= tolerance).sum())


def test_the_widget_packages_are_found_through_their_entry_points(env):
    proc = run(env, "plugins", "--check", "--json")
    assert proc.returncode == 0, proc.stderr
    plugins = {p["dist"]: p for p in json.loads(proc.stdout)["plugins"]}
    assert sorted(plugins) == ["rcon-widgets-map", "rcon-widgets-sensors", "rcon-widgets-std"]
    assert all(p["status"] == "loaded" for p in plugins.values())
    kinds = {w["kind"] for p in plugins.values() for w in p["widgets"]}
    assert {"std.button", "sensors.image", "sensors.teleop", "map.gps"} <= kinds
    folder = run(env, "plugins", "folder")  # the frozen app has a plugins folder of its own
    if sys.platform.startswith("linux"):
        assert folder.stdout.strip() == str(Path(env["XDG_DATA_HOME"]) / "rcon" / "plugins")
    else:  # Windows: %LOCALAPPDATA%\rcon\plugins, found through the shell, not the environment
        assert Path(folder.stdout.strip()).parts[-2:] == ("rcon", "plugins")


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="X11's xcb libraries are a Linux matter")
def test_the_x11_platform_plugin_finds_every_library_it_needs():
    """Qt's xcb platform plugin (a Linux desktop) needs xcb libraries that PyInstaller copies from the
    build machine: where that machine lacks one (a fresh Debian lacked libxcb-icccm4 and libxcb-keysyms1),
    the bundle lacks it too and the app cannot open a window on a tablet that lacks it as well."""
    internal = BUNDLE / "_internal"
    plugin = next(internal.rglob("platforms/libqxcb.so"))
    env = dict(os.environ, LD_LIBRARY_PATH=str(internal))
    missing = []
    for lib in (plugin, *internal.rglob("libQt6XcbQpa.so*")):
        out = subprocess.run(["ldd", str(lib)], capture_output=True, text=True, env=env, timeout=60).stdout
        missing += [line.split()[0] for line in out.splitlines() if "not found" in line]
    assert not missing, (f"the xcb platform plugin lacks {sorted(set(missing))}: install them on the build "
                         "machine (apt install libxcb-icccm4 libxcb-keysyms1) and build again")


def test_the_demo_opens_and_draws(env, tmp_path):
    Path(env["HOME"]).mkdir()
    picture, took = screenshot(env, tmp_path / "demo.png", "--demo", "--window-size", "1024x600")
    size = sum(f.stat().st_size for f in BUNDLE.rglob("*") if f.is_file() and not f.is_symlink())
    print(f"\nbundle: {size / 1e6:.0f} MB in {BUNDLE}; --demo to screenshot: {took:.1f} s (quit after 6 s)")
    assert picture.shape[:2] == (600, 1024)
    assert len(np.unique(picture.reshape(-1, 3)[::5], axis=0)) > 300  # a drawn window, not a flat fill
    assert near(picture, (36, 102, 0), 25) > 2000  # the green CONNECTED badge: the embedded robot's link
    top_of_camera = picture[180:260, 30:400]  # the front camera's sky: the sim's frames reached the view
    assert near(top_of_camera, (226, 171, 106), 45) > 3000


def test_a_labs_wheel_goes_into_the_plugins_folder_and_its_template_opens(env, tmp_path):
    Path(env["HOME"]).mkdir()
    source = tmp_path / "lab"
    shutil.copytree(ROOT / "tests" / "example_plugin", source,
                    ignore=shutil.ignore_patterns("build", "*.egg-info", "__pycache__"))
    built = subprocess.run([sys.executable, "-m", "pip", "wheel", "--quiet", "--no-deps", "--no-input", "-w",
                            str(tmp_path / "wheels"), str(source)], capture_output=True, text=True, timeout=300)
    assert built.returncode == 0, built.stderr
    [wheel] = (tmp_path / "wheels").glob("*.whl")
    env["RCON_PLUGINS_DIR"] = str(tmp_path / "plugins")  # not the machine user's folder
    done = run(env, "plugins", "install", str(wheel))
    assert done.returncode == 0, done.stderr
    assert "installed rcon-example-lab 0.3.1 into" in done.stdout and "lab.gripper" in done.stdout
    listed = json.loads(run(env, "plugins", "--check", "--json").stdout)["plugins"]
    [lab] = [p for p in listed if p["dist"] == "rcon-example-lab"]
    assert lab["status"] == "loaded" and lab["templates"] == ["Gripper station"]
    picture, _ = screenshot(env, tmp_path / "gripper.png", "--demo", "--canvas", "Gripper station",
                            "--window-size", "800x480", quit_after=5.0)
    assert picture.shape[:2] == (480, 800)
    # the widget's frame and view, with no red ERROR badge: the kind is installed (a missing one is a grey
    # placeholder with ERROR) and the embedded robot knows the plugin's lab_msgs/Gripper
    assert near(picture[165:285, 30:355], (0, 0, 176), 30) == 0
    assert near(picture[165:285, 30:355], (255, 255, 255), 10) > 20_000
    valid = run(env, "layout", "validate", str(source / "rcon_example_lab" / "gripper_station.json"))
    assert valid.returncode == 0, valid.stderr


def test_the_map_draws_offline_tiles_from_an_mbtiles_file(env, tmp_path):
    """The map's offline assets: an MBTiles file (sqlite) read inside the bundle, tiles drawn."""
    from rcon_widgets_map import mercator
    from rcon_widgets_map.mbtiles import write_mbtiles

    from rcon_core.sim.vessel import Vessel

    Path(env["HOME"]).mkdir()
    lat, lon = Vessel().origin_lat, Vessel().origin_lon
    magenta = cv2.imencode(".png", np.full((256, 256, 3), (255, 0, 255), np.uint8))[1].tobytes()

    def tiles():
        for z in range(14, 18):
            cx, cy = mercator.tile_for(lat, lon, z)
            for y in range(cy - 3, cy + 4):
                for x in range(cx - 3, cx + 4):
                    yield z, x, y, magenta

    write_mbtiles(tmp_path / "harbour.mbtiles", tiles(), {"name": "bundle smoke test"})
    canvas = {"format": "rcon-canvas", "version": 1, "canvas": {"id": "c-map", "name": "Map", "locked": True, "widgets": [
        {"id": "w-map", "kind": "map.gps", "title": "Map",
         "binding": {"name": "/gps/fix", "type": "sensor_msgs/NavSatFix", "role": "subscribe", "field_paths": []},
         "geometry": {"x": 16.0, "y": 16.0, "w": 480.0, "h": 360.0},
         "settings": {"mbtiles_path": str(tmp_path / "harbour.mbtiles"), "zoom": 16.0}}]}}
    (tmp_path / "map.json").write_text(json.dumps(canvas))
    picture, _ = screenshot(env, tmp_path / "map.png", "--demo", "--canvas", str(tmp_path / "map.json"),
                            "--window-size", "1024x600")
    assert near(picture, (255, 0, 255), 40) > 30_000  # the tiles fill most of the 480x360 map
