"""The widget API: everything a widget package may rely on, and everything RCON relies on from one, stated
in one place (no Qt). ``docs/writing-a-widget-plugin.md`` documents it; ``tests/test_plugin_api.py`` keeps
that guide, the bundled packages and the scaffold (``rcon new-widget``) in step with this module.

The contract, in the order a widget meets it:

* **The spec** (:class:`~rcon_core.plugins.spec.WidgetSpec`) names the widget's kind, roles, accepted types
  and its ``"module:attr"`` settings, model and view. ``WidgetSpec.api_version`` is the version of *this*
  contract the package was written against (``"1.1"``; empty: written before the version existed, 1.0).
  The plugin manager refuses a package built for another major version (:func:`check_api_version`), with
  one sentence saying which versions meet.
* **The model** is built as ``Model(settings, binding, port, types=..., plugin_settings=..., dispatch=...,
  clock=..., context=...)`` (``rcon_core.plugins.WidgetModel``, the base class every model derives from;
  it lives in ``model.py``, which imports this module). It gets a :class:`Binding`, a complete
  :class:`Port` and a :class:`WidgetContext`; it hands the front end frozen :class:`WidgetState` snapshots.
  What the runtime and the front end read from a model is :class:`HostedModel`.
* **Optional capabilities** of a model are declared once, in :class:`ModelHooks`, and ``WidgetModel``
  implements each as a documented no-op: ``on_focus_lost()``, ``on_fleet(robots)`` (a model that overrides
  it is *fleet-wide*), ``on_robot_link(robot_id, up)``, ``shown_message()`` (what a Compound's child
  shows) and the ``dry_run`` flag. The runtime calls them directly; nothing looks a hook up by its name.
* **The small hook**: a subscriber that only turns the bound field into what its view paints overrides
  ``WidgetModel.to_value(field_value, msg)``; raising :class:`NotAValue` skips the message with a sentence
  as the widget's error. ``on_message(msg)`` stays for models that need the whole message.
* **The view** (Qt; :class:`WidgetView`) is built as ``View(model)`` and gets ``refresh(state)`` when the
  state's ``seq`` moved, at most once per display frame.
* **Settings** are an attrs class; :class:`WidgetSettings` (``problems()``) is the "not configured" warning.
  Optional: :class:`CommandBounds` (``commands(binding)``: what the widget may send, checked against the
  robot's safety envelope) and :class:`SizedSettings` (``preferred_size()``). Settings whose checks need the
  other installed kinds (a Compound's children) derive from :class:`CatalogSettings` and get the catalog
  passed in; :func:`settings_problems`, :func:`settings_commands` and :func:`settings_size` are the one
  place the core calls them.
* **Public modules.** A widget package imports from RCON only what :data:`PUBLIC_API` lists.
"""

from __future__ import annotations

import enum
from collections.abc import Awaitable, Callable, Hashable, Mapping, Sequence
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

import attrs

from rcon_core.msgs.names import normalize

from .context import SharedResources, WidgetCatalog, WidgetContext
from .spec import (
    API_VERSION,
    Accepts,
    ApiVersionError,
    Role,
    SettingsError,
    SpecError,
    UnknownWidget,
    WidgetSettings,
    WidgetSpec,
    check_api_version,
)

if TYPE_CHECKING:
    from rcon_core.bridge.envelope import Envelope

__all__ = [
    # declared in the modules they belong to, stated here with the rest of the contract
    "WidgetSpec",
    "Accepts",
    "Role",
    "SpecError",
    "SettingsError",
    "UnknownWidget",
    "WidgetContext",
    "WidgetCatalog",
    "SharedResources",
    "API_VERSION",
    "ApiVersionError",
    "check_api_version",
    # declared here
    "Binding",
    "WidgetState",
    "Subscription",
    "Publisher",
    "ServiceServer",
    "ActionGoal",
    "BridgePort",
    "Port",
    "as_port",
    "RobotPort",
    "ModelHooks",
    "HostedModel",
    "WidgetView",
    "NotAValue",
    "WidgetSettings",
    "CommandBounds",
    "SizedSettings",
    "StaleAfterSettings",
    "CatalogSettings",
    "settings_problems",
    "stored_settings_problems",
    "settings_commands",
    "settings_size",
    "CAPABILITIES",
    "PUBLIC_API",
    "CallPhase",
    "GoalPhase",
]


