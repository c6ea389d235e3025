"""The widget contract: what a widget package declares about each widget it offers.

A widget package registers :class:`WidgetSpec` objects from its ``rcon_register_widgets(registry)`` hook.
A spec is pure data plus lazy ``"module:attr"`` references: building the list of widgets never imports a
view module (and so never imports Qt).

Accepted types are declared with :class:`Accepts`:

* ``types``: exact type names, either spelling (``"std_msgs/Float64"`` or ``"std_msgs/msg/Float64"``).
* ``packages``: whole packages (``"sensor_msgs"``), any type in them.
* ``fields``: field predicates over *leaf* fields of the type, anywhere in the message tree. Each match
  gives a field path the widget would bind to (``"percentage"``, ``"linear.x"``). Names:
  see :data:`FIELD_PREDICATES` (``"numeric"``, ``"float"``, ``"integer"``, ``"bool"``, ``"string"``,
  ``"time"``, ``"bytes"``, ``"numeric_array"``) or a callable ``fn(field: FieldDef) -> bool``.
* ``messages``: message predicates over the whole type *and* every scalar nested message field, giving
  the path of the (sub)message (``""`` is the whole message). Names: see :data:`MESSAGE_PREDICATES`
  (``"any"``, ``"empty"``, ``"image"``, ``"compressed_image"``, ``"vector3"``, ``"quaternion"``,
  ``"twist"``, ``"geo"``) or a callable ``fn(type_name: str, fields: list[FieldDef]) -> bool``.
* ``prefer``: field names (last path component) ranked first when several paths match, e.g.
  ``("percentage", "data")`` so a Slider on ``sensor_msgs/BatteryState`` binds ``percentage``.
* ``service_parts``: for service types, which side(s) the predicates look at. Paths on a service are
  prefixed with the part: ``"request.data"``, ``"response.success"``; the whole request is ``"request"``.
* ``action_parts``: for action types (role ``ACTION``), which parts the predicates look at, of
  ``"goal"``, ``"feedback"``, ``"result"``. Paths on an action are prefixed with the part:
  ``"goal.target"``, ``"feedback.distance_remaining"``; the whole goal is ``"goal"``.

``"any"`` is a *generic fallback* (ranked last by the matcher); every other predicate is *structural*.
"""

from __future__ import annotations

import enum
import importlib
from collections.abc import Callable, Iterable, Mapping
from typing import Any, Protocol, runtime_checkable

import attrs

from rcon_core.msgs.names import pkg_type

__all__ = [
    "Role",
    "Accepts",
    "WidgetSpec",
    "FieldLike",
    "FIELD_PREDICATES",
    "MESSAGE_PREDICATES",
    "SpecError",
    "SettingsError",
    "UnknownWidget",
    "API_VERSION",
    "ApiVersionError",
    "check_api_version",
    "WidgetSettings",
    "resolve",
    "NUMERIC_BASES",
    "ACTION_PARTS",
    "INTEGER_BASES",
    "FLOAT_BASES",
]


class SpecError(ValueError):
    """A widget spec is malformed (bad kind, unknown predicate name, bad reference...)."""


#: the version of this contract: a package built for another *major* version is refused; a newer minor
#: version only adds (a package built for 1.0 runs on 1.1)
API_VERSION = "1.1"


class ApiVersionError(SpecError):
    """A widget package was built for a widget API this RCON does not offer (another major version)."""


def _parse_version(text: str) -> tuple[int, int] | None:
    parts = text.strip().split(".")
    if not 1 <= len(parts) <= 2 or not all(p.isdigit() for p in parts):
        return None
    return int(parts[0]), int(parts[1]) if len(parts) == 2 else 0


def check_api_version(declared: str, kind: str, package: str = "") -> None:
    """Refuse (:class:`ApiVersionError`, one sentence) a widget built for another major version of this
    API, or one whose ``api_version`` is not a version. ``""``: written before the version existed (1.0)."""
    if not declared:
        return
    who = f"{kind!r}" + (f" (package {package})" if package else "")
    version = _parse_version(declared)
    if version is None:
        raise ApiVersionError(f"widget {who} declares api_version {declared!r}, which is not a version "
                              f"such as {API_VERSION!r}")
    major = _parse_version(API_VERSION)[0]  # type: ignore[index]
    if version[0] != major:
        raise ApiVersionError(
            f"widget {who} was built for RCON's widget API {declared}, but this RCON offers API "
            f"{API_VERSION}: install a version of the package built for API {major}.x"
            + (", or a newer rcon-core" if version[0] > major else ""))


