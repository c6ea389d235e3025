"""Field paths into plain-dict messages: ``"pose.position.x"``, ``"ranges[3]"``, ``""`` (the whole message).

Used by widget models to read the bound field from a message and to write a value into a message to
publish. Service paths carry their side as the first component (``"request.data"``); models strip it
with :func:`split_service_path` before applying the rest to the request or response dict.
"""

from __future__ import annotations

import re
from typing import Any

__all__ = ["parse_path", "get_path", "set_path", "split_service_path", "PathError"]

_TOKEN = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)|\[(\d+)\]")


class PathError(LookupError):
    """The path is malformed or does not exist in the message; ``str()`` names the failing part."""


def parse_path(path: str) -> list[str | int]:
    """``"a.b[2].c"`` -> ``["a", "b", 2, "c"]``; ``""`` -> ``[]``. Raises PathError when malformed."""
    out: list[str | int] = []
    if not path:
        return out
    pos = 0
    expect_name = True
    while pos < len(path):
        if path[pos] == "." and not expect_name and out:
            pos += 1
            expect_name = True
            continue
        m = _TOKEN.match(path, pos)
        if not m or (m.group(1) and not expect_name):
            raise PathError(f"malformed field path {path!r} at character {pos + 1}")
        if m.group(1):
            out.append(m.group(1))
        else:
            out.append(int(m.group(2)))
        expect_name = False
        pos = m.end()
    if expect_name:
        raise PathError(f"malformed field path {path!r}: ends with '.'")
    return out


def get_path(msg: Any, path: str) -> Any:
    """The value at ``path`` in ``msg``; PathError says which part is missing."""
    cur = msg
    done = ""
    for part in parse_path(path):
        try:
            cur = cur[part]
        except (KeyError, IndexError, TypeError):
            where = f" in {done!r}" if done else ""
            raise PathError(f"field {part!r}{where} not found (path {path!r})") from None
        done = f"{done}[{part}]" if isinstance(part, int) else (f"{done}.{part}" if done else part)
    return cur


def set_path(msg: dict[str, Any], path: str, value: Any) -> dict[str, Any]:
    """Set ``path`` in ``msg`` in place (creating missing dicts) and return ``msg``. ``""`` is refused."""
    parts = parse_path(path)
    if not parts:
        raise PathError("cannot set the empty path: replace the whole message instead")
    cur: Any = msg
    for part in parts[:-1]:
        try:
            cur = cur[part]
        except KeyError:
            cur[part] = {}
            cur = cur[part]
        except (IndexError, TypeError):
            raise PathError(f"cannot descend into {part!r} (path {path!r})") from None
    try:
        cur[parts[-1]] = value
    except (IndexError, TypeError):
        raise PathError(f"cannot set {parts[-1]!r} (path {path!r})") from None
    return msg


def split_service_path(path: str) -> tuple[str, str]:
    """``"request.data"`` -> ``("request", "data")``; ``"response"`` -> ``("response", "")``."""
    head, _, rest = path.partition(".")
    if head not in ("request", "response"):
        raise PathError(f"service field path {path!r} must start with 'request' or 'response'")
    return head, rest