# ------------------------------------------------------------------------------------------ binding
def _paths(value: Any) -> tuple[str, ...]:
    if value is None:
        return ()
    if isinstance(value, str):
        return (value,) if value else ()
    return tuple(value)


def _role(value: str | Role) -> Role:
    # a plain function: mypy's attrs plugin cannot follow a classmethod (Role.parse) as a converter
    return Role.parse(value)


@attrs.frozen
class Binding:
    """What a widget instance is bound to.

    ``name``: the topic, service or action name (``""`` = not bound yet). ``type``: its type, either
    spelling. ``role``: how the widget uses it. ``field_paths``: the field(s) the widget shows or sets,
    e.g. ``("percentage",)``; empty means the whole message. On a service, paths begin with ``request``
    or ``response`` (``"request.data"``); on an action with ``goal``, ``feedback`` or ``result``.
    ``robot``: the id of the workspace's robot it talks to (``""`` = the first robot, so one-robot
    layouts and plugins never set it; see ``rcon_core.canvas.robots``).
    """

    name: str = ""
    type: str = ""
    role: Role = attrs.field(default=Role.SUBSCRIBE, converter=_role)
    field_paths: tuple[str, ...] = attrs.field(default=(), converter=_paths)
    robot: str = ""

    @property
    def field_path(self) -> str:
        """The first (main) field path, ``""`` for the whole message."""
        return self.field_paths[0] if self.field_paths else ""

    @property
    def canonical_type(self) -> str:
        """The type in RCON's canonical spelling (``sensor_msgs/msg/Imu``); unchanged when it is not a
        type name (a problem the binding reports elsewhere), ``""`` when unset."""
        if not self.type:
            return ""
        try:
            return normalize(self.type)
        except ValueError:
            return self.type

    def problems(self) -> list[str]:
        """What is missing before this binding can work; ``[]`` when complete."""
        out = []
        what = self.role.noun
        if not self.name:
            out.append(f"no {what} chosen")
        elif not self.name.startswith("/") and not self.name[0].isalpha():
            out.append(f"{what} name {self.name!r} is not a valid ROS name")
        if not self.type and self.name:  # no name: "no topic chosen" already says it (and no type)
            out.append(f"no {what} type set")
        return out


@attrs.frozen
class WidgetState:
    """A snapshot of what the view paints, taken at one instant.

    ``value``: the widget's value (the bound field, or whatever the model's ``set_value`` gave).
    ``message``: the last whole message (or service response) the value came from, or None.
    ``count``: values received so far. ``age``: seconds since the last value, None if never.
    ``stale``: True when ``age`` exceeds the model's ``stale_after`` (or nothing came since start);
    never for a static topic that delivered (see ``rcon_core.plugins.staleness``). ``static``: the value
    came from a topic that looks latched or that the settings call static (``stale_after = 0``).
    ``link_down``: the bridge connection is down. ``error``: last problem as a sentence, or None.
    ``running``: the model is started. ``seq``: increases on every change (not on mere ageing).
    """

    value: Any = None
    message: Any = None
    count: int = 0
    age: float | None = None
    stale: bool = False
    link_down: bool = False
    error: str | None = None
    running: bool = False
    seq: int = 0
    static: bool = False


# ------------------------------------------------------------------------------------------ the port
class Subscription(Protocol):
    def unsubscribe(self) -> None: ...


class Publisher(Protocol):
    #: a bridge node's publisher returns False when the message was dropped (link down, not latched)
    def publish(self, msg: dict[str, Any]) -> bool | None: ...
    def unadvertise(self) -> None: ...


