"""Children of a widget (a Compound's children), Qt-free: the part of the plugin contract a children
editor and a compound model both use.

A settings field is a *children field* when it is a ``list`` of an attrs class with the fields
``kind: str``, ``field_path: str`` and ``settings: dict`` (and optionally ``title: str``)
(:func:`children_item_class`); see ``docs/writing-a-widget-plugin.md``.

* :func:`child_role`: a child fills what the parent sends and shows what it receives;
* :class:`ChildCatalog`: the fields of the parent's bound type (:func:`rcon_core.msgs.walk_fields`), the
  kinds that fit each (:func:`rcon_core.matcher.match`) and where each child sits;
* :func:`child_name`, :func:`child_problems` (:func:`kind_problems`, :func:`role_problem`): how a child is
  named and checked, shared by the catalog, a compound's settings and a compound's model;
* :func:`fetch_typedefs`: the robot's rosapi typedefs of a type the registry does not know yet;
* :func:`settings_problems`: a settings instance's own ``problems()``, a broken one reported, not raised.

The Qt editor is :mod:`rcon_core.app.children_editor`.
"""

from __future__ import annotations

import concurrent.futures
from collections.abc import Callable
from typing import Any

import attrs

from rcon_core.matcher import Match, Rank, match
from rcon_core.msgs import names, walk_fields
from rcon_core.plugins.api import settings_problems as api_settings_problems
from rcon_core.plugins.api import stored_settings_problems
from rcon_core.plugins.context import WidgetCatalog
from rcon_core.plugins.model import Binding
from rcon_core.plugins.model_types import ModelTypes
from rcon_core.plugins.paths import PathError, split_service_path
from rcon_core.plugins.spec import Role, WidgetSpec

__all__ = [
    "CHILD_FIELDS", "ChildCatalog", "ChildContext", "FieldChoice", "KindChoice", "Learn", "child_name",
    "child_problems", "child_role", "children_item_class", "fetch_typedefs", "kind_problems", "paths_overlap",
    "role_problem", "settings_problems", "short_type",
]

#: the fields an attrs class needs to describe one child
CHILD_FIELDS = ("kind", "field_path", "settings")

#: learn(type_name, is_service) -> future of [(root type name, rosapi typedefs), ...]
Learn = Callable[[str, bool], "concurrent.futures.Future[list[tuple[str, list[dict[str, Any]]]]]"]


# ------------------------------------------------------------------------------------------ declaring
def children_item_class(tp: Any) -> type | None:
    """The child class if ``tp`` (a settings field's type) declares children: ``list[C]``, C an attrs
    class with ``kind``, ``field_path`` and ``settings``. Else None."""
    import typing

    if typing.get_origin(tp) not in (list, typing.List):  # noqa: UP006 - both spellings
        return None
    args = typing.get_args(tp)
    if len(args) != 1 or not attrs.has(args[0]):
        return None
    cls = args[0]
    if isinstance(cls, type) and all(name in attrs.fields_dict(cls) for name in CHILD_FIELDS):
        return cls
    return None


def child_role(parent: Role, part: str = "") -> Role:
    """The role a child gets: it fills what the parent sends (publish, a call's request, a served
    response) and shows what the parent receives (subscribe, a call's response, a served request)."""
    if parent is Role.PUBLISH or (parent is Role.CALL and part == "request") or (
            parent is Role.SERVE and part == "response"):
        return Role.PUBLISH
    return Role.SUBSCRIBE


@attrs.define
class ChildContext:
    """What the children editor needs from its surroundings."""

    types: ModelTypes  #: the app's type registry
    plugins: WidgetCatalog  #: the enabled widget kinds (the app's plugin manager)
    binding: Callable[[], Binding | None]  #: the parent widget's binding, as currently chosen
    learn: Learn | None = None  #: fetches typedefs from the robot (None: offline)


# ------------------------------------------------------------------------------------------ catalog
@attrs.frozen
class FieldChoice:
    """A place a child can be bound to."""

    path: str  #: the child's ``field_path`` (services: starts with request/response)
    type: str  #: the field's type: a canonical message name or a builtin (``float64``, ``string[]``)
    is_message: bool
    part: str  #: "" for topics, "request" / "response" for services
    part_type: str  #: the message type the child is bound to
    rest: str  #: the path inside ``part_type`` ("" = all of it)
    role: Role  #: the child's role

    @property
    def label(self) -> str:
        return self.path or "the whole message"

    @property
    def type_label(self) -> str:
        return short_type(self.type)


@attrs.frozen
class KindChoice:
    spec: WidgetSpec
    rank: Rank
    reason: str = ""


