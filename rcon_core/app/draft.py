"""A widget being added: its kind, what it is bound to, and its settings, before it is on a canvas."""

from __future__ import annotations

from typing import Any

import attrs

from rcon_core.matcher import match
from rcon_core.plugins import Binding, Role, WidgetCatalog, WidgetSpec
from rcon_core.plugins.api import settings_problems, settings_size
from rcon_core.plugins.paths import parse_path

#: each role's button on the add panel: (what it does, in words; what it means)
ROLE_TEXT = {
    Role.SUBSCRIBE: ("Show it", "subscribe: a widget displays the messages"),
    Role.PUBLISH: ("Send on it", "publish: a widget sends messages"),
    Role.CALL: ("Call it", "call: a widget sends requests and shows the answer"),
    Role.SERVE: ("Answer it", "serve: a widget answers requests from the robot"),
    Role.ACTION: ("Send goals", "action: a widget sends goals, shows feedback and the result, and can cancel"),
}

#: categories whose widgets are for sending: they prefer publish/call over subscribe
SENDING_CATEGORIES = frozenset({"controls", "input"})
SENDING_FIRST = (Role.PUBLISH, Role.CALL, Role.ACTION, Role.SERVE, Role.SUBSCRIBE)
SHOWING_FIRST = (Role.SUBSCRIBE, Role.PUBLISH, Role.CALL, Role.SERVE, Role.ACTION)


def role_preference(spec: WidgetSpec) -> list[Role]:
    """The widget's roles, the one an operator most likely wants first: widgets of the category "Controls"
    or "Input" prefer to send (publish, then call, action, serve, subscribe), every other widget prefers to
    show (subscribe, then publish, call, serve, action)."""
    order = SENDING_FIRST if spec.category.strip().lower() in SENDING_CATEGORIES else SHOWING_FIRST
    return [r for r in order if r in spec.roles]


@attrs.define
class Candidate:
    """One ranked answer of the matcher: a widget that fits, and the field paths it would bind."""

    spec: WidgetSpec
    field_paths: tuple[str, ...] = ()
    score: float = 0.0
    reason: str = ""
    #: every field path the widget could bind on this type, best first (the operator may pick another)
    choices: tuple[str, ...] = ()


@attrs.define
class Target:
    """A topic or service a widget could be bound to."""

    name: str
    type: str
    field_paths: tuple[str, ...] = ()
    #: every field path the widget could bind on this target's type, best first
    choices: tuple[str, ...] = ()


@attrs.define
class Draft:
    """Everything needed to put a new widget on a canvas."""

    spec: WidgetSpec
    role: Role
    target: Target | None = None
    settings: Any = None
    title: str = ""
    #: the robot the topic/service comes from (the side panel's robot; "" = the first robot)
    robot: str = ""
    #: the enabled widget kinds (the app's plugin manager): settings whose checks need the other kinds (a
    #: Compound's children) are checked against it
    catalog: WidgetCatalog | None = None

    @property
    def field_path(self) -> str:
        """The field the widget shows or sets ("" = the whole message)."""
        return self.target.field_paths[0] if self.target is not None and self.target.field_paths else ""

    def set_field_path(self, path: str) -> None:
        """Bind another of the target's fitting fields; ValueError if ``path`` is not one of them."""
        if self.target is None:
            raise ValueError("choose a topic or service before its field")
        offered = self.target.choices or self.target.field_paths
        if path not in offered:
            raise ValueError(f"{path!r} is not a field this widget can use on {self.target.name} "
                             f"(offered: {list(offered)})")
        self.target = attrs.evolve(self.target, field_paths=(path,))

    @property
    def binding(self) -> Binding:
        if self.target is None:
            return Binding(role=self.role, robot=self.robot)
        return Binding(self.target.name, self.target.type, self.role, self.target.field_paths, self.robot)

    def problems(self) -> list[str]:
        """What keeps the draft from being placed: binding first, then the settings' own checks."""
        return list(self.binding.problems()) + settings_problems(self.settings, self.catalog)

    def settings_dict(self) -> dict[str, Any]:
        return self.spec.settings_to_dict(self.settings) if self.settings is not None else {}

    def size(self) -> tuple[int, int]:
        """The size a new widget gets: the kind's ``default_size``, grown to what these settings need
        when the settings object offers ``preferred_size() -> (w, h)`` (a Compound with many children)."""
        w, h = (int(v) for v in self.spec.default_size)
        preferred = settings_size(self.settings, self.catalog)  # a hint that fails is no hint
        if preferred is not None:
            w, h = max(w, int(preferred[0])), max(h, int(preferred[1]))
        return w, h