class ServiceServer(Protocol):
    def unadvertise(self) -> None: ...


class ActionGoal(Protocol):
    """What ``Port.send_action_goal`` returns: ``await goal.result(timeout)``, ``goal.cancel()``,
    ``goal.status`` (an ``rcon_core.bridge.GoalStatus``) and ``goal.done``."""

    def result(self, timeout: float | None = None) -> Awaitable[dict[str, Any]]: ...
    def cancel(self) -> Any: ...
    @property
    def status(self) -> Any: ...
    @property
    def done(self) -> bool: ...


class BridgePort(Protocol):
    """The least a model may be *given* as its port: a bridge client node (``client.node(id)``, what a
    package's tests pass), a test's fake, or a complete :class:`Port`. The model always *sees* a complete
    :class:`Port` (:func:`as_port` completes a partial one)."""

    def subscribe(
        self, topic: str, callback: Callable[[dict[str, Any]], Any], **options: Any
    ) -> Subscription: ...
    def advertise(self, topic: str, type: str, **options: Any) -> Publisher: ...
    def call_service(
        self, name: str, args: Any = None, timeout: float | None = None
    ) -> Awaitable[dict[str, Any]]: ...
    def advertise_service(
        self, name: str, type: str, handler: Callable[[dict[str, Any]], Any]
    ) -> ServiceServer: ...
    def close(self) -> None: ...


@runtime_checkable
class Port(Protocol):
    """The port a model talks through (``model.port``): its only way to the robot, and what it knows of its
    place. In the app a ``rcon_core.canvas.port.GuardedPort`` (sealed; refuses to send when view-only); in a
    Compound a child port (what it publishes is composed, not sent); in tests ``rcon_core.testing
    .RecordingPort``. Threads: the methods run on the bridge loop thread, ``changed`` on any thread.

    - ``subscribe`` / ``advertise`` / ``call_service`` / ``advertise_service`` / ``send_action_goal`` /
      ``close``: the bridge operations (a model normally uses its own ``publish``, ``call``, ``call_async``,
      which go through these).
    - ``view_only``: None, or the sentence saying why nothing may be sent (sending is refused regardless).
    - ``envelope``: the robot's safety envelope (``rcon_core.bridge.envelope.Envelope``) or None; read it at
      each use, it may change while the widget runs.
    - ``link``: an opaque key, the same for every widget on one robot link (``WidgetContext.shared`` is
      keyed by it); a model learns the link's *state* through ``set_link`` (``state.link_down``) and, when
      fleet-wide, ``on_robot_link``.
    - ``widget_id``: the widget instance's id, the same across rebuilds of its model (None outside a canvas).
    - ``composes``: True when what the model publishes is composed into a parent's message (a Compound's
      child) instead of reaching the robot: say what *will* be sent.
    - ``changed()``: the model has something new to show (``WidgetModel.announce`` calls it); the app wakes
      the front end, which repaints within the frame.
    """

    @property
    def view_only(self) -> str | None: ...
    @property
    def envelope(self) -> Envelope | None: ...
    @property
    def link(self) -> Hashable: ...
    @property
    def widget_id(self) -> str | None: ...
    @property
    def composes(self) -> bool: ...
    def changed(self) -> None: ...
    def subscribe(
        self, topic: str, callback: Callable[[dict[str, Any]], Any], **options: Any
    ) -> Subscription: ...
    def advertise(self, topic: str, type: str, **options: Any) -> Publisher: ...
    def call_service(
        self, name: str, args: Any = None, timeout: float | None = None
    ) -> Awaitable[dict[str, Any]]: ...
    def advertise_service(
        self, name: str, type: str, handler: Callable[[dict[str, Any]], Any]
    ) -> ServiceServer: ...
    def send_action_goal(self, action: str, action_type: str, args: Any = None,
                         feedback: Callable[[dict[str, Any]], Any] | None = None, **options: Any) -> ActionGoal: ...
    def close(self) -> None: ...


