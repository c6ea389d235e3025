"""Which widgets fit a type and a role, ranked, with the field path each would bind.

::

    from rcon_core.matcher import match
    for m in match("sensor_msgs/BatteryState", "subscribe", types, pm):
        print(m.rank.name, m.spec.kind, m.field_path)     # STRUCTURAL std.slider percentage ...

Ranking, best first:

1. ``EXACT``: the type is listed in ``Accepts.types`` (either spelling);
2. ``PACKAGE``: the type's package is listed in ``Accepts.packages``;
3. ``STRUCTURAL``: a field or message predicate fits some part of the definition;
4. ``GENERIC``: the widget accepts any message (``messages=["any"]``), e.g. a Text View.

Within a rank, higher ``WidgetSpec.priority`` first,
then title. Structural matching needs the definition: the registry must know the type (standard types,
plugin contributions, or ``types.add_typedefs(...)`` from a server). An unknown type still gets exact,
package and generic matches. Services (roles CALL and SERVE) match on the request/response definitions;
their paths start with ``request``/``response``. A foreign type (a Foxglove schema such as
``foxglove.CompressedImage``) matches as its ROS equivalent, or gets the any-message widgets
(``rcon_core.msgs.foreign``). Actions (role ACTION, type ``pkg/action/X``) match on
the goal, feedback and result definitions (``Accepts.action_parts``); their paths start with
``goal``/``feedback``/``result``.
"""

from __future__ import annotations

import enum
from collections.abc import Iterator
from typing import Any

import attrs

from rcon_core.msgs import foreign, names, walk_fields
from rcon_core.msgs.walk import own_fields
from rcon_core.plugins.context import WidgetCatalog
from rcon_core.plugins.model_types import ModelTypes
from rcon_core.plugins.spec import (
    ACTION_PARTS,
    FIELD_PREDICATES,
    MESSAGE_PREDICATES,
    Accepts,
    FieldLike,
    FieldPredicate,
    MessagePredicate,
    Role,
    WidgetSpec,
)

__all__ = ["match", "Match", "Rank", "candidate_paths"]

#: used when a widget gives no ``prefer`` list: the usual names of "the value" of a message
DEFAULT_PREFER = ("data", "value", "percentage", "position", "x")


class Rank(enum.IntEnum):
    EXACT = 0
    PACKAGE = 1
    STRUCTURAL = 2
    GENERIC = 3


@attrs.frozen
class Match:
    """One widget that fits. ``field_path`` is what a new instance binds by default (``""`` = whole
    message); ``field_paths`` lists every path that fits, best first; ``reason`` is for people."""

    spec: WidgetSpec
    rank: Rank
    field_path: str = ""
    field_paths: tuple[str, ...] = ()
    reason: str = ""

    @property
    def kind(self) -> str:
        return self.spec.kind

    def to_dict(self) -> dict[str, Any]:
        return {
            "kind": self.spec.kind,
            "title": self.spec.title,
            "package": self.spec.package,
            "rank": self.rank.name.lower(),
            "field_path": self.field_path,
            "field_paths": list(self.field_paths),
            "reason": self.reason,
        }


@attrs.frozen
class _Node:
    """A (sub)message or a leaf field in the flattened definition."""

    path: str
    type: str  # canonical message name, or the leaf's base type
    field: Any = None  # FieldDef for leaves and nested fields; None for the roots
    fields: tuple[Any, ...] = ()  # the message's own fields (messages only)


def _walk(types: ModelTypes, type_name: str, prefix: str) -> Iterator[tuple[str, _Node]]:
    """Yield ("message", node) for the message and every scalar nested message, ("leaf", node) for
    every builtin field (scalars and arrays): :func:`rcon_core.msgs.walk_fields`, with each message's
    own fields for the message predicates."""
    yield "message", _Node(prefix, type_name, None, own_fields(types, type_name))
    for step in walk_fields(types, type_name, prefix):
        f = step.field
        if f.is_builtin:
            yield "leaf", _Node(step.path, f.base, f)
        else:
            yield "message", _Node(step.path, f.base, f, own_fields(types, f.base))


def _roots(types: ModelTypes, type_name: str, role: Role, acc: Accepts) -> list[tuple[str, str]]:
    """(path prefix, message type) to search: the message itself, the service parts in role order, or
    the action's parts (goal, feedback, result)."""
    if role.is_action:
        return [(p, types.action_part_name(type_name, p)) for p in ACTION_PARTS if p in acc.action_parts]
    if not role.is_service:
        return [("", types.resolve(type_name))]
    order = ("request", "response") if role is Role.CALL else ("response", "request")
    return [(p, types.service_part_name(type_name, p)) for p in order if p in acc.service_parts]


def _field_fits(pred: str | FieldPredicate, field: FieldLike) -> bool:
    """Whether a field predicate (a name from FIELD_PREDICATES, checked by Accepts, or a callable) fits."""
    fn = FIELD_PREDICATES[pred] if isinstance(pred, str) else pred
    try:
        return bool(fn(field))
    except Exception:  # a custom predicate that raises does not fit (and does not break matching)
        return False


