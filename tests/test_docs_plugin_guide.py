"""issue 15.5/15.6: every code block of docs/writing-a-widget-plugin.md is either a verbatim excerpt of the
example package it describes (tests/example_plugin, whose own tests run in test_plugins_example.py) or is
run here, and the `Accepts` table says which field really gets bound. The guide cannot drift."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from rcon_core.matcher import candidate_paths
from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import Accepts, Role, WidgetSpec

ROOT = Path(__file__).resolve().parents[1]
GUIDE = ROOT / "docs" / "writing-a-widget-plugin.md"
EXAMPLE = ROOT / "tests" / "example_plugin"
MARKER = re.compile(r"<!-- (example|run): (\S+) -->")


def blocks() -> list[tuple[int, str, str | None, str | None, str]]:
    """(line, language, marker kind, marker argument, body) of every fenced block in the guide."""
    lines = GUIDE.read_text().splitlines()
    out = []
    i = 0
    while i < len(lines):
        stripped = lines[i].strip()
        if stripped.startswith("```") and stripped != "```":
            indent = len(lines[i]) - len(lines[i].lstrip())
            lang = stripped[3:]
            prev = next((lines[j].strip() for j in range(i - 1, -1, -1) if lines[j].strip()), "")
            found = MARKER.fullmatch(prev)
            body = []
            i += 1
            while lines[i].strip() != "```":
                body.append(lines[i][indent:])
                i += 1
            out.append((i, lang, found.group(1) if found else None, found.group(2) if found else None,
                        "\n".join(body) + "\n"))
        i += 1
    return out


def test_every_block_is_an_example_excerpt_or_run():
    found = blocks()
    assert len(found) >= 10
    unchecked = [(line, lang) for line, lang, kind, _, _ in found if kind is None and lang != "text"]
    assert not unchecked, f"code blocks without an <!-- example: --> or <!-- run: --> marker: {unchecked}"


@pytest.mark.parametrize("line, path, body", [(b[0], b[3], b[4]) for b in blocks() if b[2] == "example"])
def test_example_blocks_are_verbatim_excerpts_of_the_package(line, path, body):
    source = (ROOT / path).read_text()
    assert body in source, f"the block ending on line {line} is not an excerpt of {path}"


def test_the_package_tree_lists_the_example_files():
    [tree] = [b[4] for b in blocks() if b[1] == "text"]
    stack: list[str] = []
    listed = []
    for raw in tree.splitlines()[1:]:
        name = raw.split("#")[0].rstrip()
        depth = (len(name) - len(name.lstrip())) // 2 - 1
        stack[depth:] = [name.strip()]
        if not name.endswith("/"):
            listed.append("".join(stack))
    assert len(listed) >= 7
    for rel in listed:
        assert (EXAMPLE / rel).is_file(), rel
    assert (EXAMPLE / "tests" / "test_gripper.py").read_text() in GUIDE.read_text()


@pytest.mark.parametrize("line, body", [(b[0], b[4]) for b in blocks() if b[2:4] == ("run", "python")])
def test_python_blocks_run(line, body):
    exec(compile(body, f"{GUIDE.name}:{line}", "exec"), {"__name__": "guide_block"})


def test_the_shell_block_runs_in_a_copy_of_the_package(tmp_path):
    """The commands of "Check it", in a copy of the example package. Translated only as needed here:
    `pip install -e .` installs into a private directory (not this test environment), `pytest` and `rcon`
    run through this interpreter."""
    [body] = [b[4] for b in blocks() if b[2:4] == ("run", "shell")]
    package = tmp_path / "rcon-example-lab"
    shutil.copytree(EXAMPLE, package, ignore=shutil.ignore_patterns("__pycache__", "build", "*.egg-info"))
    site = tmp_path / "site"
    env = dict(os.environ, PYTHONPATH=str(site), QT_QPA_PLATFORM="offscreen")
    commands = [line.split("#")[0].split() for line in body.splitlines() if line.split("#")[0].strip()]
    assert [c[0] for c in commands] == ["pip", "pytest", "rcon", "rcon"]
    outputs = []
    for cmd in commands:
        if cmd == ["pip", "install", "-e", "."]:
            argv = [sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--no-input",
                    "--target", str(site), "."]
        elif cmd[0] == "pytest":
            argv = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", *cmd[1:]]
        else:
            argv = [sys.executable, "-m", "rcon_core", *cmd[1:]]
        proc = subprocess.run(argv, cwd=package, env=env, capture_output=True, text=True, timeout=300)
        assert proc.returncode == 0, f"{' '.join(cmd)}:\n{proc.stdout}\n{proc.stderr}"
        outputs.append(proc.stdout)
    assert "2 passed" in outputs[1]
    assert "rcon-example-lab 0.3.1" in outputs[2] and "lab.gripper" in outputs[2]
    assert outputs[3].splitlines()[0].split()[:2] == ["exact", "lab.gripper"]


def _bound(type_name: str, **accepts) -> str:
    spec = WidgetSpec(kind="doc.w", title="W", roles={Role.SUBSCRIBE}, accepts=Accepts(**accepts), model="x:y")
    return candidate_paths(spec, Role.SUBSCRIBE, type_name, TYPES)[0]


TYPES = TypeRegistry.standard()
TYPES.add_msg_text("lab_msgs/Gripper", "float64 opening\nfloat64 force\nbool grasping\nstring tool_id\n")


def test_the_accepts_table_says_which_field_is_bound():
    text = " ".join(GUIDE.read_text().split())
    assert _bound("sensor_msgs/BatteryState", fields=["numeric"]) == "percentage"
    assert "the best numeric field (see below): `percentage` for a BatteryState" in text
    assert _bound("sensor_msgs/Imu", messages=["vector3"]) == "angular_velocity"
    assert "the first one: `angular_velocity` for an Imu" in text
    assert _bound("lab_msgs/Gripper", fields=["numeric"], prefer=["opening"]) == "opening"
    assert _bound("sensor_msgs/BatteryState", fields=["numeric"], prefer=["opening"]) == "voltage"
    assert "binds `opening` on a Gripper but `voltage` (the first numeric field) on a BatteryState" in text
    assert _bound("sensor_msgs/Imu", messages=["vector3"], prefer=["linear_acceleration"]) == "linear_acceleration"
    assert '`messages=["vector3"], prefer=["linear_acceleration"]` binds `linear_acceleration`' in text