class _NodePort:
    """A partial port (a bare bridge node in a package's test, a fake) completed with the defaults of a
    widget outside any canvas: sendable, no envelope, its own link, no widget id, not composed."""

    composes = False
    view_only: str | None = None
    widget_id: str | None = None

    def __init__(self, port: BridgePort) -> None:
        self._port = port
        self.link: Hashable = id(port)

    @property
    def envelope(self) -> Envelope | None:
        return None

    def changed(self) -> None:
        """Nobody to wake outside a canvas."""

    def subscribe(self, topic: str, callback: Callable[[dict[str, Any]], Any], **options: Any) -> Subscription:
        return self._port.subscribe(topic, callback, **options)

    def advertise(self, topic: str, type: str, **options: Any) -> Publisher:
        return self._port.advertise(topic, type, **options)

    def call_service(self, name: str, args: Any = None, timeout: float | None = None) -> Awaitable[dict[str, Any]]:
        return self._port.call_service(name, args, timeout=timeout)

    def advertise_service(self, name: str, type: str, handler: Callable[[dict[str, Any]], Any]) -> ServiceServer:
        return self._port.advertise_service(name, type, handler)

    def send_action_goal(self, action: str, action_type: str, args: Any = None,
                         feedback: Callable[[dict[str, Any]], Any] | None = None, **options: Any) -> ActionGoal:
        node: Any = self._port  # a bridge node sends goals; a fake without them cannot
        try:
            send = node.send_action_goal
        except AttributeError:
            raise RuntimeError(f"{type(self._port).__name__} cannot send action goals") from None
        return send(action, action_type, args, feedback=feedback, **options)  # type: ignore[no-any-return]

    def close(self) -> None:
        self._port.close()

    def __getattr__(self, name: str) -> Any:
        # what else the given port offers (a test reads its fake's records through model.port)
        return getattr(self._port, name)

    def __repr__(self) -> str:
        return f"<port over {self._port!r}>"


def as_port(port: BridgePort | Port) -> Port:
    """``port`` itself when it is a complete :class:`Port`, else ``port`` completed with the defaults of a
    widget outside any canvas (a bridge node, a test's fake)."""
    if isinstance(port, Port):
        return port
    return _NodePort(port)


@attrs.frozen
class RobotPort:
    """One robot as a fleet-wide widget sees it (``ModelHooks.on_fleet``): who it is and its port."""

    id: str
    name: str
    colour: str
    port: BridgePort


# ------------------------------------------------------------------------------------------ the model
class ModelHooks(Protocol):
    """The optional capabilities of a model. ``WidgetModel`` implements each as a documented no-op, so the
    runtime calls them directly; override the ones the widget needs.

    - ``on_focus_lost()`` (bridge thread): the window lost focus or the canvas is being left, before its
      models stop. A model that moves the robot stops commanding here (publishes its zero).
    - ``on_fleet(robots)`` (bridge thread, before ``start``): one :class:`RobotPort` per robot of the
      workspace. A model that overrides it is fleet-wide (``fleet_wide``) and subscribes on each port.
    - ``on_robot_link(robot_id, up)`` (bridge thread): a fleet-wide model hears each robot's link state.
    - ``shown_message()`` (bridge thread): for a Compound's input child, a message of its bound type holding
      the value it shows (raise ``ValueError`` to block the send with the reason); None: what it last
      published.
    - ``dry_run``: True while the model runs as the add panel's preview (nothing it sends reaches the robot);
      set by the app.
    """

    dry_run: bool

    @property
    def fleet_wide(self) -> bool: ...
    def on_focus_lost(self) -> None: ...
    def on_fleet(self, robots: list[RobotPort]) -> None: ...
    def on_robot_link(self, robot_id: str, up: bool) -> None: ...
    def shown_message(self) -> dict[str, Any] | None: ...