def field_type(types: Any, type_name: str, path: str, service: bool = False) -> str:
    """The type of the field at ``path`` in ``type_name`` as the registry spells it (``float32``,
    ``uint8[]``, ``geometry_msgs/msg/Vector3``); on a service the path starts with its side
    (``request.data``). ``""`` when the registry does not know it."""
    try:
        parts = parse_path(path)
        if service:
            if not parts:
                return ""
            side, *parts = parts
            current = types.service_part_name(type_name, str(side))
        else:
            current = types.resolve(type_name)
        found, base = current, current
        for part in parts:
            if isinstance(part, int):  # one element of the array just named
                found = base
                continue
            field = next((f for f in types.fields(current) if f.name == part), None)
            if field is None:
                return ""
            found, base, current = field.type, field.base, field.base
        return str(found)
    except Exception:  # unknown type or malformed path: no type to show, nothing to fail over
        return ""


#: last name segments that say how a topic is sent, not what it is (dropped from a suggested title)
GENERIC_TAILS = frozenset({"image_raw", "image", "image_rect", "image_color", "image_rect_color", "raw",
                           "compressed", "data", "state", "status"})
#: a first segment that reads better after the rest: /camera/front -> "front camera"
NOUN_FIRST = frozenset({"camera", "cam"})


def suggested_title(name: str, field_path: str = "", *, service: bool = False) -> str:
    """A short readable title for a widget on ``name``: ``battery · voltage``, ``front camera`` (from
    ``/camera/front/image_raw``), a service's name without its slashes (``dock``, ``lights set``), like a
    topic's. "" when there is no name."""
    if not name:
        return ""
    if service:
        return " ".join(p for p in name.strip("/").split("/") if p).replace("_", " ") or name
    parts = [p for p in name.strip("/").split("/") if p]
    while len(parts) > 1 and parts[-1] in GENERIC_TAILS:
        parts.pop()
    if len(parts) == 2 and parts[0] in NOUN_FIRST:
        parts = [parts[1], parts[0]]
    base = " ".join(parts[-2:]).replace("_", " ") if parts else name
    if field_path:
        field = field_path if len(field_path) <= 20 else field_path.rsplit(".", 1)[-1]
        return f"{base} · {field}"
    return base


def rank_widgets(type_name: str, role: Role, types: Any, plugins: Any) -> list[Candidate]:
    """The widgets that fit ``type_name`` in ``role``, best first, as the add panel lists them."""
    try:
        found = match(type_name, role, types, plugins)
    except ValueError:  # no type known (an action whose type the robot did not tell): nothing fits
        return []
    return [Candidate(m.spec, (m.field_path,) if m.field_path else (), float(int(m.rank)), m.reason,
                      tuple(m.field_paths)) for m in found]


def targets_for(spec: WidgetSpec, role: Role, entries: list[tuple[str, str]], types: Any,
                plugins: Any) -> list[Target]:
    """The robot's topics (services, actions: ``entries`` of name and type) a widget of ``spec`` fits."""
    out = []
    for name, type_name in entries:
        for m in match(type_name, role, types, plugins):
            if m.spec.kind == spec.kind:
                out.append(Target(name, type_name, (m.field_path,) if m.field_path else (), tuple(m.field_paths)))
                break
    return out