class UnknownWidget(KeyError):
    """No installed (and enabled) plugin offers this widget kind."""

    def __str__(self) -> str:  # KeyError quotes its argument; we want a sentence
        return str(self.args[0]) if self.args else "unknown widget"


@runtime_checkable
class WidgetSettings(Protocol):
    """Per-instance settings: ``problems()`` lists what keeps the widget from working, one sentence each
    (``[]``: configured); the frame shows them as the "not configured" warning."""

    def problems(self) -> list[str]: ...


class SettingsError(ValueError):
    """Stored settings could not be turned into the widget's settings class; ``str()`` says why.

    ``problems`` holds one sentence per bad value ("invalid settings: max_length must be a number (got
    'abc')"): the widget's "not configured" warning.
    """

    def __init__(self, message: str, problems: list[str] | None = None) -> None:
        super().__init__(message)
        self.problems: list[str] = list(problems) if problems else [message]


class Role(enum.StrEnum):
    """How a widget is bound to the robot. A widget may support several roles."""

    SUBSCRIBE = "subscribe"  #: shows messages from a topic
    PUBLISH = "publish"  #: publishes messages on a topic
    CALL = "call"  #: calls a service (a client)
    SERVE = "serve"  #: answers a service (advertises it)
    ACTION = "action"  #: sends goals to a ROS 2 action server (shows feedback and result, can cancel)

    @property
    def is_service(self) -> bool:
        return self in (Role.CALL, Role.SERVE)

    @property
    def is_action(self) -> bool:
        return self is Role.ACTION

    @property
    def noun(self) -> str:
        """What a binding of this role names: ``"topic"``, ``"service"`` or ``"action"``."""
        return "action" if self is Role.ACTION else "service" if self.is_service else "topic"

    @classmethod
    def parse(cls, value: str | Role) -> Role:
        """``"subscribe"``, ``"SUBSCRIBE"``, ``Role.SUBSCRIBE`` -> ``Role.SUBSCRIBE``; clear error otherwise."""
        if isinstance(value, Role):
            return value
        try:
            return cls(str(value).strip().lower())
        except ValueError:
            names = ", ".join(r.value for r in cls)
            raise ValueError(f"unknown role {value!r}: expected one of {names}") from None


class FieldLike(Protocol):
    """What predicates see: ``rcon_core.msgs.FieldDef`` (name, type, base, array_len, is_builtin)."""

    name: str
    type: str
    base: str
    array_len: int | None
    is_builtin: bool


INTEGER_BASES = frozenset(
    {"int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64", "byte", "char"}
)
FLOAT_BASES = frozenset({"float32", "float64"})
NUMERIC_BASES = INTEGER_BASES | FLOAT_BASES
STRING_BASES = frozenset({"string", "wstring"})
TIME_BASES = frozenset({"time", "duration", "builtin_interfaces/msg/Time", "builtin_interfaces/msg/Duration"})


#: the parts of an action type, in the order the matcher searches them
ACTION_PARTS = ("goal", "feedback", "result")


def _scalar(f: FieldLike) -> bool:
    return f.array_len is None


FieldPredicate = Callable[[FieldLike], bool]
MessagePredicate = Callable[[str, "list[FieldLike]"], bool]

#: named predicates over one leaf field
FIELD_PREDICATES: dict[str, FieldPredicate] = {
    "numeric": lambda f: _scalar(f) and f.base in NUMERIC_BASES,
    "float": lambda f: _scalar(f) and f.base in FLOAT_BASES,
    "integer": lambda f: _scalar(f) and f.base in INTEGER_BASES,
    "bool": lambda f: _scalar(f) and f.base == "bool",
    "string": lambda f: _scalar(f) and f.base in STRING_BASES,
    "time": lambda f: _scalar(f) and f.base in TIME_BASES,
    "bytes": lambda f: f.array_len is not None and f.base in ("uint8", "char", "byte"),
    "numeric_array": lambda f: f.array_len is not None and f.base in NUMERIC_BASES,
}


def _names(fields: list[FieldLike]) -> dict[str, FieldLike]:
    return {f.name: f for f in fields}


def _has_numeric(fields: list[FieldLike], *names: str) -> bool:
    by = _names(fields)
    return all(n in by and FIELD_PREDICATES["numeric"](by[n]) for n in names)