class HostedModel(ModelHooks, Protocol):
    """What the canvas runtime and the front end use of a model: ``WidgetModel`` is one, and so are the
    placeholders the runtime puts where a widget cannot run (``rcon_core.canvas.placeholders``)."""

    binding: Binding
    shows_every_robot: bool

    @property
    def state(self) -> WidgetState: ...
    @property
    def view_only(self) -> str | None: ...
    def problems(self) -> list[str]: ...
    def start(self) -> None: ...
    def stop(self) -> None: ...
    def set_link(self, up: bool) -> None: ...
    def set_error(self, error: str | None) -> None: ...
    def child_models(self) -> Sequence[HostedModel]:
        """The models of its child widgets (a Compound's), built through ``WidgetContext.build_child``."""
        ...


class NotAValue(ValueError):
    """Raised by ``WidgetModel.to_value``: this message gives no value (a field of the wrong kind); the
    sentence becomes the widget's error and the last value stays."""


# ------------------------------------------------------------------------------------------ the view
@runtime_checkable
class WidgetView(Protocol):
    """A widget's Qt view (a ``QWidget``), built on the GUI thread as ``View(model)``. ``refresh(state)`` is
    called when ``state.seq`` moved, at most once per display frame, with the latest state; it only stores
    what to draw and calls ``update()``. (A view without ``refresh`` still works: the host calls its
    ``update()`` instead and it reads ``model.state`` in ``paintEvent``.)"""

    def refresh(self, state: WidgetState) -> None: ...


# ------------------------------------------------------------------------------------------ settings
@runtime_checkable
class CommandBounds(Protocol):
    """Settings that bound what the widget may send: ``commands(binding)`` -> ``[(field path, largest
    value)]``. The Configure dialog asks before saving a limit beyond the robot's safety envelope."""

    def commands(self, binding: Binding) -> list[tuple[str, float]]: ...


@runtime_checkable
class SizedSettings(Protocol):
    """Settings that know the size a new widget needs (a Compound with many children): ``(w, h)``."""

    def preferred_size(self) -> tuple[float, float]: ...


@runtime_checkable
class StaleAfterSettings(Protocol):
    """Settings that say when the value is stale (``stale_after`` seconds; 0: a static topic; None: the
    model's own default): they override ``WidgetModel.stale_after`` per instance."""

    stale_after: float | None


class CatalogSettings:
    """Base class of settings whose checks depend on the other installed widget kinds (the Compound's
    children): the core passes its catalog (the app's plugin manager, or what a test registered) to
    ``problems``, ``commands`` and ``preferred_size``. Without one (None) they check only what they can."""

    __slots__ = ()

    def problems(self, catalog: WidgetCatalog | None = None) -> list[str]:
        return []

    def commands(self, binding: Binding, catalog: WidgetCatalog | None = None) -> list[tuple[str, float]]:
        return []

    def preferred_size(self, catalog: WidgetCatalog | None = None) -> tuple[float, float] | None:
        return None


def settings_problems(settings: Any, catalog: WidgetCatalog | None = None) -> list[str]:
    """The settings' own ``problems()`` as sentences (none when it has no such method); one that raises is
    itself a problem to show, never a crash."""
    try:
        if isinstance(settings, CatalogSettings):
            found = settings.problems(catalog)
        elif isinstance(settings, WidgetSettings):
            found = settings.problems()
        else:
            return []
        return [str(p) for p in found]
    except Exception as exc:
        return [f"settings check failed: {exc}"]


def stored_settings_problems(spec: WidgetSpec, data: Mapping[str, Any] | None,
                             catalog: WidgetCatalog | None = None) -> list[str]:
    """Everything wrong with a widget's stored settings (a layout's dict), as sentences: values of the wrong
    type (``SettingsError``), then the settings' own checks against ``catalog``."""
    try:
        obj = spec.make_settings(data)
    except SettingsError as exc:
        return list(exc.problems)
    return settings_problems(obj, catalog)


def settings_commands(settings: Any, binding: Binding,
                      catalog: WidgetCatalog | None = None) -> list[tuple[str, float]]:
    """What the settings say the widget may send (``commands``); ``[]`` when they do not say or fail."""
    try:
        if isinstance(settings, CatalogSettings):
            return list(settings.commands(binding, catalog))
        if isinstance(settings, CommandBounds):
            return list(settings.commands(binding))
    except Exception:  # a plugin's hint must never keep the operator from saving
        return []
    return []


