"""`rcon new-widget PACKAGE --kind NAME [--type pkg/Msg]` writes a distribution that installs, passes its
own tests against the embedded robot, and shows in `rcon plugins` and `rcon match`."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from rcon_core.cli.main import main


def rcon(*argv, cwd=None, env=None):
    return subprocess.run([sys.executable, "-m", "rcon_core", *argv], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=300)


def test_a_generated_package_installs_passes_its_tests_and_is_found(tmp_path):
    proc = rcon("new-widget", "rcon-lab-winch", "--kind", "lab.winch", "--type", "lab_msgs/Winch", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    assert lines[1:] == ["next:", '  cd rcon-lab-winch && pip install -e ".[test]"', "  pytest",
                         "  rcon plugins --check && rcon match lab_msgs/Winch"]
    package = tmp_path / "rcon-lab-winch"
    assert {p.relative_to(package).as_posix() for p in package.rglob("*") if p.is_file()} == {
        "pyproject.toml", "README.md", "rcon_lab_winch/__init__.py", "rcon_lab_winch/py.typed",
        "rcon_lab_winch/plugin.py", "rcon_lab_winch/model.py", "rcon_lab_winch/view.py",
        "tests/conftest.py", "tests/test_model.py", "tests/test_view.py"}
    site = tmp_path / "site"  # installed beside, not into, this test environment
    pip = subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--no-input",
                          "--target", str(site), str(package)], capture_output=True, text=True, timeout=300)
    assert pip.returncode == 0, pip.stderr
    assert (site / "rcon_lab_winch" / "py.typed").exists()
    env = dict(os.environ, PYTHONPATH=str(site), QT_QPA_PLATFORM="offscreen")
    tests = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider"], cwd=package, env=env,
                           capture_output=True, text=True, timeout=300)
    assert tests.returncode == 0, tests.stdout + tests.stderr
    assert "3 passed" in tests.stdout
    listed = rcon("plugins", "--check", "--json", env=env)
    assert listed.returncode == 0, listed.stderr
    [mine] = [p for p in json.loads(listed.stdout)["plugins"] if p["dist"] == "rcon-lab-winch"]
    assert mine["status"] == "loaded" and mine["types"] == ["lab_msgs/Winch"]
    assert [w["kind"] for w in mine["widgets"]] == ["lab.winch"]
    matched = rcon("match", "lab_msgs/Winch", "--json", env=env)
    first = json.loads(matched.stdout)["matches"][0]
    assert (first["kind"], first["rank"], first["field_path"]) == ("lab.winch", "exact", "value")


@pytest.mark.parametrize("argv, message", [
    (["Not_A_Dist", "--kind", "lab.x"], "must be a lowercase distribution name"),
    (["rcon-lab-x", "--kind", "nodot"], "must be a dotted lowercase id"),
    (["rcon-lab-x", "--kind", "lab.x", "--type", "std_msgs/String"], "has no numeric field"),
    (["rcon-lab-x", "--kind", "lab.x", "--type", "std_srvs/srv/Trigger"], "must be a message type"),
])
def test_bad_arguments_write_nothing(tmp_path, capsys, argv, message):
    rc = main(["new-widget", *argv, "--dir", str(tmp_path / "out")])
    assert rc == 2 and message in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_an_existing_directory_is_not_overwritten(tmp_path, capsys):
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "mine.txt").write_text("keep")
    assert main(["new-widget", "rcon-lab-x", "--kind", "lab.x", "--dir", str(tmp_path / "out")]) == 1
    assert "exists and is not empty" in capsys.readouterr().err
    assert [p.name for p in (tmp_path / "out").iterdir()] == ["mine.txt"]