def _is_image(_t: str, fields: list[FieldLike]) -> bool:
    by = _names(fields)
    return (
        _has_numeric(fields, "height", "width")
        and "encoding" in by
        and "data" in by
        and FIELD_PREDICATES["bytes"](by["data"])
    )


def _is_compressed_image(_t: str, fields: list[FieldLike]) -> bool:
    by = _names(fields)
    return "format" in by and "data" in by and FIELD_PREDICATES["bytes"](by["data"]) and "width" not in by


def _is_twist(_t: str, fields: list[FieldLike]) -> bool:
    by = _names(fields)
    return all(n in by and by[n].array_len is None and not by[n].is_builtin for n in ("linear", "angular"))


#: named predicates over a whole (sub)message: fn(type_name, fields)
MESSAGE_PREDICATES: dict[str, MessagePredicate] = {
    "any": lambda _t, _f: True,
    "empty": lambda _t, fields: len(fields) == 0,
    "image": _is_image,
    "compressed_image": _is_compressed_image,
    "vector3": lambda _t, f: _has_numeric(f, "x", "y", "z") and "w" not in _names(f),
    "quaternion": lambda _t, f: _has_numeric(f, "x", "y", "z", "w"),
    "twist": _is_twist,
    "geo": lambda _t, f: _has_numeric(f, "latitude", "longitude"),
}


def _tuple(value: Iterable[Any] | str | None) -> tuple[Any, ...]:
    if value is None:
        return ()
    if isinstance(value, str):
        return (value,)
    return tuple(value)


def _check_predicates(kind: str, table: Mapping[str, Any]) -> Callable[[Any, Any, tuple[Any, ...]], None]:
    def check(_inst: Any, _attr: Any, value: tuple[Any, ...]) -> None:
        for p in value:
            if isinstance(p, str):
                if p not in table:
                    raise SpecError(
                        f"unknown {kind} predicate {p!r}: known ones are {', '.join(sorted(table))}"
                    )
            elif not callable(p):
                raise SpecError(f"{kind} predicate must be a name or a callable, got {p!r}")

    return check


@attrs.frozen
class Accepts:
    """Which types a widget fits. See the module docstring for the meaning of each field."""

    types: tuple[str, ...] = attrs.field(default=(), converter=_tuple)
    packages: tuple[str, ...] = attrs.field(default=(), converter=_tuple)
    fields: tuple[str | FieldPredicate, ...] = attrs.field(
        default=(), converter=_tuple, validator=_check_predicates("field", FIELD_PREDICATES)
    )
    messages: tuple[str | MessagePredicate, ...] = attrs.field(
        default=(), converter=_tuple, validator=_check_predicates("message", MESSAGE_PREDICATES)
    )
    prefer: tuple[str, ...] = attrs.field(default=(), converter=_tuple)
    service_parts: tuple[str, ...] = attrs.field(default=("request", "response"), converter=_tuple)
    action_parts: tuple[str, ...] = attrs.field(default=("goal", "feedback", "result"), converter=_tuple)

    @action_parts.validator
    def _check_action_parts(self, _attr: Any, value: tuple[str, ...]) -> None:
        bad = [p for p in value if p not in ACTION_PARTS]
        if bad:
            raise SpecError(f"action_parts may hold 'goal', 'feedback' and 'result' only, got {bad}")

    @service_parts.validator
    def _check_parts(self, _attr: Any, value: tuple[str, ...]) -> None:
        bad = [p for p in value if p not in ("request", "response")]
        if bad:
            raise SpecError(f"service_parts may hold 'request' and 'response' only, got {bad}")

    @property
    def is_generic(self) -> bool:
        """True when the only thing accepted is "any message" (a fallback widget such as Text View)."""
        return not self.types and not self.packages and not self.fields and self.messages == ("any",)

    def describe(self) -> list[str]:
        """Human-readable list, for ``rcon plugins``: ``["std_msgs/Float64", "field:numeric", ...]``.

        Types are shown in one spelling (ROS 1's, the shorter) whichever spelling the plugin declared.
        """
        out: list[str] = [pkg_type(t) for t in self.types]
        out += [f"{p}/*" for p in self.packages]
        out += ["field:" + _pred_name(p) for p in self.fields]
        out += ["message:" + _pred_name(p) for p in self.messages]
        return out


def _pred_name(p: Any) -> str:
    return p if isinstance(p, str) else getattr(p, "__name__", repr(p))


