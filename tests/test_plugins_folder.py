"""issue 25: a lab's widget package added to an installed app without rebuilding it (the plugins folder,
`rcon plugins install WHEEL`). The bundle's own smoke test (bundle/test_bundle.py) does the same in the
frozen app; these run the same code in this environment, with RCON_PLUGINS_DIR naming the folder."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from rcon_core.cli.main import main
from rcon_core.plugins import folder
from rcon_core.plugins.folder import PluginInstallError, install, installed, plugins_dir, remove

EXAMPLE = Path(__file__).resolve().parent / "example_plugin"


def make_wheel(where: Path, name: str = "rcon-lab-tiny", version: str = "1.0", *, requires=(),
               entry_points: str | None = None, extra: dict[str, str] | None = None,
               tag: str = "py3-none-any") -> Path:
    """A small wheel written by hand (what `pip wheel` makes for a one-module package)."""
    module = name.replace("-", "_")
    info = f"{module}-{version}.dist-info"
    if entry_points is None:
        entry_points = f"[rcon.widgets]\ntiny = {module}.plugin\n"
    meta = f"Metadata-Version: 2.1\nName: {name}\nVersion: {version}\n" + "".join(
        f"Requires-Dist: {r}\n" for r in requires)
    files = {
        f"{module}/__init__.py": "",
        f"{module}/plugin.py": (
            "from rcon_core.plugins import WidgetSpec, hookimpl\n\n@hookimpl\ndef rcon_register_widgets(registry):\n"
            f"    registry.add(WidgetSpec(kind='tiny.v{version.replace('.', '_')}', title='Tiny', model='x:y'))\n"),
        f"{info}/METADATA": meta,
        f"{info}/WHEEL": f"Wheel-Version: 1.0\nRoot-Is-Purelib: true\nTag: {tag}\n",
        f"{info}/entry_points.txt": entry_points,
        f"{info}/RECORD": "",
        **(extra or {}),
    }
    where.mkdir(parents=True, exist_ok=True)
    path = where / f"{module}-{version}-{tag}.whl"
    with zipfile.ZipFile(path, "w") as zf:
        for member, text in files.items():
            zf.writestr(member, text)
    return path


def rcon(*argv, env):
    return subprocess.run([sys.executable, "-m", "rcon_core", *argv], capture_output=True, text=True, env=env,
                          timeout=300)


def test_the_folder_is_the_env_or_the_frozen_apps_and_a_pip_install_has_none(tmp_path):
    assert plugins_dir({"RCON_PLUGINS_DIR": str(tmp_path)}, frozen=False) == tmp_path
    assert plugins_dir({}, frozen=False) is None
    frozen = plugins_dir({}, frozen=True)
    assert frozen is not None and frozen.parts[-2:] == ("rcon", "plugins")


def test_a_pip_install_says_to_use_pip(capsys, monkeypatch):
    monkeypatch.delenv(folder.ENV, raising=False)
    assert main(["plugins", "install", "x.whl"]) == 2
    assert "pip installation, which has no plugins folder: `pip install WHEEL`" in capsys.readouterr().err


def test_the_example_package_installs_into_the_folder_and_loads(tmp_path):
    """A real lab package (pip wheel of tests/example_plugin) installed and found by a fresh `rcon`."""
    source = tmp_path / "src"
    shutil.copytree(EXAMPLE, source, ignore=shutil.ignore_patterns("build", "*.egg-info", "__pycache__"))
    built = subprocess.run([sys.executable, "-m", "pip", "wheel", "--quiet", "--no-deps", "--no-input", "-w",
                            str(tmp_path / "wheels"), str(source)], capture_output=True, text=True, timeout=300)
    assert built.returncode == 0, built.stderr
    [wheel] = (tmp_path / "wheels").glob("*.whl")
    env = dict(os.environ, RCON_PLUGINS_DIR=str(tmp_path / "plugins"), QT_QPA_PLATFORM="offscreen")
    done = rcon("plugins", "install", str(wheel), env=env)
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines() == [
        f"rcon plugins: installed rcon-example-lab 0.3.1 into {tmp_path / 'plugins' / 'rcon-example-lab'}",
        "  lab: lab.gripper; restart RCON to use it"]
    listed = rcon("plugins", "--check", "--json", env=env)
    assert listed.returncode == 0, listed.stderr
    [lab] = [p for p in json.loads(listed.stdout)["plugins"] if p["dist"] == "rcon-example-lab"]
    assert lab["status"] == "loaded" and lab["templates"] == ["Gripper station"] and lab["types"] == ["lab_msgs/Gripper"]
    assert rcon("plugins", "folder", env=env).stdout.strip() == str(tmp_path / "plugins")
    gone = rcon("plugins", "remove", "rcon_example_lab", env=env)
    assert gone.returncode == 0 and "removed rcon-example-lab 0.3.1" in gone.stdout
    after = json.loads(rcon("plugins", "--json", env=env).stdout)["plugins"]
    assert "rcon-example-lab" not in {p["dist"] for p in after}


def test_a_newer_version_replaces_the_old_one(tmp_path):
    root = tmp_path / "plugins"
    install(make_wheel(tmp_path / "a", version="1.0"), root)
    install(make_wheel(tmp_path / "b", version="2.0"), root)
    assert [(p.name, p.version, p.path.name) for p in installed(root)] == [("rcon-lab-tiny", "2.0", "rcon-lab-tiny")]
    assert sorted(p.name for p in root.iterdir()) == ["rcon-lab-tiny"]  # no staging or old folder left
    remove("rcon-lab-tiny", root)
    assert installed(root) == []
    with pytest.raises(KeyError):
        remove("rcon-lab-tiny", root)


@pytest.mark.parametrize("kwargs, reason", [
    ({"tag": "cp311-cp311-manylinux_2_17_x86_64"}, "holds compiled code (cp311, manylinux_2_17_x86_64): the app "
     "takes pure-Python wheels only"),
    ({"entry_points": "[console_scripts]\nx = y:z\n"}, "rcon-lab-tiny 1.0 offers no widgets: its wheel has no "
     "'rcon.widgets' entry point"),
    ({"requires": ["rcon-core>=0.1", "no-such-dist-here>=1"]}, "rcon-lab-tiny 1.0 needs what this RCON does not "
     "have: no-such-dist-here>=1 (not in this RCON). The app cannot install more packages"),
    ({"requires": ["rcon-core>=99"]}, "rcon-core>=99 (this RCON has 0.1.0)"),
    ({"name": "rcon-widgets-std"}, "this RCON already has rcon-widgets-std 0.1.0: a plugin may not replace"),
    ({"extra": {"../../evil.py": "x"}}, "member '../../evil.py' would be written outside its folder"),
])
def test_what_cannot_work_is_refused_before_anything_is_written(tmp_path, kwargs, reason):
    wheel = make_wheel(tmp_path / "w", **kwargs)
    root = tmp_path / "plugins"
    with pytest.raises(PluginInstallError) as caught:
        install(wheel, root)
    assert reason in str(caught.value)
    assert not root.exists() or list(root.iterdir()) == []


def test_requirements_for_another_python_or_an_extra_are_not_asked_for(tmp_path):
    wheel = make_wheel(tmp_path / "w", requires=['rcon-core>=0.1', 'nothing-here; python_version < "3.0"',
                                                 'pytest-nothing; extra == "test"'])
    assert install(wheel, tmp_path / "plugins").version == "1.0"


def test_not_a_wheel(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv(folder.ENV, str(tmp_path / "plugins"))
    (tmp_path / "lab.zip").write_bytes(b"PK")
    assert main(["plugins", "install", str(tmp_path / "lab.zip")]) == 1
    assert "lab.zip is not a wheel (name-version-python-abi-platform.whl)" in capsys.readouterr().err
    broken = tmp_path / "lab-1.0-py3-none-any.whl"
    broken.write_bytes(b"not a zip")
    assert main(["plugins", "install", str(broken)]) == 1
    assert "is not a readable wheel (not a zip file)" in capsys.readouterr().err
    assert main(["plugins", "install", str(tmp_path / "nope-1.0-py3-none-any.whl")]) == 1
    assert "no such file" in capsys.readouterr().err
