"""Everything but the Qt front end and widget views imports without Qt (checked in a fresh interpreter)."""

import json
import subprocess
import sys

SCRIPT = r"""
import importlib, importlib.util, json, sys
core = ["rcon_core", "rcon_core.msgs", "rcon_core.bridge", "rcon_core.sim", "rcon_core.plugins",
        "rcon_core.matcher", "rcon_core.canvas", "rcon_core.canvas.runtime", "rcon_core.cli.main",
        "rcon_core.cli.plugin_cmds", "rcon_core.testing", "rcon_core.record.writer", "rcon_core.record.ingest",
        "rcon_core.record.files", "rcon_core.record.recover", "rcon_core.record.session", "rcon_core.sim.playback",
        "rcon_core.link", "rcon_core.foxglove", "rcon_core.foxglove.gateway", "rcon_core.foxglove.testing",
        "rcon_core.foxglove.flatbuf", "rcon_core.record.foxglove_source"]
checked, missing = [], []
for name in core:
    if importlib.util.find_spec(name) is None:
        missing.append(name)
        continue
    importlib.import_module(name)
    checked.append(name)
from rcon_core.plugins import PluginManager
pm = PluginManager()
pm.load_entry_points()
for spec in pm.widgets():
    for ref in (spec.model, spec.settings, spec.plugin_settings):
        if isinstance(ref, str):
            checked.append(ref)
    spec.load_model(); spec.load_settings_class(); spec.load_plugin_settings_class()
from rcon_core.cli.main import build_parser
build_parser()  # imports every CLI command module
checked.append("rcon_core.cli.main:build_parser()")
qt = sorted(m for m in sys.modules if m.split(".")[0].startswith(("PySide6", "PyQt", "qtpy", "shiboken")))
plugins = {i.name: i.status for i in pm.plugins}
print(json.dumps({"checked": checked, "missing": missing, "qt": qt, "plugins": plugins,
                  "widgets": [s.kind for s in pm.widgets()]}))
"""


def test_no_qt_outside_the_app():
    proc = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    assert not out["missing"], f"core modules missing: {out['missing']}"
    assert not out["qt"], f"Qt imported by {out['checked']}: {out['qt']}"
    assert {"std", "sensors", "map"} <= set(out["plugins"]), out["plugins"]
    failed = {k: v for k, v in out["plugins"].items() if v != "loaded"}
    assert not failed, f"widget plugins not checked because they did not load: {failed}"
    assert len(out["checked"]) >= 11, out["checked"]