def resolve(ref: str | Any) -> Any:
    """Import a ``"package.module:attr.sub"`` reference; objects pass through unchanged.

    Raises :class:`SpecError` naming the reference when the module or attribute is missing (the
    underlying ImportError is chained).
    """
    if not isinstance(ref, str):
        return ref
    module_name, sep, attr = ref.partition(":")
    if not sep or not module_name or not attr:
        raise SpecError(f"reference {ref!r} must look like 'package.module:attr'")
    try:
        obj: Any = importlib.import_module(module_name)
    except ImportError as exc:
        raise SpecError(f"cannot import {module_name!r} for {ref!r}: {exc}") from exc
    for part in attr.split("."):
        try:
            obj = getattr(obj, part)
        except AttributeError:
            raise SpecError(f"{module_name!r} has no attribute {attr!r} (from {ref!r})") from None
    return obj


def _check_ref(_inst: Any, attribute: Any, value: Any) -> None:
    if value is None:
        return
    if isinstance(value, str) and (":" not in value or value.startswith(":") or value.endswith(":")):
        raise SpecError(f"WidgetSpec.{attribute.name} {value!r} must look like 'package.module:attr'")


def _roles(value: Iterable[Role | str] | Role | str) -> frozenset[Role]:
    if isinstance(value, (Role, str)):
        value = [value]
    return frozenset(Role.parse(v) for v in value)


def _check_kind(_inst: Any, _attr: Any, value: str) -> None:
    import re

    if not re.fullmatch(r"[a-z][a-z0-9_]*(\.[a-z0-9_][a-z0-9_-]*)+", value or ""):
        raise SpecError(
            f"widget kind {value!r} must be a dotted lowercase id with a package prefix, e.g. 'std.slider'"
        )


@attrs.frozen
class WidgetSpec:
    """One widget kind offered by a widget package.

    ``kind`` is the stable id saved in layouts (``"std.slider"``): never rename it once released.
    ``settings`` is the *per-instance* settings class (an attrs class whose instances have
    ``problems() -> list[str]``: an empty list means "configured"; each string becomes a line of the
    "not configured" warning). ``plugin_settings`` is the *per-kind* settings class shared by every
    instance of that kind (e.g. a tile cache directory), same protocol. Both, and ``model``, may be a
    ``"module:attr"`` string or the object itself; ``view`` must be a ``"module:attr"`` string (it
    imports Qt). ``package`` is filled in by the plugin manager from the distribution name; leave it empty.
    ``default_size`` is (w, h) in canvas units (device-independent pixels). Higher ``priority`` wins ties
    in the matcher between widgets of the same rank. ``api_version``: the widget API the package was
    written against (``rcon_core.plugins.api.API_VERSION`` at the time, written out: ``"1.1"``); the plugin
    manager refuses a package built for another major version. Empty: written before the version existed
    (1.0).
    """

    kind: str = attrs.field(validator=_check_kind)
    title: str
    model: str | type = attrs.field(validator=_check_ref)
    view: str | None = attrs.field(default=None, validator=_check_ref)
    roles: frozenset[Role] = attrs.field(default=frozenset({Role.SUBSCRIBE}), converter=_roles)
    accepts: Accepts = attrs.field(factory=Accepts)
    settings: str | type | None = attrs.field(default=None, validator=_check_ref)
    plugin_settings: str | type | None = attrs.field(default=None, validator=_check_ref)
    icon: str = ""
    description: str = ""
    category: str = ""
    default_size: tuple[float, float] = (160.0, 80.0)
    priority: int = 0
    package: str = ""
    api_version: str = ""

    @view.validator
    def _view_is_lazy(self, _attr: Any, value: Any) -> None:
        if value is not None and not isinstance(value, str):
            raise SpecError(f"WidgetSpec.view for {self.kind!r} must be a 'module:attr' string (lazy)")

    @roles.validator
    def _has_role(self, _attr: Any, value: frozenset[Role]) -> None:
        if not value:
            raise SpecError(f"widget {self.kind!r} declares no role")

    # -- lazy loading ------------------------------------------------------------------------------
    def load_model(self) -> type:
        """The model class (imports the model module; never Qt)."""
        model: type = resolve(self.model)
        return model

    def load_view(self) -> type:
        """The Qt view class (imports Qt). Only the front end calls this."""
        if self.view is None:
            raise SpecError(f"widget {self.kind!r} has no view")
        view: type = resolve(self.view)
        return view

    def load_settings_class(self) -> type | None:
        return resolve(self.settings) if self.settings is not None else None

    def load_plugin_settings_class(self) -> type | None:
        return resolve(self.plugin_settings) if self.plugin_settings is not None else None

    # -- settings ------------------------------------------------------------------------------------
    def make_settings(self, data: Mapping[str, Any] | None = None) -> Any:
        """Build the per-instance settings object from a stored dict (unknown keys are ignored).

        Returns None when the widget has no settings class. Raises :class:`SettingsError` with a
        human-readable reason when a value has the wrong type.
        """
        return _structure(self.load_settings_class(), data, self.kind)

    def make_plugin_settings(self, data: Mapping[str, Any] | None = None) -> Any:
        """Same as :meth:`make_settings` for the per-kind shared settings."""
        return _structure(self.load_plugin_settings_class(), data, self.kind)

    def settings_problems(self, data: Mapping[str, Any] | None = None) -> list[str]:
        """Everything wrong with these stored settings, as sentences; ``[]`` means configured. (Settings whose
        checks need the other installed kinds, a Compound's, get them through
        ``rcon_core.plugins.api.stored_settings_problems(spec, data, catalog)``.)"""
        try:
            obj = self.make_settings(data)
        except SettingsError as exc:
            return list(exc.problems)
        if not isinstance(obj, WidgetSettings):
            return []
        return list(obj.problems())

    def settings_to_dict(self, settings: Any) -> dict[str, Any]:
        """The dict stored in a layout for a settings object."""
        if settings is None:
            return {}
        stored: dict[str, Any] = _converter().unstructure(settings)
        return stored