def short_type(name: str) -> str:
    """``geometry_msgs/msg/Vector3`` -> ``Vector3``; builtins as they are."""
    return name.rsplit("/", 1)[-1] if "/" in name else name


def _join(prefix: str, name: str) -> str:
    return f"{prefix}.{name}" if prefix else name


class ChildCatalog:
    """Fields of the parent's bound type, the kinds that fit each, and each child's problems (no Qt)."""

    def __init__(self, types: ModelTypes, plugins: WidgetCatalog, binding: Binding | None, exclude: tuple[str, ...] = ()) -> None:
        self.types, self.plugins, self.binding = types, plugins, binding
        self.exclude = set(exclude)
        self._matches: dict[tuple[str, Role], list[Match]] = {}
        self._fields: list[FieldChoice] | None = None

    # -- the type ----------------------------------------------------------------------------------
    @property
    def type_name(self) -> str:
        return self.binding.type if self.binding is not None else ""

    @property
    def is_service(self) -> bool:
        return self.binding is not None and self.binding.role.is_service

    def known(self) -> bool:
        """Whether the registry knows the bound type (else it must be learned from the robot)."""
        if not self.type_name:
            return False
        try:
            return bool(self.types.has_service(self.type_name) if self.is_service else self.types.has(self.type_name))
        except ValueError:
            return False

    def parts(self) -> list[tuple[str, str, Role]]:
        """(part, message type, child role) for each side the children can sit on."""
        assert self.binding is not None
        role = self.binding.role
        if role.is_service:
            return [(p, self.types.service_part_name(self.type_name, p), child_role(role, p))
                    for p in ("request", "response")]
        return [("", self.types.resolve(self.type_name), child_role(role))]

    # -- fields ------------------------------------------------------------------------------------
    def all_fields(self) -> list[FieldChoice]:
        """Every place a child can sit: each part as a whole, each nested message and each leaf."""
        if self._fields is None:
            out: list[FieldChoice] = []
            for part, part_type, role in self.parts():
                out.append(FieldChoice(part, part_type, True, part, part_type, "", role))
                for step in walk_fields(self.types, part_type):
                    f = step.field
                    tp = f.type if f.is_builtin else f.base
                    out.append(FieldChoice(_join(part, step.path), tp, step.is_message, part, part_type,
                                           step.path, role))
            self._fields = out
        return self._fields

    def fields(self) -> list[FieldChoice]:
        """The places at least one installed widget fits, in definition order."""
        return [c for c in self.all_fields() if self.kinds_for(c)]

    def choice(self, path: str) -> FieldChoice | None:
        return next((c for c in self.all_fields() if c.path == path), None)

    # -- kinds -------------------------------------------------------------------------------------
    def _match(self, type_name: str, role: Role) -> list[Match]:
        key = (type_name, role)
        if key not in self._matches:
            self._matches[key] = match(type_name, role, self.types, self.plugins)
        return self._matches[key]

    def kinds_for(self, choice: FieldChoice) -> list[KindChoice]:
        """The widgets that fit ``choice`` in the child's role, best first.

        A leaf fits the widgets whose structural predicates pick that path of the part type; a message
        (or a whole part) fits the widgets taking that message type whole: listed exactly or by
        package, a message predicate on it, or a generic (``any``) widget.
        """
        best: dict[str, KindChoice] = {}

        def offer(m: Match) -> None:
            if m.spec.kind in self.exclude:
                return
            old = best.get(m.spec.kind)
            if old is None or m.rank < old.rank:
                best[m.spec.kind] = KindChoice(m.spec, m.rank, m.reason)

        if choice.rest:
            for m in self._match(choice.part_type, choice.role):
                if choice.rest in m.field_paths:
                    offer(m)
        if choice.is_message:
            for m in self._match(choice.type, choice.role):
                whole = ("" in m.field_paths or (m.rank in (Rank.EXACT, Rank.PACKAGE) and not m.field_path)
                         or "any" in m.spec.accepts.messages)
                if whole:
                    offer(m)
        return sorted(best.values(), key=lambda k: (k.rank, self._breadth(k.spec, choice), -k.spec.priority,
                                                    k.spec.title.lower(), k.spec.kind))

    @staticmethod
    def _breadth(spec: WidgetSpec, choice: FieldChoice) -> int:
        """How many kinds of field ``spec`` takes, for a leaf: of two widgets that fit a float64 equally
        well, the one made for numbers (Slider: numeric) ranks above the one for anything (Text Field:
        numeric, string, bool, time). 0 for messages (no tie to break this way)."""
        if choice.is_message or not choice.rest:
            return 0
        return len(spec.accepts.fields) or 99

    # -- checking ----------------------------------------------------------------------------------
    def spec_of(self, kind: str) -> WidgetSpec | None:
        return self.plugins.widget(kind) if kind and self.plugins.has_widget(kind) else None

    def child_name(self, index: int, item: Any) -> str:
        """``child 2 (Slider) on linear.x``: how problems name a child."""
        return child_name(index + 1, item, self.spec_of(item.kind))

    def placement_problems(self, item: Any) -> list[str]:
        """What is wrong with where the child sits: no such widget, no such field, a kind that does
        not fit the field. Empty while the bound type is unknown (nothing to check against yet)."""
        spec = self.spec_of(item.kind)
        if spec is None:
            return kind_problems(item, spec)
        if item.kind in self.exclude:
            return [f"{spec.title} cannot be a child here"]
        if self.binding is None or not self.known():
            return []
        if self.is_service:
            try:
                split_service_path(item.field_path)
            except PathError as exc:
                return [str(exc)]
        choice = self.choice(item.field_path)
        if choice is None:
            return [f"{self.type_name} has no field {item.field_path!r}"]
        if not any(k.spec.kind == item.kind for k in self.kinds_for(choice)):
            return [f"{role_problem(spec, choice.role)} {choice.label} ({choice.type_label})"]
        return []

    def settings_problems(self, item: Any) -> list[str]:
        spec = self.spec_of(item.kind)
        return stored_settings_problems(spec, item.settings, self.plugins) if spec is not None else []

    def child_binding(self, index: int, item: Any) -> Binding | None:
        """The binding the child's model gets (part type, child role, path inside the part)."""
        if self.binding is None or not self.known():
            return None
        choice = self.choice(item.field_path)
        if choice is None:
            return None
        return Binding(f"{self.binding.name}#{index + 1}", choice.part_type, choice.role,
                       (choice.rest,) if choice.rest else ())


