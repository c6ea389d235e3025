"""issue 25: the four distributions build as wheels and install from those files alone into a fresh venv,
where `rcon` runs: the plugins are found through their entry points and the demo opens and draws.

The fresh venv gets the four wheels with `pip install --no-index --find-links WHEELS` (nothing comes
from an index, so a wrong name such as `rcon` cannot be fetched). The third-party dependencies are not
downloaded: a folder on the fresh venv's path holds links to what this environment has installed, but
only the distributions the four wheels' metadata requires (followed through their own requirements).
So a dependency the metadata forgets to declare is missing there and the demo fails.
"""

from __future__ import annotations

import email.parser
import importlib.metadata as md
import json
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest
from packaging.requirements import Requirement
from packaging.utils import canonicalize_name

ROOT = Path(__file__).resolve().parents[1]
SOURCES = {
    "rcon-core": (ROOT, ["pyproject.toml", "README.md", "rcon_core"]),
    "rcon-widgets-std": (ROOT / "plugins" / "rcon_widgets_std", None),
    "rcon-widgets-sensors": (ROOT / "plugins" / "rcon_widgets_sensors", None),
    "rcon-widgets-map": (ROOT / "plugins" / "rcon_widgets_map", None),
}
IGNORE = shutil.ignore_patterns("build", "dist", "*.egg-info", "__pycache__", "tests", ".tox")


