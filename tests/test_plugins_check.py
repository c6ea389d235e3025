"""issue 15.4: `rcon plugins --check` exits 1 and names each failed plugin and why (a lab's CI step)."""

import os
import subprocess
import sys
import textwrap
from pathlib import Path


def _write_dist(root: Path, dist: str, module: str, ep_name: str, code: str) -> None:
    (root / module).mkdir(parents=True)
    (root / module / "__init__.py").write_text(textwrap.dedent(code))
    info = root / f"{dist.replace('-', '_')}-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {dist}\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text(f"[rcon.widgets]\n{ep_name} = {module}\n")


def _plugins(site: Path, *args: str) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=str(site))
    return subprocess.run([sys.executable, "-m", "rcon_core", "plugins", *args], capture_output=True, text=True,
                          env=env, timeout=120)


def test_check_passes_when_every_plugin_loads(tmp_path):
    proc = _plugins(tmp_path, "--check")
    assert proc.returncode == 0, proc.stderr
    assert "failed" not in proc.stderr


def test_check_names_each_failed_plugin_and_why(tmp_path):
    _write_dist(tmp_path, "rcon-test-noimport", "rcon_test_noimport", "noimport",
                "raise ImportError('needs libfoo, which is not installed')\n")
    _write_dist(tmp_path, "rcon-test-badtype", "rcon_test_badtype", "badtype", """
        from rcon_core.plugins import hookimpl

        @hookimpl
        def rcon_register_types(registry):
            registry.add_msg("lab_msgs/Broken", "flaot64 x\\n")
        """)
    plain = _plugins(tmp_path)
    assert plain.returncode == 0  # listing alone stays informative
    proc = _plugins(tmp_path, "--check")
    assert proc.returncode == 1
    assert "plugin 'noimport' (rcon-test-noimport 1.0) failed: ImportError: needs libfoo" in proc.stderr
    assert "plugin 'badtype' (rcon-test-badtype 1.0) failed:" in proc.stderr and "flaot64" in proc.stderr
    assert "2 plugin(s) failed" in proc.stderr
    assert _plugins(tmp_path, "--check", "--json").returncode == 1
