"""The three bundled widget packages build as wheels with complete metadata, their entry point and
`py.typed` (built from a copy, so the source tree gets no build directory)."""

from __future__ import annotations

import email.parser
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

PLUGINS = Path(__file__).resolve().parents[1] / "plugins"


@pytest.mark.parametrize("name, entry_point", [("std", "std"), ("sensors", "sensors"), ("map", "map")])
def test_the_package_builds_a_complete_wheel(tmp_path, name, entry_point):
    dist = f"rcon_widgets_{name}"
    source = tmp_path / dist
    shutil.copytree(PLUGINS / dist, source, ignore=shutil.ignore_patterns("build", "*.egg-info", "__pycache__"))
    proc = subprocess.run([sys.executable, "-m", "pip", "wheel", "--quiet", "--no-deps", "--no-input",
                           "-w", str(tmp_path / "out"), str(source)], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    [wheel] = (tmp_path / "out").glob(f"{dist}-*-py3-none-any.whl")
    with zipfile.ZipFile(wheel) as zf:
        files = set(zf.namelist())
        info = next(f.split("/")[0] for f in files if f.endswith(".dist-info/METADATA"))
        meta = email.parser.Parser().parsestr(zf.read(f"{info}/METADATA").decode())
        entry_points = zf.read(f"{info}/entry_points.txt").decode()
    assert f"{dist}/py.typed" in files and f"{dist}/plugin.py" in files
    assert not any(f.startswith("tests/") for f in files)
    assert meta["Name"] == f"rcon-widgets-{name}" and meta["Version"]
    assert meta["Summary"].startswith("RCON ") and meta["Requires-Python"] == ">=3.11"
    assert meta["License"] == "BSD-3-Clause" and meta["Author"]
    assert meta["Description-Content-Type"] == "text/markdown"
    assert meta.get_payload().startswith(f"# rcon-widgets-{name}")  # the README
    assert "Typing :: Typed" in meta.get_all("Classifier")
    assert any(r.startswith("rcon") for r in meta.get_all("Requires-Dist"))
    assert meta["Keywords"]
    assert f"[rcon.widgets]\n{entry_point} = {dist}.plugin" in entry_points
