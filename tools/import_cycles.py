"""Import cycles between the modules of some packages, lazy imports included.

Usage: ``python tools/import_cycles.py [--typing] [DIR ...]`` (default: ``rcon_core``); exit status 1 when
a cycle is found.  Each DIR is a package directory (``rcon_core/bridge``, ``plugins/rcon_widgets_std/rcon_widgets_std``);
its modules are named from the nearest directory above it without an ``__init__.py``.

Every ``import``/``from ... import`` statement counts wherever it is -- at the top, inside a function (a lazy
import), under ``try`` -- except under ``if TYPE_CHECKING:`` (those never run).  ``from pkg import name`` is an
edge to ``pkg.name`` when that is a module, else to ``pkg`` (its ``__init__``).  Only edges between modules of
the given directories are kept; a cycle is a strongly connected component of more than one module (or a
module importing itself).  ``--typing`` counts the ``if TYPE_CHECKING:`` imports too: it shows the
dependencies that annotations alone hide (a helper typed against the class that imports it).
"""

from __future__ import annotations

import ast
import sys
from collections.abc import Iterable, Iterator
from pathlib import Path


def _module_name(path: Path) -> str:
    """``a/b/c.py`` -> ``b.c`` when ``a`` has no ``__init__.py``; ``pkg/__init__.py`` -> ``pkg``."""
    parts = [path.stem] if path.name != "__init__.py" else []
    folder = path.parent
    while (folder / "__init__.py").exists():
        parts.insert(0, folder.name)
        folder = folder.parent
    return ".".join(parts)


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")


def _imports(tree: ast.AST, typing: bool = False) -> Iterator[ast.Import | ast.ImportFrom]:
    """Every import statement, skipping the bodies of ``if TYPE_CHECKING:`` (their ``else`` counts) unless
    ``typing``."""
    stack: list[ast.AST] = [tree]
    while stack:
        node = stack.pop()
        if isinstance(node, ast.Import | ast.ImportFrom):
            yield node
            continue
        if isinstance(node, ast.If) and _is_type_checking(node.test) and not typing:
            stack.extend(node.orelse)
            continue
        stack.extend(ast.iter_child_nodes(node))


def _resolve(module: str, is_package: bool, node: ast.ImportFrom) -> str:
    if not node.level:
        return node.module or ""
    base = module.split(".")
    if not is_package:
        base = base[:-1]
    if node.level > 1:
        base = base[: len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def graph(dirs: Iterable[str | Path], typing: bool = False) -> dict[str, set[str]]:
    """Module -> the modules (of the same directories) it imports."""
    files: dict[str, Path] = {}
    for d in dirs:
        for path in sorted(Path(d).rglob("*.py")):
            files[_module_name(path)] = path
    known = set(files)
    edges: dict[str, set[str]] = {m: set() for m in files}
    for module, path in files.items():
        tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
        is_package = path.name == "__init__.py"
        for node in _imports(tree, typing):
            targets: list[str] = []
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            else:
                base = _resolve(module, is_package, node)
                for alias in node.names:
                    sub = f"{base}.{alias.name}" if base else alias.name
                    targets.append(sub if sub in known else base)
            for target in targets:
                # ``import a.b.c`` runs a, a.b and a.b.c; the deepest known one is the edge that matters
                while target and target not in known:
                    target = target.rpartition(".")[0]
                if target and target != module:
                    edges[module].add(target)
                elif target == module and isinstance(node, ast.ImportFrom) and node.level:
                    edges[module].add(module)
    return edges


def cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with a cycle (Tarjan), each sorted, biggest first."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    on_stack: set[str] = set()
    stack: list[str] = []
    found: list[list[str]] = []
    counter = 0

    def visit(v: str) -> None:
        nonlocal counter
        index[v] = low[v] = counter
        counter += 1
        stack.append(v)
        on_stack.add(v)
        for w in sorted(edges.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1 or v in edges.get(v, ()):
                found.append(sorted(component))

    sys.setrecursionlimit(max(sys.getrecursionlimit(), 10000))
    for v in sorted(edges):
        if v not in index:
            visit(v)
    return sorted(found, key=lambda c: (-len(c), c))


def main(argv: list[str]) -> int:
    typing = "--typing" in argv
    dirs = [a for a in argv if a != "--typing"] or ["rcon_core"]
    edges = graph(dirs, typing)
    found = cycles(edges)
    print(f"{len(edges)} modules, {sum(len(t) for t in edges.values())} imports, {len(found)} cycle(s)")
    for component in found:
        inner = {m: sorted(t & set(component)) for m, t in edges.items() if m in component}
        print("  cycle: " + ", ".join(component))
        for m, targets in inner.items():
            print(f"    {m} -> {', '.join(targets)}")
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