def build_wheels(tmp: Path) -> dict[str, Path]:
    """One wheel per distribution, built from copies (the source tree gets no build directory)."""
    copies = []
    for dist, (source, only) in SOURCES.items():
        copy = tmp / "src" / dist
        if only is None:
            shutil.copytree(source, copy, ignore=IGNORE)
        else:
            copy.mkdir(parents=True)
            for name in only:
                src = source / name
                if src.is_dir():
                    shutil.copytree(src, copy / name, ignore=IGNORE)
                else:
                    shutil.copy2(src, copy / name)
        copies.append(str(copy))
    out = tmp / "wheels"
    proc = subprocess.run([sys.executable, "-m", "pip", "wheel", "--quiet", "--no-deps", "--no-input", "-w",
                           str(out), *copies], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    wheels = {canonicalize_name(w.name.split("-")[0]): w for w in out.glob("*.whl")}
    assert sorted(wheels) == sorted(SOURCES)
    return wheels


def wheel_metadata(wheel: Path) -> tuple[set[str], email.message.Message, str]:
    with zipfile.ZipFile(wheel) as zf:
        names = set(zf.namelist())
        info = next(f.split("/")[0] for f in names if f.endswith(".dist-info/METADATA"))
        meta = email.parser.Parser().parsestr(zf.read(f"{info}/METADATA").decode())
        entry_points = zf.read(f"{info}/entry_points.txt").decode() if f"{info}/entry_points.txt" in names else ""
    return names, meta, entry_points


def dependency_closure(requirements: list[str]) -> dict[str, md.Distribution]:
    """The installed distributions these requirements need, followed through their own requirements
    (markers evaluated for this interpreter; extras are not followed)."""
    found: dict[str, md.Distribution] = {}
    todo = [Requirement(r) for r in requirements]
    while todo:
        req = todo.pop()
        if req.marker is not None and not req.marker.evaluate({"extra": ""}):
            continue
        name = canonicalize_name(req.name)
        if name in found or name in SOURCES:
            continue
        dist = md.distribution(req.name)
        assert req.specifier.contains(dist.version, prereleases=True), f"{req} but {dist.version} is installed"
        found[name] = dist
        todo += [Requirement(r) for r in dist.requires or []]
    return found


def link_dependencies(dists: dict[str, md.Distribution], into: Path) -> None:
    """Links in ``into`` to each distribution's top-level files and folders (its packages, its
    .dist-info, its bundled libraries), so only these are importable from there."""
    into.mkdir()
    for dist in dists.values():
        base = Path(dist.locate_file(""))
        tops = {Path(str(f)).parts[0] for f in dist.files or [] if not str(f).startswith("..")}
        for top in tops:
            target = base / top
            if target.exists() and not (into / top).exists():
                (into / top).symlink_to(target, target_is_directory=target.is_dir())


@pytest.mark.skipif(sys.platform == "win32", reason="the fresh venv's links need a POSIX file system")
def test_four_wheels_install_offline_into_a_fresh_venv_and_rcon_runs(tmp_path):
    wheels = build_wheels(tmp_path)
    requirements: list[str] = []
    for dist, wheel in wheels.items():
        names, meta, entry_points = wheel_metadata(wheel)
        assert canonicalize_name(meta["Name"]) == dist
        requires = meta.get_all("Requires-Dist") or []
        assert "rcon" not in {canonicalize_name(Requirement(r).name) for r in requires}
        if dist == "rcon-core":
            assert "[console_scripts]\nrcon = rcon_core.cli.main:main" in entry_points
            assert {"rcon_core/canvas/layout.schema.json", "rcon_core/app/link-settings.svg"} <= names
            assert any(n.startswith("rcon_core/msgs/defs/") and n.endswith(".msg") for n in names)
        else:
            assert any(canonicalize_name(Requirement(r).name) == "rcon-core" for r in requires)
            assert "[rcon.widgets]" in entry_points
        requirements += [r for r in requires if canonicalize_name(Requirement(r).name) not in SOURCES]

    venv = tmp_path / "fresh"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True, timeout=120)
    python = venv / "bin" / "python"
    site = Path(subprocess.run([str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                               capture_output=True, text=True, check=True).stdout.strip())
    deps = dependency_closure(requirements)
    assert {"pyside6-essentials", "numpy", "websockets", "pluggy"} <= set(deps)
    link_dependencies(deps, tmp_path / "deps")
    (site / "deps.pth").write_text(str(tmp_path / "deps") + "\n")

    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV", "PYTHONHOME")}
    env |= {"QT_QPA_PLATFORM": "offscreen", "HOME": str(tmp_path / "home"),
            "XDG_CONFIG_HOME": str(tmp_path / "config"), "XDG_DATA_HOME": str(tmp_path / "data"),
            "XDG_CACHE_HOME": str(tmp_path / "cache"), "PYTHON_KEYRING_BACKEND": "keyring.backends.null.Keyring"}
    pip = subprocess.run([sys.executable, "-m", "pip", "--python", str(python), "install", "--quiet",
                          "--no-index", "--no-input", "--find-links", str(tmp_path / "wheels"), *SOURCES],
                         capture_output=True, text=True, timeout=300, env=env)
    assert pip.returncode == 0, pip.stdout + pip.stderr

    where = subprocess.run([str(python), "-c", "import rcon_core, rcon_widgets_map; print(rcon_core.__file__);"
                            "print(rcon_widgets_map.__file__)"], capture_output=True, text=True, env=env,
                           cwd=tmp_path, timeout=120)
    assert where.returncode == 0, where.stderr
    assert all(Path(line).is_relative_to(site) for line in where.stdout.splitlines())

    rcon = venv / "bin" / "rcon"
    listed = subprocess.run([str(rcon), "plugins", "--check", "--json"], capture_output=True, text=True, env=env,
                            cwd=tmp_path, timeout=120)
    assert listed.returncode == 0, listed.stderr
    plugins = {p["dist"]: p for p in json.loads(listed.stdout)["plugins"]}
    assert sorted(plugins) == ["rcon-widgets-map", "rcon-widgets-sensors", "rcon-widgets-std"]
    assert all(p["status"] == "loaded" and p["widgets"] for p in plugins.values())

    shot = tmp_path / "demo.png"
    demo = subprocess.run([str(rcon), "--demo", "--screenshot", str(shot), "--quit-after", "6"],
                          capture_output=True, text=True, env=env, cwd=tmp_path, timeout=180)
    assert demo.returncode == 0, demo.stdout + demo.stderr
    assert "failed to load" not in demo.stderr
    import cv2
    import numpy as np

    picture = cv2.imread(str(shot))
    assert picture is not None and picture.shape[1] >= 800 and picture.shape[0] >= 500
    # a drawn window: many colours (camera views, the pad), not one flat fill
    assert len(np.unique(picture.reshape(-1, 3)[::7], axis=0)) > 200
