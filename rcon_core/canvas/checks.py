"""What a layout file may hold, checked before anything is built from it.

A layout file is untrusted input: hand edits, a half-synced copy, a file from another tool. Everything
here turns what is wrong into a sentence that says where (which canvas, which widget, which key) and
what was found, so the store can report it on the banner and keep the file as it is.

* :func:`check_tree` walks the parsed JSON once, without recursion: nesting at most :data:`MAX_DEPTH`
  levels, every number finite (no ``NaN``/``Infinity``, nothing that overflows to infinity).
* :func:`strict_bool`, :func:`strict_str` and :func:`coordinate` are the converter's rules for single
  values: a boolean is ``true`` or ``false`` (never ``"no"``), a string is a string, a coordinate is a
  finite number within :data:`COORD_LIMIT`.
* :func:`where` names the place of a cattrs error path (``canvases[0].widgets[3].geometry``) after the
  canvas and widget it points at.
"""

from __future__ import annotations

import math
import re
from typing import Any

__all__ = ["MAX_DEPTH", "COORD_LIMIT", "MAX_PROBLEMS", "check_tree", "TreeProblem", "strict_bool", "strict_str",
           "coordinate", "path_text", "where", "found", "summarize"]

#: how deeply a layout file may nest (a real one nests about 6 levels; settings add a few)
MAX_DEPTH = 64
#: the largest coordinate or size on a canvas, in canvas units (a canvas is never that large)
COORD_LIMIT = 100_000.0
#: how many problems a message lists before "and N more"
MAX_PROBLEMS = 3
#: how much of a bad value a message quotes
_QUOTE = 40


def found(value: Any) -> str:
    """A short, bounded description of a value for a problem sentence (never formats a deep structure)."""
    if isinstance(value, dict):
        return f"an object with {len(value)} key(s)"
    if isinstance(value, list):
        return f"a list of {len(value)} item(s)"
    text = repr(value)
    return text if len(text) <= _QUOTE else text[: _QUOTE - 3] + "..."


def path_text(path: list[str | int]) -> str:
    """``["canvases", 0, "locked"]`` as ``canvases[0].locked`` (the way cattrs writes paths)."""
    out = ""
    for part in path:
        if isinstance(part, str) and len(part) > _QUOTE:
            part = part[: _QUOTE - 3] + "..."
        out += f"[{part}]" if isinstance(part, int) else f".{part}" if out else str(part)
    return out or "the top level"


class TreeProblem(ValueError):
    """What :func:`check_tree` found, and where (``path``: keys and indexes from the top)."""

    def __init__(self, path: list[str | int], problem: str) -> None:
        self.path = path
        self.problem = problem
        super().__init__(f"{path_text(path)}: {problem}")


def _bad(item: Any, depth: int) -> str | None:
    if type(item) is dict or type(item) is list:
        return f"is nested deeper than {MAX_DEPTH} levels" if depth >= MAX_DEPTH else None
    if type(item) is float and item - item != 0.0:  # NaN or an infinity
        return f"is not a finite number (found {item!r})"
    return None


def check_tree(data: Any) -> None:
    """Raise :class:`TreeProblem` when ``data`` nests deeper than :data:`MAX_DEPTH` or holds a number
    that is not finite. Iterative (a hostile file cannot exhaust the stack), linear in the size."""
    stack: list[tuple[Any, int]] = [(data, 1)] if type(data) is dict or type(data) is list else []
    while stack:
        value, depth = stack.pop()
        for item in value.values() if type(value) is dict else value:
            kind = type(item)
            if kind is dict or kind is list:
                if depth >= MAX_DEPTH:
                    _locate(data)
                stack.append((item, depth + 1))
            elif kind is float and item - item != 0.0:
                _locate(data)


def _locate(data: Any) -> None:
    """The slow second pass, run only when something is wrong: find the first problem's path."""
    stack: list[tuple[Any, int, list[str | int]]] = [(data, 1, [])]
    while stack:
        value, depth, path = stack.pop()
        for key, item in value.items() if type(value) is dict else enumerate(value):
            problem = _bad(item, depth)
            if problem is not None:
                raise TreeProblem([*path, key], problem)
            if type(item) is dict or type(item) is list:
                stack.append((item, depth + 1, [*path, key]))
    raise AssertionError("check_tree found a problem that _locate did not")  # pragma: no cover


def strict_bool(value: Any, what: str = "") -> bool:
    if not isinstance(value, bool):
        raise ValueError(f"{what} must be true or false, found {found(value)}".lstrip())
    return value


def strict_str(value: Any, what: str = "") -> str:
    if not isinstance(value, str):
        raise ValueError(f"{what} must be a string, found {found(value)}".lstrip())
    return value


def coordinate(value: Any, what: str, *, size: bool = False) -> float:
    """A finite number within ``±COORD_LIMIT`` (``0..COORD_LIMIT`` for a ``size``)."""
    if type(value) is float and -COORD_LIMIT <= value <= COORD_LIMIT and (value >= 0.0 or not size):
        return value  # the common case, quickly (NaN fails the comparisons)
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"{what} must be a number, found {found(value)}")
    try:
        number = float(value)
    except OverflowError:  # an int too large for a float
        number = math.inf
    low = 0.0 if size else -COORD_LIMIT
    if not (math.isfinite(number) and low <= number <= COORD_LIMIT):
        raise ValueError(f"{what} must be between {low:g} and {COORD_LIMIT:g}, found {found(value)}")
    return number


_PATH = re.compile(r"^canvases\[(\d+)\](?:\.widgets\[(\d+)\])?\.?(.*)$")


def _named(obj: Any, kind: str) -> str:
    if not isinstance(obj, dict):
        return kind
    ident = obj.get("id")
    label = obj.get("name") if kind == "canvas" else obj.get("title") or obj.get("kind")
    parts = [kind]
    if isinstance(label, str) and label:
        parts.append(found(label))
    if isinstance(ident, str) and ident:
        parts.append(f"({found(ident)})")
    return " ".join(parts)


def where(path: str, data: Any) -> tuple[str, str] | None:
    """Where a cattrs error path (``canvases[0].widgets[3].geometry``) points, named after the canvas
    and widget in the raw ``data``: ``("canvas 'Main' ('c-1') (#1), widget 'Speed' ('w-2') (#4)",
    "geometry")``; None for a path outside the canvases."""
    m = _PATH.match(path)
    if m is None or not isinstance(data, dict) or not isinstance(data.get("canvases"), list):
        return None
    canvases = data["canvases"]
    ci = int(m.group(1))
    canvas = canvases[ci] if ci < len(canvases) else None
    place = f"{_named(canvas, 'canvas')} (#{ci + 1})"
    if m.group(2) is not None:
        wi = int(m.group(2))
        widgets = canvas.get("widgets") if isinstance(canvas, dict) else None
        widget = widgets[wi] if isinstance(widgets, list) and wi < len(widgets) else None
        place += f", {_named(widget, 'widget')} (#{wi + 1})"
    return place, m.group(3)


def summarize(problems: list[str]) -> str:
    """At most :data:`MAX_PROBLEMS` sentences, then how many more there are."""
    shown = "; ".join(problems[:MAX_PROBLEMS])
    more = len(problems) - MAX_PROBLEMS
    return f"{shown}; and {more} more problem(s)" if more > 0 else shown
