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

A subscriber that only turns the bound field into what its view paints overrides the small hook
:meth:`WidgetModel.to_value` instead (raise :class:`~rcon_core.plugins.api.NotAValue` to skip a message with
a sentence as the error). The optional capabilities (``on_focus_lost``, ``on_fleet``, ``on_robot_link``,
``shown_message``, ``dry_run``) are documented no-ops here; the runtime calls them directly
(:class:`~rcon_core.plugins.api.ModelHooks`).

Staleness is decided here for every widget (see :attr:`WidgetState.stale`), by the rules of
:mod:`rcon_core.plugins.staleness`.
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import threading
import time
from collections.abc import Awaitable, Callable
from typing import Any

from rcon_core.bridge.errors import NotConnectedError
from rcon_core.msgs.names import part_name

from .api import (
    Binding,
    BridgePort,
    NotAValue,
    Port,
    Publisher,
    RobotPort,
    ServiceServer,
    StaleAfterSettings,
    Subscription,
    WidgetState,
    as_port,
    settings_problems,
)
from .context import WidgetContext
from .model_types import ModelTypes
from .paths import PathError, get_path, set_path, split_service_path
from .spec import Role
from .staleness import NO_DATA_AFTER, Staleness

__all__ = [
    "Binding",
    "BridgePort",
    "Port",
    "WidgetModel",
    "WidgetState",
    "Dispatch",
    "NO_DATA_AFTER",
]

#: runs a plain function on the bridge loop thread (e.g. ``BridgeThread.call``); default: call it now
Dispatch = Callable[[Callable[[], Any]], Any]


def _call_now(fn: Callable[[], Any]) -> Any:
    return fn()


