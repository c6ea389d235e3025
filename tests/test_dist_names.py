"""issue 25: the distributions have names of their own on the package index.

`rcon` on the index is an unrelated project (a game-server remote console client). A lab that follows
the scaffold or the guide and writes `rcon>=0.1` gets that project wherever RCON is not already
installed. These tests read every pyproject.toml, what `rcon new-widget` writes and the docs, and fail on
the old name."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

import pytest

from rcon_core.cli.new_widget import write_package

ROOT = Path(__file__).resolve().parents[1]

#: distribution name -> the import package it carries (the rule: the import name with dashes)
NAMES = {
    "rcon-core": "rcon_core",
    "rcon-widgets-std": "rcon_widgets_std",
    "rcon-widgets-sensors": "rcon_widgets_sensors",
    "rcon-widgets-map": "rcon_widgets_map",
}
PYPROJECTS = {
    "rcon-core": ROOT / "pyproject.toml",
    "rcon-widgets-std": ROOT / "plugins" / "rcon_widgets_std" / "pyproject.toml",
    "rcon-widgets-sensors": ROOT / "plugins" / "rcon_widgets_sensors" / "pyproject.toml",
    "rcon-widgets-map": ROOT / "plugins" / "rcon_widgets_map" / "pyproject.toml",
}
#: a requirement on the distribution `rcon` (PEP 503: `rcon`, `Rcon`; not `rcon-core`, not `rcon_core`)
OLD_REQUIREMENT = re.compile(r"""["']rcon\s*(\[[^\]]*\])?\s*(>=|==|~=|<|>|!=|;|["'])""")
#: an install of the distribution `rcon`: `pip install rcon`, `pip install "rcon[test]"`
OLD_INSTALL = re.compile(r"""pip install (-\S+ )*["']?rcon(\[[^\]]*\])?["']?(\s|$)""")


def requirement_names(requirements: list[str]) -> set[str]:
    return {re.split(r"[\s\[<>=!~;(]", r, maxsplit=1)[0].lower().replace("_", "-") for r in requirements}


def old_name_uses(text: str) -> list[str]:
    return [m.group(0).strip() for m in OLD_REQUIREMENT.finditer(text)] + \
        [m.group(0).strip() for m in OLD_INSTALL.finditer(text)]


def test_the_patterns_catch_the_old_name_and_pass_the_new():
    assert old_name_uses('dependencies = ["rcon>=0.1"]') == ['"rcon>=']
    assert old_name_uses('test = ["rcon[test]"]')
    assert old_name_uses("pip install rcon")
    assert old_name_uses('pip install "rcon[test]"')
    assert old_name_uses('dependencies = ["rcon-core>=0.1"]') == []
    assert old_name_uses('pip install rcon-core rcon-widgets-std') == []
    assert old_name_uses("the `rcon` command; `rcon --demo`") == []


@pytest.mark.parametrize("dist", sorted(PYPROJECTS))
def test_each_distribution_has_its_own_name(dist):
    project = tomllib.loads(PYPROJECTS[dist].read_text())["project"]
    assert project["name"] == dist
    assert dist.replace("-", "_") == NAMES[dist]
    assert "rcon" not in requirement_names(project.get("dependencies", []))
    if dist != "rcon-core":
        assert "rcon-core" in requirement_names(project["dependencies"])


def test_the_core_keeps_the_rcon_command_and_the_import_name():
    project = tomllib.loads(PYPROJECTS["rcon-core"].read_text())
    assert project["project"]["scripts"] == {"rcon": "rcon_core.cli.main:main"}
    assert project["tool"]["setuptools"]["packages"]["find"]["include"] == ["rcon_core*"]


def test_the_example_package_depends_on_rcon_core():
    project = tomllib.loads((ROOT / "tests" / "example_plugin" / "pyproject.toml").read_text())["project"]
    assert requirement_names(project["dependencies"]) == {"rcon-core"}


@pytest.mark.parametrize("argv", [("lab.winch", "lab_msgs/Winch", "subscribe"),
                                  ("lab.pump", "lab_srvs/SetPump", "call")])
def test_what_new_widget_writes_names_rcon_core(tmp_path, argv):
    kind, msg_type, role = argv
    written = write_package(tmp_path / "pkg", "rcon-lab-x", kind, msg_type, role=role)
    project = tomllib.loads((tmp_path / "pkg" / "pyproject.toml").read_text())["project"]
    assert requirement_names(project["dependencies"]) == {"rcon-core"}
    assert requirement_names(project["optional-dependencies"]["test"]) == {"rcon-core"}
    for path in written:
        assert old_name_uses(path.read_text()) == [], path


def test_no_doc_names_the_old_distribution():
    docs = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md")), *sorted((ROOT / "plugins").glob("*/README.md"))]
    assert len(docs) >= 8
    found = {str(p.relative_to(ROOT)): old_name_uses(p.read_text()) for p in docs}
    assert {k: v for k, v in found.items() if v} == {}
    guide = (ROOT / "docs" / "writing-a-widget-plugin.md").read_text()
    assert '"rcon-core>=0.1"' in guide and "rcon-core[test]" in guide
    hooks = " ".join((ROOT / "docs" / "hooks.md").read_text().split())
    assert "depends on **`rcon-core`**" in hooks and "Never write `rcon`" in hooks