_CONVERTER: Any = None


def _converter() -> Any:
    global _CONVERTER
    if _CONVERTER is None:
        import cattrs

        _CONVERTER = cattrs.Converter(forbid_extra_keys=False)
        _CONVERTER.register_structure_hook(bool, _strict_bool)  # cattrs would read "no" as True
    return _CONVERTER


def _strict_bool(value: Any, _type: Any) -> bool:
    if not isinstance(value, bool):
        raise ValueError("must be true or false")
    return value




def _structure(cls: type | None, data: Mapping[str, Any] | None, kind: str) -> Any:
    if cls is None:
        return None
    if data is None:
        data = {}
    if not attrs.has(cls):
        try:
            return cls(**data)
        except TypeError as exc:
            raise SettingsError(f"{kind}: {exc}") from exc
    import cattrs

    known = {a.name for a in attrs.fields(cls)} | {a.alias for a in attrs.fields(cls)}
    data = {k: v for k, v in data.items() if k in known}
    try:
        return _converter().structure(data, cls)
    except cattrs.ClassValidationError as exc:
        problems = [_sentence(m, data) for m in cattrs.transform_error(exc, format_exception=_expected)]
        raise SettingsError(f"{kind}: " + "; ".join(problems), problems) from exc
    except (TypeError, ValueError) as exc:
        raise SettingsError(f"{kind}: invalid settings: {exc}", [f"invalid settings: {exc}"]) from exc


_EXPECTED = {float: "a number", int: "a whole number", bool: "true or false", str: "text"}


def _expected(exc: BaseException, type_: Any) -> str:
    """cattrs' per-value message, in words: "must be a number"."""
    if isinstance(exc, ValueError) and str(exc).startswith("must be"):
        return str(exc)  # our own hooks' words (strict booleans)
    if type_ in _EXPECTED:
        return f"must be {_EXPECTED[type_]}"
    if isinstance(exc, KeyError):
        return "is required"
    name = getattr(type_, "__name__", None) or str(type_)
    return f"must be {name}" if type_ is not None else f"is not valid ({exc})"


def _sentence(message: str, data: Mapping[str, Any]) -> str:
    """``"must be a number @ $.max_length"`` -> ``"invalid settings: max_length must be a number (got 'abc')"``."""
    text, _, where = message.rpartition(" @ ")
    path = where[2:] if where.startswith("$.") else where.lstrip("$")
    value: Any = data
    for part in path.replace("[", ".").replace("]", "").split("."):
        if isinstance(value, Mapping) and part in value:
            value = value[part]
        elif isinstance(value, list) and part.isdigit() and int(part) < len(value):
            value = value[int(part)]
        else:
            value = _MISSING
            break
    got = "" if value is _MISSING else f" (got {_short(value)})"
    return f"invalid settings: {path or 'the settings'} {text or 'is not valid'}{got}"


_MISSING = object()


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."
