"""Places where code reads or calls another object's ``_private`` attribute.

Usage: ``python tools/private_access.py [DIR ...]`` (default: ``rcon_core``); prints each place and the count.

Counted: ``x._name`` where ``x`` is anything but ``self`` or ``cls`` (``self.node._subs``, ``client._send``,
``goal._future``), and ``from module import _name`` (a module's private helper used by another).  Not
counted: ``self._name``, ``cls._name``, dunder names (``__class__``), and ``_name`` attributes of the
``sys``/``os`` modules (``sys._getframe``).
"""

from __future__ import annotations

import ast
import sys
from collections.abc import Iterator
from pathlib import Path

_OWN = {"self", "cls"}
_STDLIB = {"sys", "os"}


def _private(name: str) -> bool:
    return name.startswith("_") and not name.startswith("__")


def places(path: Path) -> Iterator[tuple[int, str]]:
    tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and _private(node.attr):
            owner = node.value
            if isinstance(owner, ast.Name) and (owner.id in _OWN or owner.id in _STDLIB):
                continue
            yield node.lineno, ast.unparse(node)
        elif isinstance(node, ast.ImportFrom):
            for alias in node.names:
                if _private(alias.name):
                    yield node.lineno, f"from {'.' * node.level}{node.module or ''} import {alias.name}"


def main(argv: list[str]) -> int:
    total = 0
    for d in argv or ["rcon_core"]:
        for path in sorted(Path(d).rglob("*.py")):
            for line, text in places(path):
                print(f"{path}:{line}: {text}")
                total += 1
    print(f"{total} place(s)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