class WidgetModel:
    """Base class of every widget model. See the module docstring for the threading rules.

    Constructor arguments (the runtime passes all of them):

    - ``settings``: the per-instance settings object (``spec.make_settings(dict)``), or None.
    - ``binding``: a :class:`Binding`.
    - ``port``: a :class:`~rcon_core.plugins.api.Port`: in the app a ``GuardedPort`` onto
      ``client.node(instance_id)``. A partial one (a bare bridge node, a test's fake) is completed with the
      defaults of a widget outside any canvas (:func:`~rcon_core.plugins.api.as_port`): ``self.port`` is
      always a complete ``Port``.
    - ``types``: the app's type registry (``rcon_core.msgs.TypeRegistry``); the runtime always passes one.
      Without it (a bare test) the model gets a standard registry of its own: ``self.types`` is never None.
    - ``plugin_settings``: the per-kind shared settings object, or None.
    - ``dispatch``: runs a function on the bridge loop thread; default runs it immediately.
    - ``clock``: monotonic seconds, for ages (tests may pass a fake).
    - ``context``: a :class:`~rcon_core.plugins.context.WidgetContext` (the catalog of other kinds, child
      widgets, objects shared per robot link); default: one that knows no other kind.
    """

    #: seconds without a value after which ``state.stale`` is True; None disables; 0 = a static topic
    #: (never stale once a value came). A settings object with a ``stale_after`` attribute overrides it
    #: per instance (:class:`~rcon_core.plugins.api.StaleAfterSettings`).
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
        port: BridgePort | Port,
        *,
        types: ModelTypes | None = None,
        plugin_settings: Any = None,
        dispatch: Dispatch | None = None,
        clock: Callable[[], float] = time.monotonic,
        context: WidgetContext | None = None,
    ) -> None:
        self.settings = settings
        self.context = context if context is not None else WidgetContext()
        self.binding = binding
        self.port = port
        if types is None:  # a bare test: the standard types (ROS 1 spelling), as `rcon type` knows them
            from rcon_core.msgs import TypeRegistry

            types = TypeRegistry.standard()
        #: the app's type registry (the standard types when none was given; never None)
        self.types: ModelTypes = types
        self.plugin_settings = plugin_settings
        self._dispatch: Dispatch = dispatch or _call_now
        self._clock = clock
        self._lock = threading.Lock()
        self._value: Any = None
        self._message: Any = None
        self._count = 0
        self._stamp: float | None = None
        self._staleness = Staleness()
        self._link_down = False
        self._error: str | None = None
        self._seq = 0
        self._running = False
        self._sub: Subscription | None = None
        self._pub: Publisher | None = None
        self._srv: ServiceServer | None = None
        self._tasks: set[asyncio.Task[Any]] = set()
        if isinstance(settings, StaleAfterSettings) and settings.stale_after is not None:
            self.stale_after = float(settings.stale_after)

    @property
    def port(self) -> Port:
        """The model's port, always a complete :class:`~rcon_core.plugins.api.Port` (one assigned later, a
        test's fake, is completed too)."""
        return self._port

    @port.setter
    def port(self, port: BridgePort | Port) -> None:
        self._port = as_port(port)

    @property
    def view_only(self) -> str | None:
        """Why this widget may not send anything (its port is view-only), or None. Views show their
        controls disabled with this reason; the port refuses regardless (see ``rcon_core.canvas.port``)."""
        reason = self.port.view_only
        return reason if isinstance(reason, str) and reason else None

    @property
    def clock(self) -> Callable[[], float]:
        """The model's clock (monotonic seconds; a test's fake)."""
        return self._clock

    @property
    def dispatch(self) -> Dispatch:
        """Runs a function on the bridge loop thread (what the model was given)."""
        return self._dispatch

    # -- optional capabilities (documented no-ops; see rcon_core.plugins.api.ModelHooks) --------------
    def on_focus_lost(self) -> None:
        """The window lost focus or the canvas is being left (bridge thread, before the models stop). A
        model that moves the robot stops commanding here (publishes its zero). Keep it quick."""

    def on_fleet(self, robots: list[RobotPort]) -> None:
        """One :class:`~rcon_core.plugins.api.RobotPort` per robot of the workspace (bridge thread, before
        :meth:`start`). Override it to show every robot: the model is then :attr:`fleet_wide`, subscribes on
        each port itself, and sets :attr:`shows_every_robot` when it took the others on."""

    def on_robot_link(self, robot_id: str, up: bool) -> None:
        """A fleet-wide model hears each robot's link state here (bridge thread)."""

    def on_commands_held(self, reason: str | None) -> None:
        """The robot's bridge holds this link's commands behind a service call it has not answered
        (rosbridge 2.1.0 runs one connection's frames one at a time: ``rcon_core/bridge/held.py``):
        ``reason`` says so ("commands held: the robot's bridge is still busy with /dock"); None once it
        answered (bridge thread). A widget that streams commands (the teleop pad) stops sending while held,
        so nothing more queues behind the call, and says why."""

    def shown_message(self) -> dict[str, Any] | None:
        """As a Compound's input child: a message of the bound type holding the value the widget shows
        (bridge thread); raise ``ValueError`` with the problem when it cannot say (the send is blocked, the
        child named). None: the compound takes what the child last published."""
        return None

    @property
    def fleet_wide(self) -> bool:
        """Whether the model takes every robot (it overrides :meth:`on_fleet`)."""
        return type(self).on_fleet is not WidgetModel.on_fleet

    def child_models(self) -> list[Any]:
        """The child widgets' models built through ``context.build_child`` (a Compound's children)."""
        return list(self.context.children)

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
            self._staleness.started(self._clock())
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
            self._staleness.delivered(self._clock())
        try:
            self.on_message(msg)
        except NotAValue as exc:  # the model's own sentence: the message gives no value
            self.set_error(str(exc))
        except Exception as exc:  # a bad message must not break the bridge's callback loop
            self.set_error(f"{type(exc).__name__}: {exc}")

    def on_message(self, msg: dict[str, Any]) -> None:
        """A message arrived (subscribers). Default: the bound field, turned by :meth:`to_value`, becomes
        the value (a missing field is the widget's error). Override this only to use the whole message."""
        path = self.binding.field_path
        try:
            value = get_path(msg, path) if path else msg
        except PathError as exc:
            self.set_error(str(exc))
            return
        self.set_value(self.to_value(value, msg), message=msg)

    def to_value(self, field_value: Any, msg: dict[str, Any]) -> Any:
        """The small hook (bridge thread): what the view gets for the bound field's ``field_value`` (``msg``
        is the whole message). Default: the field as it came. Raise
        :class:`~rcon_core.plugins.api.NotAValue` with a sentence to skip the message and show the sentence
        as the error; any other exception shows as ``TypeError: ...``."""
        return field_value

    def _serve(self, request: dict[str, Any]) -> Any:
        return self.handle_request(request)

    def handle_request(self, request: dict[str, Any]) -> dict[str, Any] | Awaitable[dict[str, Any]]:
        """Answer a service request (role SERVE). Default: an all-default response, and the request
        becomes the value (so a view can show the last request)."""
        self.set_value(request, message=request)
        response = self._service_part_type("response")
        return self.types.default(response) if self.types.has(response) else {}

    def _service_part_type(self, part: str) -> str:
        # registries name service parts by the service type plus the part; one that does not know the
        # service yet: the canonical part name
        try:
            return self.types.service_part_name(self.binding.type, part)
        except (KeyError, ValueError):
            try:
                return part_name(self.binding.type, part)
            except ValueError:
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
        if not self.binding.type:
            return ""
        try:
            if not self.types.has(self.binding.type):
                return ""
            problems = self.types.validate(self.binding.type, msg)
        except Exception:  # a registry that cannot tell must not stop the publish
            return ""
        return "; ".join(str(p) for p in problems[:3])

    def build_message(self, value: Any, path: str | None = None) -> dict[str, Any]:
        """A message of the bound type with ``value`` at ``path`` (default: the bound field path).

        The rest of the message is the type's default when the registry knows the type, else an empty dict
        (the robot fills in defaults).
        """
        path = self.binding.field_path if path is None else path
        if not path:
            if not isinstance(value, dict):
                raise PathError("the whole message must be a dict")
            return value
        base = self.types.default(self.binding.type) if self.types.has(self.binding.type) else {}
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
            if self._link_down:  # a tap is the operator's intent now: never kept to reach the robot later
                raise NotConnectedError("not sent: the robot's link is down (a call is not kept to be sent "
                                        "when it comes back; tap again then)")
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
        """Tell the front end this model has something new to show (any thread; the port's ``changed``:
        the app's ports wake the GUI, which repaints within the frame)."""
        self.port.changed()

    def touch(self) -> None:
        """What the view shows changed without a new value (a child widget's state, any thread): ``seq``
        moves so the view repaints; the value, count, age and error stay."""
        with self._lock:
            self._seq += 1
        self.announce()

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
                    self._staleness.resubscribed(self._clock())

    @property
    def state(self) -> WidgetState:
        """A consistent snapshot for the view (any thread)."""
        with self._lock:
            now = self._clock()
            age = None if self._stamp is None else max(0.0, now - self._stamp)
            stale, static = self._staleness.judge(
                now, age, self.stale_after, self._running and self.binding.role is Role.SUBSCRIBE)
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

    def problems(self) -> list[str]:
        """Everything that keeps this widget from working, as sentences (binding + settings, the settings
        checked against the context's catalog)."""
        return list(self.binding.problems()) + settings_problems(self.settings, self.context.catalog)
