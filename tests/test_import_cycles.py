"""No import cycles in the packages that were cleaned (lazy imports count; ``if TYPE_CHECKING:`` does not).

The finder is ``tools/import_cycles.py``; the lead extends ``CLEAN`` package by package.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
CLEAN = ["rcon_core/bridge", "rcon_core/msgs", "rcon_core/app", "rcon_core/canvas", "rcon_core/plugins",
         "rcon_core/foxglove", "rcon_core/link"]
#: no cycle of real imports; the sim's op handlers still name ``SimServer`` in annotations only
CLEAN_RUNTIME = [*CLEAN, "rcon_core/sim"]


def _finder():
    spec = importlib.util.spec_from_file_location("import_cycles", ROOT / "tools" / "import_cycles.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_cleaned_packages_have_no_import_cycle() -> None:
    finder = _finder()
    edges = finder.graph([ROOT / d for d in CLEAN_RUNTIME])
    assert "rcon_core.bridge.client" in edges and "rcon_core.msgs.registry" in edges
    assert "rcon_core.app.children_editor" in edges and "rcon_core.plugins.children" in edges
    assert "rcon_core.sim.server" in edges and "rcon_core.canvas.runtime" in edges
    assert finder.cycles(edges) == []


def test_no_cycle_even_for_annotations() -> None:
    """The msgs helpers take a lookup protocol, the bridge's parts take the client's protocols (host.py):
    neither is typed against the class that imports it."""
    finder = _finder()
    assert finder.cycles(finder.graph([ROOT / d for d in CLEAN], typing=True)) == []


@pytest.mark.parametrize("lazy", [False, True])
def test_the_finder_sees_a_cycle_and_skips_type_checking_imports(tmp_path: Path, lazy: bool) -> None:
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    back = "def f():\n    from . import a\n" if lazy else "from .a import x\n"
    (pkg / "a.py").write_text("from typing import TYPE_CHECKING\nfrom . import b\nx = 1\n"
                              "if TYPE_CHECKING:\n    from .c import y\n")
    (pkg / "b.py").write_text(back)
    (pkg / "c.py").write_text("from .a import x\ny = 2\n")
    finder = _finder()
    assert finder.cycles(finder.graph([pkg])) == [["pkg.a", "pkg.b"]]
    assert finder.cycles(finder.graph([pkg], typing=True)) == [["pkg.a", "pkg.b", "pkg.c"]]
