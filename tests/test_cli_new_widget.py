"""`rcon new-widget PACKAGE --kind NAME [--type pkg/Msg]` writes a distribution that installs, passes its
own tests against the embedded robot, and shows in `rcon plugins` and `rcon match`."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from rcon_core.cli.main import main
from rcon_core.plugins.api import API_VERSION


def rcon(*argv, cwd=None, env=None):
    return subprocess.run([sys.executable, "-m", "rcon_core", *argv], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=300)


def install_and_test(tmp_path, package, passed):
    """Install the package (a wheel build: --target is not editable) beside this environment, run its own
    tests there; returns the environment that sees it."""
    site = tmp_path / "site"  # installed beside, not into, this test environment
    pip = subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--no-input",
                          "--target", str(site), str(package)], capture_output=True, text=True, timeout=300)
    assert pip.returncode == 0, pip.stderr
    env = dict(os.environ, PYTHONPATH=str(site), QT_QPA_PLATFORM="offscreen")
    tests = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider"], cwd=package, env=env,
                           capture_output=True, text=True, timeout=300)
    assert tests.returncode == 0, tests.stdout + tests.stderr
    assert f"{passed} passed" in tests.stdout
    return site, env


def test_a_generated_package_installs_passes_its_tests_and_is_found(tmp_path):
    proc = rcon("new-widget", "rcon-lab-winch", "--kind", "lab.winch", "--type", "lab_msgs/Winch", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    assert lines[0].endswith("files of rcon-lab-winch (subscribe lab_msgs/Winch) in rcon-lab-winch")
    assert lines[1:] == ["next:", '  cd rcon-lab-winch && pip install -e ".[test]"', "  pytest",
                         "  rcon plugins --check && rcon match lab_msgs/Winch"]
    package = tmp_path / "rcon-lab-winch"
    assert {p.relative_to(package).as_posix() for p in package.rglob("*") if p.is_file()} == {
        "pyproject.toml", "README.md", "rcon_lab_winch/__init__.py", "rcon_lab_winch/py.typed",
        "rcon_lab_winch/plugin.py", "rcon_lab_winch/model.py", "rcon_lab_winch/view.py",
        "rcon_lab_winch/template.json", "tests/conftest.py", "tests/test_model.py", "tests/test_view.py",
        "tests/test_conformance.py"}
    assert f'api_version="{API_VERSION}"' in (package / "rcon_lab_winch" / "plugin.py").read_text()
    site, env = install_and_test(tmp_path, package, 5)
    assert (site / "rcon_lab_winch" / "py.typed").exists()
    assert (site / "rcon_lab_winch" / "template.json").exists()  # issue 25.1: the wheel carries the template
    listed = rcon("plugins", "--check", "--json", env=env)
    assert listed.returncode == 0, listed.stderr
    [mine] = [p for p in json.loads(listed.stdout)["plugins"] if p["dist"] == "rcon-lab-winch"]
    assert mine["status"] == "loaded" and mine["types"] == ["lab_msgs/Winch"]
    assert mine["templates"] == ["Winch canvas"] and mine["problems"] == []
    assert [w["kind"] for w in mine["widgets"]] == ["lab.winch"]
    matched = rcon("match", "lab_msgs/Winch", "--json", env=env)
    first = json.loads(matched.stdout)["matches"][0]
    assert (first["kind"], first["rank"], first["field_path"]) == ("lab.winch", "exact", "value")


@pytest.mark.parametrize("argv, role, passed", [
    (["--type", "lab_srvs/SetPump"], "call", 8),  # not standard: a _srvs package is a service; a .srv to fill in
    (["--type", "std_srvs/SetBool", "--role", "call"], "call", 8),
    (["--type", "std_msgs/Float64", "--role", "publish"], "publish", 5),
    (["--type", "lab_msgs/Winch", "--role", "publish"], "publish", 5),  # its view test has no registry
])
def test_a_publisher_and_a_service_caller_install_and_pass_their_tests(tmp_path, argv, role, passed):
    """issue 25.2: `--type std_srvs/SetBool` crashed and `--type lab_srvs/SetPump` wrote a subscriber that
    registered the service as a message. The caller's tests provide the service on the embedded robot."""
    proc = rcon("new-widget", "rcon-lab-pump", "--kind", "lab.pump", *argv, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert f"({role} {argv[1]})" in proc.stdout.splitlines()[0]
    package = tmp_path / "rcon-lab-pump"
    _, env = install_and_test(tmp_path, package, passed)
    listed = rcon("plugins", "--check", "--json", env=env)
    assert listed.returncode == 0, listed.stderr
    [mine] = [p for p in json.loads(listed.stdout)["plugins"] if p["dist"] == "rcon-lab-pump"]
    assert [w["roles"] for w in mine["widgets"]] == [[role]]
    if argv[1] == "lab_srvs/SetPump":
        assert mine["types"] == ["lab_srvs/SetPump"]
        assert "registry.add_srv(TYPE, DEFINITION)" in (package / "rcon_lab_pump" / "plugin.py").read_text()
    matched = rcon("match", argv[1], "--role", role, "--json", env=env)
    ranks = {m["kind"]: m["rank"] for m in json.loads(matched.stdout)["matches"]}
    assert ranks["lab.pump"] == "exact"  # a standard type is also offered the std widgets


@pytest.mark.parametrize("argv, message", [
    (["Not_A_Dist", "--kind", "lab.x"], "must be a lowercase distribution name"),
    (["rcon-lab-x", "--kind", "nodot"], "must be a dotted lowercase id"),
    (["rcon-lab-x", "--kind", "lab.x", "--type", "std_msgs/String"], "has no numeric field"),
    (["rcon-lab-x", "--kind", "lab.x", "--type", "std_srvs/srv/Trigger", "--role", "subscribe"],
     "std_srvs/srv/Trigger is a service type: a widget that calls it takes --role call"),
    (["rcon-lab-x", "--kind", "lab.x", "--type", "std_srvs/SetBool", "--role", "publish"],
     "std_srvs/SetBool is a service type: a widget that calls it takes --role call"),
    (["rcon-lab-x", "--kind", "lab.x", "--type", "lab_srvs/SetPump", "--role", "subscribe"],
     "lab_srvs/SetPump is a service type"),
    (["rcon-lab-x", "--kind", "lab.x", "--type", "std_msgs/Float64", "--role", "call"],
     "--role call takes a service type such as std_srvs/SetBool; std_msgs/Float64 is a message type"),
    (["rcon-lab-x", "--kind", "lab.x", "--type", "lab_msgs/Winch", "--role", "call"], "is a message type"),
    (["rcon-lab-x", "--kind", "lab.x", "--type", "nav2_msgs/action/NavigateToPose"], "is an action"),
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