def settings_size(settings: Any, catalog: WidgetCatalog | None = None) -> tuple[float, float] | None:
    """The size the settings ask for (``preferred_size``), or None; a hint that fails is no hint."""
    try:
        if isinstance(settings, CatalogSettings):
            size = settings.preferred_size(catalog)
        elif isinstance(settings, SizedSettings):
            size = settings.preferred_size()
        else:
            return None
        if size is None:
            return None
        w, h = size
        return float(w), float(h)
    except Exception:  # a plugin's hint must never stop a widget from being placed
        return None


# ------------------------------------------------------------------------------------------ shared kinds
class CallPhase(enum.StrEnum):
    """Where a call, a press or a goal stands, as the standard widgets show it (a ``str``: ``"ok"``)."""

    BUSY = "busy"
    OK = "ok"
    FAILED = "failed"


class GoalPhase(enum.StrEnum):
    """Where an action goal stands (the standard Action widget, the map's navigation): sent and running
    (``ACTIVE``, ``CANCELING``), or one of the final phases."""

    IDLE = "idle"
    ACTIVE = "active"
    CANCELING = "canceling"
    SUCCEEDED = "succeeded"
    CANCELED = "canceled"
    ABORTED = "aborted"
    FAILED = "failed"
    UNKNOWN = "unknown"

    @property
    def running(self) -> bool:
        return self in (GoalPhase.ACTIVE, GoalPhase.CANCELING)

    @property
    def final(self) -> bool:
        return self in (GoalPhase.SUCCEEDED, GoalPhase.CANCELED, GoalPhase.ABORTED, GoalPhase.FAILED,
                        GoalPhase.UNKNOWN)


#: every optional capability and port attribute the core once looked up by name: declared above (on
#: :class:`Port`, :class:`ModelHooks`, :class:`WidgetView` and the settings protocols) and never looked up
#: with ``getattr``/``hasattr`` by the core or the bundled packages (tests/test_plugin_api.py counts them)
CAPABILITIES = frozenset({
    "on_focus_lost", "on_fleet", "on_robot_link", "dry_run", "shown_message", "composes", "fleet_wide",
    "view_only", "envelope", "link", "widget_id", "changed", "send_action_goal", "refresh",
    "problems", "commands", "preferred_size", "stale_after", "shows_every_robot",
})

#: what a widget package may import from RCON: module -> the names it may use ("*": the module's
#: ``__all__``). Package code (hooks, models, views) and its tests; the rest of ``rcon_core`` may change
#: without notice.
PUBLIC_API: dict[str, frozenset[str] | str] = {
    "rcon_core.plugins": "*",
    "rcon_core.plugins.api": "*",
    "rcon_core.plugins.paths": "*",
    "rcon_core.plugins.send_guard": "*",
    "rcon_core.plugins.children": frozenset({"child_name", "child_problems", "child_role", "role_problem",
                                             "kind_problems"}),
    "rcon_core.msgs": "*",
    "rcon_core.msgs.names": "*",
    "rcon_core.msgs.time": "*",
    "rcon_core.msgs.values": "*",
    "rcon_core.msgs.text": frozenset({"parse_text", "to_text", "MessageTextError"}),
    "rcon_core.bridge": "*",
    "rcon_core.bridge.errors": "*",
    "rcon_core.bridge.envelope": frozenset({"Envelope", "NO_LIMITS", "MAX_LINEAR", "MAX_ANGULAR", "motion_path"}),
    "rcon_core.priority": frozenset({"lower_this_thread"}),
    # tests only
    "rcon_core.testing": "*",
    "rcon_core.matcher": frozenset({"match", "Match", "Rank"}),
    # views only (Qt)
    "rcon_core.app.settings_form": frozenset({"form_label", "tune_form"}),
}
