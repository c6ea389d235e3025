"""A ROS parameter server: a tree of values addressed by slash-separated names."""

from __future__ import annotations

import copy
from typing import Any


def _parts(name: str) -> list[str]:
    return [p for p in name.strip().split("/") if p]


class ParamTree:
    """Nested dicts; a namespace reads back as a dict of everything below it."""

    def __init__(self, initial: dict[str, Any] | None = None) -> None:
        self._root: dict[str, Any] = {}
        for name, value in (initial or {}).items():
            self.set(name, value)

    def set(self, name: str, value: Any) -> None:
        parts = _parts(name)
        if not parts:
            if isinstance(value, dict):
                self._root = copy.deepcopy(value)
            return
        node = self._root
        for part in parts[:-1]:
            child = node.get(part)
            if not isinstance(child, dict):
                child = node[part] = {}
            node = child
        node[parts[-1]] = copy.deepcopy(value)

    def _lookup(self, name: str) -> tuple[bool, Any]:
        node: Any = self._root
        for part in _parts(name):
            if not isinstance(node, dict) or part not in node:
                return False, None
            node = node[part]
        return True, node

    def has(self, name: str) -> bool:
        return self._lookup(name)[0]

    def get(self, name: str, default: Any = None) -> Any:
        found, value = self._lookup(name)
        return copy.deepcopy(value) if found else default

    def delete(self, name: str) -> bool:
        parts = _parts(name)
        if not parts:
            return False
        found, parent = self._lookup("/".join(parts[:-1]))
        if found and isinstance(parent, dict) and parts[-1] in parent:
            del parent[parts[-1]]
            return True
        return False

    def names(self) -> list[str]:
        """Every leaf's full name (dicts are namespaces, as in ROS)."""
        out: list[str] = []

        def walk(prefix: str, node: dict[str, Any]) -> None:
            for key, value in node.items():
                full = f"{prefix}/{key}"
                if isinstance(value, dict) and value:
                    walk(full, value)
                else:
                    out.append(full)

        walk("", self._root)
        return out