# ------------------------------------------------------------------------------------------ checking
# The checks every holder of children shares (the children editor's catalog above, a compound's settings
# and its model): how a child is named, and what is wrong with its kind, its role and its settings.
def child_name(number: int, item: Any, spec: WidgetSpec | None) -> str:
    """``child 2 (Slider) on linear.x``: how problems name child ``number`` (from 1): its title, else its
    widget's title, else its kind."""
    what = getattr(item, "title", "") or (spec.title if spec is not None else item.kind or "?")
    return f"child {number} ({what}) on {item.field_path or 'the whole message'}"


def kind_problems(item: Any, spec: WidgetSpec | None) -> list[str]:
    """What is wrong with the child's kind: none chosen, or no installed package offers it (``spec`` is
    the kind's spec, None when unknown)."""
    if not item.kind:
        return ["no widget chosen"]
    return [f"no installed widget package offers {item.kind!r}"] if spec is None else []


def role_problem(spec: WidgetSpec, role: Role) -> str:
    """``Label cannot publish``: a child of this kind cannot take the role its place gives it."""
    return f"{spec.title} cannot {role.value}"


def child_problems(item: Any, spec: WidgetSpec | None, role: Role | None = None) -> list[str]:
    """Everything wrong with a child that needs no message type: its kind, its role (when ``role``, the
    role its place gives it, is known) and its own settings. Unnamed: prefix :func:`child_name`."""
    out = kind_problems(item, spec)
    if spec is None:
        return out
    if role is not None and role not in spec.roles:
        out.append(role_problem(spec, role))
    return out + spec.settings_problems(item.settings)


# ------------------------------------------------------------------------------------------ learning
async def fetch_typedefs(rosapi: Any, type_name: str, service: bool) -> list[tuple[str, list[dict[str, Any]]]]:
    """The robot's rosapi typedefs of a message or service type, as (root name, typedefs) pairs."""
    if service:
        out = []
        for part in ("request", "response"):
            fn = getattr(rosapi, f"service_{part}_details")
            out.append((names.part_name(type_name, part), await fn(type_name)))
        return out
    return [(names.normalize(type_name), await rosapi.message_details(type_name))]


def paths_overlap(a: str, b: str) -> bool:
    """Two children on ``a`` and ``b`` would set the same value: the same field, or one inside the other
    (``linear`` and ``linear.x``; ``""``, the whole message, holds every field)."""
    return a == b or not a or not b or a.startswith(f"{b}.") or b.startswith(f"{a}.") or a.startswith(
        f"{b}[") or b.startswith(f"{a}[")


def settings_problems(settings: Any, catalog: WidgetCatalog | None = None) -> list[str]:
    """The settings' own ``problems()`` (:func:`rcon_core.plugins.api.settings_problems`: checked against
    ``catalog`` when they need the other kinds, a broken one reported, not raised)."""
    return api_settings_problems(settings, catalog)
