"""Re-targeting a canvas to another robot: which names its widgets use there. Pure (no Qt, no network).

A canvas duplicated for another robot (``Document.duplicate_for_robot``) talks to that robot. A robot that
runs in a namespace (``rcon sim --name boat2``: ``/boat2/cmd_vel``, ``/boat2/gps/fix``) does not have the
names of the original (``/cmd_vel``, ``/gps/fix``): a copy bound to them shows NO DATA and a pad on it
drives nothing. :func:`plan_retarget` maps each name through the target robot's namespace, found in the
target's own list of topics, services and actions (its catalogue), and lists what the target does not have
at all, so the app can say so before the copy is made.

How a name is mapped, for each name the widgets use (their bindings, and topic names in their settings,
such as a switch's ``state_topic``):

1. the target has the name itself: kept (the bridge's ``/rosout``, a robot without a namespace);
2. else the name without the source's namespace (``/boat1/cmd_vel`` -> ``/cmd_vel``), under each of the
   target's namespaces that hold it (``/boat2/cmd_vel``): the namespace that explains the most names is
   the target's, and every name found under it is mapped there;
3. else it is *missing*: kept as it is, and listed.

Without the target's catalogue (the robot is not connected) nothing can be checked: ``checked`` is False
and every name is kept.
"""

from __future__ import annotations

import collections
import re
from collections.abc import Iterable
from typing import Any

import attrs

__all__ = ["RetargetPlan", "plan_retarget", "setting_names", "rename_settings"]

_NAME = re.compile(r"^/[A-Za-z_~][A-Za-z0-9_/~]*$")


@attrs.frozen
class RetargetPlan:
    """``renames``: name on the source -> name on the target (only names that change); ``missing``: names
    the target has neither as they are nor under its namespace; ``namespace``: the target's namespace used
    (``"/boat2"``, or ``""``); ``checked``: the target's names were known."""

    renames: dict[str, str] = attrs.field(factory=dict)
    missing: tuple[str, ...] = ()
    namespace: str = ""
    checked: bool = True

    @property
    def quiet(self) -> bool:
        """Nothing to tell the operator: every name exists on the target as it is."""
        return self.checked and not self.renames and not self.missing

    def describe(self, robot: str) -> str:
        """What the copy will talk to on ``robot``, in a few lines (for the question before it is made)."""
        lines = []
        if not self.checked:
            lines.append(f"{robot}'s topics are not known (is it connected?): the names were not checked.")
        if self.renames:
            where = f" in {robot}'s namespace {self.namespace}" if self.namespace else ""
            lines.append(f"Names mapped{where}:")
            lines += [f"  {a} → {b}" for a, b in sorted(self.renames.items())]
        if self.missing:
            lines.append(f"Not on {robot} (these widgets would show NO DATA or drive nothing):")
            lines += [f"  {name}" for name in self.missing]
        return "\n".join(lines)


def _namespace_of(name: str, catalogue: set[str]) -> list[str]:
    """The namespaces under which ``catalogue`` holds ``name`` (a relative tail of it too): ``/boat2``."""
    out = []
    parts = name.strip("/").split("/")
    for k in range(len(parts)):  # the name itself, then without its leading segments (a source namespace)
        tail = "/" + "/".join(parts[k:])
        for entry in catalogue:
            if entry == tail and k > 0:  # a namespaced name on a robot without one: /boat1/cmd_vel -> /cmd_vel
                out.append((k, ""))
            elif entry != tail and entry.endswith(tail):
                ns = entry[: -len(tail)]
                if ns.startswith("/") and _NAME.match(ns):
                    out.append((k, ns))
    # the fewest stripped segments first (keep as much of the name as the target has)
    return [ns for _k, ns in sorted(set(out))]


def plan_retarget(names: Iterable[str], target: Iterable[str] | None) -> RetargetPlan:
    """The plan for ``names`` (what the copied widgets use) on a target robot whose catalogue (every topic,
    service and action name) is ``target``; None: not known. See the module docstring."""
    wanted = [n for n in dict.fromkeys(names) if isinstance(n, str) and n]
    if target is None:
        return RetargetPlan(checked=False)
    have = set(target)
    unresolved = [n for n in wanted if n not in have]
    votes: collections.Counter[str] = collections.Counter()
    candidates: dict[str, list[str]] = {}
    for name in unresolved:
        found = _namespace_of(name, have)
        candidates[name] = found
        votes.update(set(found))
    renames: dict[str, str] = {}
    missing: list[str] = []
    best = votes.most_common(1)[0][0] if votes else None
    for name in unresolved:  # one namespace for the robot: a name found only elsewhere is not guessed at
        mapped = _under(name, best, have) if best is not None and best in candidates[name] else None
        if mapped is None:
            missing.append(name)
        else:
            renames[name] = mapped
    return RetargetPlan(renames, tuple(missing), best or "" if renames else "", True)


def _under(name: str, ns: str, have: set[str]) -> str | None:
    """``name`` (or its tail without leading segments) under ``ns``, when the target has it."""
    parts = name.strip("/").split("/")
    for k in range(len(parts)):
        candidate = ns + "/" + "/".join(parts[k:])
        if candidate in have:
            return candidate
    return None


def setting_names(settings: Any) -> list[str]:
    """ROS names in a widget's stored settings: every string that is one under a key naming a topic or a
    service (a switch's ``state_topic``, a pad's ``speed_limit_topic``, a Compound child's), nested dicts
    and lists walked. A path to a file is not a name here (its key says neither)."""
    out: list[str] = []
    stack: list[tuple[str, Any]] = [("", settings)]
    while stack:
        key, value = stack.pop()
        if isinstance(value, dict):
            stack.extend((str(k), v) for k, v in value.items())
        elif isinstance(value, list):
            stack.extend((key, v) for v in value)
        elif isinstance(value, str) and _NAME.match(value) and any(w in key.lower() for w in _NAME_KEYS):
            out.append(value)
    return out


_NAME_KEYS = ("topic", "service", "action")


def rename_settings(settings: Any, renames: dict[str, str], key: str = "") -> Any:
    """A copy of stored settings with each renamed name replaced (where :func:`setting_names` finds one)."""
    if isinstance(settings, dict):
        return {k: rename_settings(v, renames, str(k)) for k, v in settings.items()}
    if isinstance(settings, list):
        return [rename_settings(v, renames, key) for v in settings]
    if isinstance(settings, str) and any(w in key.lower() for w in _NAME_KEYS):
        return renames.get(settings, settings)
    return settings