def _message_fits(pred: str | MessagePredicate, type_name: str, fields: list[FieldLike]) -> bool:
    """Whether a message predicate (a name from MESSAGE_PREDICATES, checked by Accepts, or a callable) fits."""
    fn = MESSAGE_PREDICATES[pred] if isinstance(pred, str) else pred
    try:
        return bool(fn(type_name, fields))
    except Exception:  # a custom predicate that raises does not fit (and does not break matching)
        return False


def candidate_paths(spec: WidgetSpec, role: Role | str, type_name: str, types: ModelTypes) -> list[str]:
    """Every path of ``type_name`` the spec's structural predicates fit, best first.

    Raises the registry's UnknownTypeError when the type (or a type it uses) is unknown.
    """
    role = Role.parse(role)
    acc = spec.accepts
    field_preds = acc.fields
    msg_preds = [p for p in acc.messages if p != "any"]
    found: list[str] = []
    if not field_preds and not msg_preds:
        return found
    for prefix, root in _roots(types, type_name, role, acc):
        for kind, node in _walk(types, root, prefix):
            if kind == "leaf" and any(_field_fits(p, node.field) for p in field_preds):
                found.append(node.path)
            elif kind == "message" and any(_message_fits(p, node.type, list(node.fields)) for p in msg_preds):
                found.append(node.path)
    prefer = acc.prefer or DEFAULT_PREFER
    return sorted(found, key=lambda p: _path_key(p, prefer, found))


def _path_key(path: str, prefer: tuple[str, ...], order: list[str]) -> tuple[int, bool, int, int]:
    """Preferred names first, then anything outside a ``header`` (metadata), then shallow paths."""
    parts = path.split(".") if path else []
    last = parts[-1] if parts else ""
    pref = prefer.index(last) if last in prefer else len(prefer)
    return (pref, "header" in parts[:-1], path.count("."), order.index(path))


def _canonical_names(type_name: str, role: Role) -> set[str]:
    """The spellings a widget may have listed this type under (canonical forms)."""
    try:
        pkg, _kind, typ = names.split(type_name)
    except ValueError:
        return {type_name}
    kind = "action" if role.is_action else "srv" if role.is_service else "msg"
    return {f"{pkg}/{kind}/{typ}", names.normalize(type_name)}


def _listed(spec_types: tuple[str, ...], wanted: set[str], role: Role) -> bool:
    for t in spec_types:
        try:
            if _canonical_names(t, role) & wanted:
                return True
        except ValueError:
            continue
    return False


def _match_one(spec: WidgetSpec, role: Role, type_name: str, types: ModelTypes, wanted: set[str]) -> Match | None:
    acc = spec.accepts
    package = type_name.strip("/").split("/")[0]
    try:
        paths = candidate_paths(spec, role, type_name, types) if types is not None else []
        known = True
    except (KeyError, ValueError):
        paths, known = [], False
    first = paths[0] if paths else ""
    if _listed(acc.types, wanted, role):
        return Match(spec, Rank.EXACT, first, tuple(paths), f"lists {type_name}")
    if package in acc.packages:
        return Match(spec, Rank.PACKAGE, first, tuple(paths), f"accepts every {package} type")
    if paths:
        return Match(spec, Rank.STRUCTURAL, first, tuple(paths), f"fits field {first or '(whole message)'}")
    if "any" in acc.messages:
        why = "accepts any message" if known else "accepts any message (definition unknown)"
        return Match(spec, Rank.GENERIC, "", (), why)
    return None


def _generic_only(role: Role, plugin_manager: WidgetCatalog) -> list[Match]:
    found = [Match(spec, Rank.GENERIC, "", (), "accepts any message (a foreign type)")
             for spec in plugin_manager.widgets() if role in spec.roles and "any" in spec.accepts.messages]
    found.sort(key=lambda m: (-m.spec.priority, m.spec.title.lower(), m.spec.kind))
    return found


def match(type_name: str, role: Role | str, types: ModelTypes, plugin_manager: WidgetCatalog) -> list[Match]:
    """The widgets that fit ``type_name`` in ``role``, best first (see the module docstring).

    ``types`` is an ``rcon_core.msgs.TypeRegistry`` (or None: name-based matches only);
    ``plugin_manager`` anything with ``widgets() -> list[WidgetSpec]``. Raises ValueError for a
    malformed type name or role.
    """
    role = Role.parse(role)
    if foreign.is_foreign(type_name):  # a Foxglove/protobuf/JSON type: as its ROS equivalent, else any-message
        equivalent = foreign.ros_equivalent(type_name)
        if equivalent is None:
            return _generic_only(role, plugin_manager)
        type_name = equivalent
    names.split(type_name)  # ValueError with a clear message for a malformed name
    wanted = _canonical_names(type_name, role)
    found: list[Match] = []
    for spec in plugin_manager.widgets():
        if role not in spec.roles:
            continue
        m = _match_one(spec, role, type_name, types, wanted)
        if m is not None:
            found.append(m)
    found.sort(key=lambda m: (m.rank, -m.spec.priority, m.spec.title.lower(), m.spec.kind))
    return found
