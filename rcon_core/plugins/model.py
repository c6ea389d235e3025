"""The widget-model base class (pure Python, never Qt) and the bridge port it is given.

A widget is a *model* (this module: talks to the robot, holds the state) plus a *view* (Qt, paints
``model.state``). The canvas runtime builds a model per widget instance::

    model = Model(settings, binding, port, types=type_registry, plugin_settings=shared, dispatch=bt.call)
    model.start()            # on the bridge loop thread: subscribes / advertises as the role says
    ...
    model.stop()             # ends every subscription/advertisement it made (idempotent)

Threads. ``start``, ``stop``, ``on_message`` and ``handle_request`` run on the bridge loop thread
(the runtime arranges it). The view runs on the GUI thread and only (a) reads :attr:`WidgetModel.state`
(a frozen snapshot, built under a lock) and (b) calls the *action* methods :meth:`publish`,
:meth:`publish_value`, :meth:`call`, which hand their work to the loop thread through ``dispatch``.
Compare ``state.seq`` with the last painted one to skip repaints: it increases on every change.

A subclass usually overrides only :meth:`on_message` (turn a message into a value and call
:meth:`set_value`), and, for a server, :meth:`handle_request`. Everything else has a sensible default.

Staleness (decided here for every widget, see :attr:`WidgetState.stale`). A subscriber is stale when no
value came for ``stale_after`` seconds, except on a *static* topic, which delivers once and then stays
quiet by design (a latched ``/map``, a robot description):

- a topic that delivered exactly one message since subscribing, that one within :data:`NO_DATA_AFTER`
  seconds (or ``stale_after`` when longer; what a latched topic does: it sends its message on
  subscribe, a big map over a slow link taking a few seconds), counts as static until a second message
  arrives. rosbridge does not say
  whether a topic is latched; this is what it looks like from the client. A stream that dies right
  after its first message looks the same: the value's age still shows how old it is.
- the operator can say so: a settings object with ``stale_after = 0`` means "static: never stale once
  a value came" (the widget still shows NO DATA when nothing came for :data:`NO_DATA_AFTER` seconds).

After the link comes back the subscription is made again and a latched topic delivers again, so the
count of deliveries starts over.
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import threading
import time
from collections.abc import Awaitable, Callable
from typing import Any, Protocol

import attrs

from rcon_core.msgs.names import normalize

from .context import WidgetContext
from .model_types import ModelTypes
from .paths import PathError, get_path, set_path, split_service_path
from .spec import Role

__all__ = [
    "Binding",
    "BridgePort",
    "WidgetModel",
    "WidgetState",
    "Dispatch",
]


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


class Subscription(Protocol):
    def unsubscribe(self) -> None: ...


class Publisher(Protocol):
    #: a bridge node's publisher returns False when the message was dropped (link down, not latched)
    def publish(self, msg: dict[str, Any]) -> bool | None: ...
    def unadvertise(self) -> None: ...


class ServiceServer(Protocol):
    def unadvertise(self) -> None: ...


class BridgePort(Protocol):
    """The slice of a bridge client node (``client.node(id)``) a model may use. Tests may pass a fake or a
    node; in the app it is a ``rcon_core.canvas.port.GuardedPort`` (sealed; refuses to send when view-only).

    Besides these methods the app's port carries plain attributes a model may read with
    ``getattr(port, name, None)`` (a fake may lack them): ``view_only`` (None or why nothing may be sent),
    ``envelope`` (the robot's safety envelope, ``rcon_core.bridge.envelope.Envelope``, or None; read it at
    each use: it may change while the widget runs),
    ``link`` (an opaque key, the same for every widget on one robot; to share per-robot objects use
    ``WidgetContext.shared``, which is keyed by it) and
    ``widget_id`` (the widget instance's id, the same across rebuilds of its model)."""

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


#: with ``stale_after = 0`` (a static topic), how long nothing at all may come before NO DATA; also how
#: long a latched topic's one message may take to arrive after subscribing (at least)
NO_DATA_AFTER = 5.0

#: runs a plain function on the bridge loop thread (e.g. ``BridgeThread.call``); default: call it now
Dispatch = Callable[[Callable[[], Any]], Any]


def _call_now(fn: Callable[[], Any]) -> Any:
    return fn()


@attrs.frozen
class WidgetState:
    """A snapshot of what the view paints, taken at one instant.

    ``value``: the widget's value (the bound field, or whatever the model's ``set_value`` gave).
    ``message``: the last whole message (or service response) the value came from, or None.
    ``count``: values received so far. ``age``: seconds since the last value, None if never.
    ``stale``: True when ``age`` exceeds the model's ``stale_after`` (or nothing came since start);
    never for a static topic that delivered (see the module docstring). ``static``: the value came from
    a topic that looks latched or that the settings call static (``stale_after = 0``).
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


class WidgetModel:
    """Base class of every widget model. See the module docstring for the threading rules.

    Constructor arguments (the runtime passes all of them):

    - ``settings``: the per-instance settings object (``spec.make_settings(dict)``), or None.
    - ``binding``: a :class:`Binding`.
    - ``port``: a :class:`BridgePort`: in the app a ``GuardedPort`` onto ``client.node(instance_id)``.
    - ``types``: an ``rcon_core.msgs.TypeRegistry`` (for default messages), or None.
    - ``plugin_settings``: the per-kind shared settings object, or None.
    - ``dispatch``: runs a function on the bridge loop thread; default runs it immediately.
    - ``clock``: monotonic seconds, for ages (tests may pass a fake).
    - ``context``: a :class:`~rcon_core.plugins.context.WidgetContext` (other kinds' specs through the
      app's plugin manager, objects shared per robot link); default :meth:`WidgetContext.standalone`.
    """

    #: seconds without a value after which ``state.stale`` is True; None disables; 0 = a static topic
    #: (never stale once a value came). A settings object with a ``stale_after`` attribute overrides it
    #: per instance.
    stale_after: float | None = 5.0
    #: timeout (seconds) for :meth:`call`; None uses the client's default
    call_timeout: float | None = None
    #: True while the widget shows every robot of the workspace (a model sets it in ``on_fleet`` when it
    #: took the other robots on): on a canvas that mixes robots its frame then names no single robot
    shows_every_robot: bool = False
    #: True while the model runs as a preview in the app's add panel: it is offline on purpose and
    #: nothing it sends reaches the robot (a view can say so instead of "link down"). Set by the app.
    dry_run: bool = False

    def __init__(
        self,
        settings: Any,
        binding: Binding,
        port: BridgePort,
        *,
        types: ModelTypes | None = None,
        plugin_settings: Any = None,
        dispatch: Dispatch | None = None,
        clock: Callable[[], float] = time.monotonic,
        context: WidgetContext | None = None,
    ) -> None:
        self.settings = settings
        self.context = context if context is not None else WidgetContext.standalone()
        self.binding = binding
        self.port = port
        #: the app's type registry (None: a model that needs no definitions, e.g. in a bare test)
        self.types: ModelTypes | None = types
        self.plugin_settings = plugin_settings
        self._dispatch: Dispatch = dispatch or _call_now
        self._clock = clock
        self._lock = threading.Lock()
        self._value: Any = None
        self._message: Any = None
        self._count = 0
        self._stamp: float | None = None
        self._started_at: float | None = None
        self._subscribed_at: float | None = None  # when the subscription was (re)made
        self._deliveries = 0  # messages since then
        self._first_delivery: float | None = None  # seconds from subscribing to the first of them
        self._link_down = False
        self._error: str | None = None
        self._seq = 0
        self._running = False
        self._sub: Subscription | None = None
        self._pub: Publisher | None = None
        self._srv: ServiceServer | None = None
        self._tasks: set[asyncio.Task[Any]] = set()
        if settings is not None and getattr(settings, "stale_after", None) is not None:
            self.stale_after = float(settings.stale_after)

    @property
    def view_only(self) -> str | None:
        """Why this widget may not send anything (its port is view-only), or None. Views show their
        controls disabled with this reason; the port refuses regardless (see ``rcon_core.canvas.port``)."""
        try:
            reason = getattr(self.port, "view_only", None)
        except Exception:  # a port that refuses every use (a placeholder's) sends nothing either way
            return None
        return reason if isinstance(reason, str) and reason else None

    # -- lifecycle (bridge loop thread) --------------------------------------------------------------
    @property
    def running(self) -> bool:
        return self._running

    def start(self) -> None:
        """Open what the role needs: subscribe, advertise a topic, or advertise a service (role ACTION
        opens nothing: the model sends goals when asked). Idempotent.

        Does nothing but mark the model running when the binding is incomplete (``problems()``), so
        an unconfigured widget shows its warning instead of failing.
        """
        if self._running:
            return
        b = self.binding
        if not b.problems():
            if b.role is Role.SUBSCRIBE:
                self._sub = self.port.subscribe(
                    b.name, self._receive, type=b.type, **self.subscribe_options()
                )
            elif b.role is Role.PUBLISH:
                self._pub = self.port.advertise(b.name, b.type, **self.advertise_options())
            elif b.role is Role.SERVE:
                self._srv = self.port.advertise_service(b.name, b.type, self._serve)
        with self._lock:
            self._running = True
            self._started_at = self._subscribed_at = self._clock()
            self._deliveries, self._first_delivery = 0, None
            self._seq += 1
        self.on_start()

    def stop(self) -> None:
        """End every subscription/advertisement this model made. Idempotent; never raises for those."""
        if not self._running:
            return
        self.on_stop()
        for handle, method in (
            (self._sub, "unsubscribe"),
            (self._pub, "unadvertise"),
            (self._srv, "unadvertise"),
        ):
            if handle is not None:
                try:
                    getattr(handle, method)()
                except Exception as exc:  # the link may be down; the server drops them with the socket
                    self.set_error(f"while stopping: {exc}")
        self._sub = self._pub = self._srv = None
        for task in list(self._tasks):
            task.cancel()
        with self._lock:
            self._running = False
            self._seq += 1

    def on_start(self) -> None:
        """Hook for subclasses: called at the end of :meth:`start`."""

    def on_stop(self) -> None:
        """Hook for subclasses: called at the beginning of :meth:`stop`."""

    def subscribe_options(self) -> dict[str, Any]:
        """Extra keywords for ``port.subscribe`` (throttle_rate, queue_length, compression...)."""
        return {}

    def advertise_options(self) -> dict[str, Any]:
        """Extra keywords for ``port.advertise`` (latch, queue_size, max_age: the freshness limit)."""
        return {}

    # -- incoming (bridge loop thread) ---------------------------------------------------------------
    def _receive(self, msg: dict[str, Any]) -> None:
        with self._lock:
            self._deliveries += 1
            if self._deliveries == 1 and self._subscribed_at is not None:
                self._first_delivery = self._clock() - self._subscribed_at
        try:
            self.on_message(msg)
        except Exception as exc:  # a bad message must not break the bridge's callback loop
            self.set_error(f"{type(exc).__name__}: {exc}")

    def on_message(self, msg: dict[str, Any]) -> None:
        """A message arrived (subscribers). Default: the bound field becomes the value."""
        path = self.binding.field_path
        try:
            value = get_path(msg, path) if path else msg
        except PathError as exc:
            self.set_error(str(exc))
            return
        self.set_value(value, message=msg)

    def _serve(self, request: dict[str, Any]) -> Any:
        return self.handle_request(request)

    def handle_request(self, request: dict[str, Any]) -> dict[str, Any] | Awaitable[dict[str, Any]]:
        """Answer a service request (role SERVE). Default: an all-default response, and the request
        becomes the value (so a view can show the last request)."""
        self.set_value(request, message=request)
        if self.types is not None:
            return self.types.default(self._service_part_type("response"))
        return {}

    def _service_part_type(self, part: str) -> str:
        # registries name service parts by the service type plus the part; ask the registry if it can
        if self.types is not None:
            return self.types.service_part_name(self.binding.type, part)
        return f"{self.binding.type}_{part.capitalize()}"

    # -- outgoing (any thread) -----------------------------------------------------------------------
    def publish(self, msg: dict[str, Any]) -> bool:
        """Publish a whole message on the bound topic. Returns False (and sets ``error``) if not running,
        or if the message does not fit the bound type: rosbridge drops such a message and says so only in
        the robot's log, so it is checked here when the type registry knows the type (a wrong field name,
        text for a number, a number out of the field's range); missing fields are fine (the robot fills
        in defaults)."""
        if self._pub is None:
            self.set_error("not publishing: the widget is not running or has no topic")
            return False
        misfit = self._misfit(msg)
        if misfit:
            self.set_error(f"not sent: the message does not fit {self.binding.type} ({misfit})")
            return False
        pub = self._pub

        def send() -> None:
            try:
                pub.publish(msg)
            except Exception as exc:  # a view-only port refuses, a closed link raises: shown, not lost
                self.set_error(str(exc) or type(exc).__name__)

        self._dispatch(send)
        return True

    def _misfit(self, msg: Any) -> str:
        """The first problems of ``msg`` as a message of the bound type; "" when it fits or cannot be
        checked (no registry, a type it does not know)."""
        check = getattr(self.types, "validate", None)
        if check is None or not self.binding.type:
            return ""
        try:
            if not self.types.has(self.binding.type):  # type: ignore[union-attr]
                return ""
            problems = check(self.binding.type, msg)
        except Exception:  # a registry that cannot tell must not stop the publish
            return ""
        return "; ".join(str(p) for p in problems[:3])

    def build_message(self, value: Any, path: str | None = None) -> dict[str, Any]:
        """A message of the bound type with ``value`` at ``path`` (default: the bound field path).

        The rest of the message is the type's default (needs ``types``), else an empty dict.
        """
        path = self.binding.field_path if path is None else path
        if not path:
            if not isinstance(value, dict):
                raise PathError("the whole message must be a dict")
            return value
        base = self.types.default(self.binding.type) if self.types is not None else {}
        return set_path(base, path, value)

    def publish_value(self, value: Any) -> bool:
        """Publish ``value`` at the bound field of an otherwise default message."""
        return self.publish(self.build_message(value))

    def call(self, args: dict[str, Any] | None = None) -> concurrent.futures.Future[dict[str, Any]]:
        """Call the bound service from any thread. The response becomes ``state.message`` and its bound
        ``response.*`` field (if any) the value. Returns a future with the response (or the error)."""
        fut: concurrent.futures.Future[dict[str, Any]] = concurrent.futures.Future()

        def go() -> None:
            try:
                loop = asyncio.get_running_loop()
            except RuntimeError:
                fut.set_exception(
                    RuntimeError("call() needs the bridge loop: pass dispatch=BridgeThread.call")
                )
                return
            task = loop.create_task(self._call_into(args, fut))
            self._tasks.add(task)
            task.add_done_callback(self._tasks.discard)

        self._dispatch(go)
        return fut

    async def call_async(self, args: dict[str, Any] | None = None) -> dict[str, Any]:
        """Same as :meth:`call`, awaited on the bridge loop."""
        fut: concurrent.futures.Future[dict[str, Any]] = concurrent.futures.Future()
        await self._call_into(args, fut)
        return fut.result()

    async def _call_into(self, args: dict[str, Any] | None, fut: concurrent.futures.Future[Any]) -> None:
        try:
            response = await self.port.call_service(self.binding.name, args, timeout=self.call_timeout)
        except Exception as exc:
            self.set_error(f"call {self.binding.name} failed: {exc}")
            if not fut.done():
                fut.set_exception(exc)
            return
        self.on_response(response)
        if not fut.done():
            fut.set_result(response)

    def on_response(self, response: dict[str, Any]) -> None:
        """A service response arrived (role CALL). Default: the first ``response.*`` path is the value."""
        value: Any = response
        for path in self.binding.field_paths:
            part, rest = split_service_path(path)
            if part == "response":
                try:
                    value = get_path(response, rest)
                except PathError as exc:
                    self.set_error(str(exc))
                    return
                break
        self.set_value(value, message=response)

    # -- state (thread-safe) -------------------------------------------------------------------------
    def set_value(self, value: Any, message: Any = None) -> None:
        """Record a new value (any thread): stamps it, clears the error, bumps ``seq``; the front end is
        told at once (:meth:`announce`)."""
        with self._lock:
            self._value = value
            self._message = message
            self._count += 1
            self._stamp = self._clock()
            self._error = None
            self._seq += 1
        self.announce()

    def announce(self) -> None:
        """Tell the front end this model has something new to show (any thread; the port's ``changed``,
        when it has one: the app's ports wake the GUI, which repaints within the frame)."""
        changed = getattr(self.port, "changed", None)
        if changed is not None:
            changed()

    def replace_value(self, value: Any) -> None:
        """Change what the view shows without counting a new value from the robot (any thread).

        For changes the operator makes (a filter) or data from a widget's extra subscriptions: ``count``,
        the age and the error stay as they are; ``seq`` moves so the view repaints.
        """
        with self._lock:
            self._value = value
            self._seq += 1
        self.announce()

    def set_error(self, error: str | None) -> None:
        """Record a problem to show on the widget (None clears it)."""
        with self._lock:
            if error == self._error:
                return
            self._error = error
            self._seq += 1
        self.announce()

    def set_link(self, up: bool) -> None:
        """The runtime tells the model the bridge connection went down or came back."""
        with self._lock:
            if self._link_down == up:
                self._link_down = not up
                self._seq += 1
                if up:  # subscribed again: a latched topic delivers again
                    self._subscribed_at = self._clock()
                    self._deliveries, self._first_delivery = 0, None

    def on_commands_held(self, reason: str | None) -> None:
        """The robot's bridge holds this link's commands behind a service call it has not answered
        (rosbridge 2.1.0 runs one connection's frames one at a time: ``rcon_core/bridge/held.py``):
        ``reason`` says so ("commands held: the robot's bridge is still busy with /dock"); None once it
        answered. Called by the runtime on the loop thread. Default: nothing. A widget that streams
        commands (the teleop pad) stops sending while held, so nothing more queues behind the call, and
        says why."""

    @property
    def state(self) -> WidgetState:
        """A consistent snapshot for the view (any thread)."""
        with self._lock:
            now = self._clock()
            age = None if self._stamp is None else max(0.0, now - self._stamp)
            static = self._static()
            stale = False
            if self.stale_after is not None and self._running and self.binding.role is Role.SUBSCRIBE:
                if age is None:  # nothing yet: NO DATA
                    stale = now - (self._started_at or now) > (self.stale_after or NO_DATA_AFTER)
                elif not static:
                    stale = age > self.stale_after
            return WidgetState(
                value=self._value,
                message=self._message,
                count=self._count,
                age=age,
                stale=stale,
                link_down=self._link_down,
                error=self._error,
                running=self._running,
                seq=self._seq,
                static=static,
            )

    def _static(self) -> bool:
        """Whether the value came from a static topic (under the lock): the settings say so, or it looks
        latched (one delivery, right after subscribing)."""
        if self._stamp is None:
            return False
        if self.stale_after == 0:
            return True
        window = max(NO_DATA_AFTER, self.stale_after or 0.0)
        return self._deliveries == 1 and self._first_delivery is not None and self._first_delivery <= window

    def problems(self) -> list[str]:
        """Everything that keeps this widget from working, as sentences (binding + settings)."""
        out = list(self.binding.problems())
        if self.settings is not None and hasattr(self.settings, "problems"):
            out += list(self.settings.problems())
        return out
