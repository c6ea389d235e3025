"""The port every widget model talks through: a sealed slice of its bridge node, and view-only mode.

The canvas runtime never hands a model its bridge node. It hands it a :class:`GuardedPort`, which offers
exactly the :class:`~rcon_core.plugins.model.BridgePort` methods (``subscribe``, ``advertise``,
``call_service``, ``advertise_service``, ``send_action_goal``, ``close``) and returns handles that offer
only ``unsubscribe`` / ``publish`` / ``unadvertise`` (and a goal's ``result``, ``cancel``, ``status``).
No attribute of the port or of a handle leads to the node or to the :class:`BridgeClient` (the node and
the bridge's own handles live only in closures), so a widget package cannot reach the raw client
through its port to get round the rules below.

**View-only** (``view_only="reason"``): the port never publishes, calls or serves anything.

- ``advertise`` sends nothing to the robot and returns a publisher whose ``publish`` raises
  :class:`ViewOnlyError` (the model shows the sentence as the widget's error);
- ``call_service`` raises :class:`ViewOnlyError` without sending, except for the read-only rosapi
  queries in :data:`READ_ONLY_SERVICES` (types, topic lists: what the app itself asks for);
- ``advertise_service`` sends nothing and returns an inert handle; ``send_action_goal`` raises;
- ``subscribe`` works as usual: a view-only widget shows everything.

**The safety envelope** of the robot (``port.envelope``: a
:class:`~rcon_core.bridge.envelope.Envelope`, or None) is read from the node's client at each use, so a
widget can show what will actually be sent; the bridge client holds every motion command to it whatever
a widget does (``rcon_core/bridge/envelope.py``).

Each refusal is counted (``port.refused``) and reported through ``on_refused(sentence)`` (the runtime
puts it on the widget). Models read ``port.view_only`` (the reason, or None) to show their controls as
disabled; the app disables the view of every publishing, calling or serving widget too.

Under the port, the bridge itself refuses the same for a robot marked view-only
(``rcon_core.bridge.guard``: the mark is on the robot's link, so the app's panels and anything else on
that link are refused too); the port's own refusal is what a view-only *canvas* has, and what lets the
widget show its controls disabled. :class:`ViewOnlyError` and :data:`READ_ONLY_SERVICES` are the bridge's.

What this is not: a sandbox. A widget package is Python code running in the app's process with the
operator's rights; it could open its own WebSocket to the robot. View-only stops the widgets RCON runs
from sending through RCON; a robot that must not be commanded is protected on the robot side (rosbridge's
``topics_glob`` / ``services_glob``, rosauth). See docs/security.md.
"""

from __future__ import annotations

import asyncio
import inspect
import logging
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

from rcon_core.bridge.guard import READ_ONLY_SERVICES, ViewOnlyError, read_only_service

if TYPE_CHECKING:
    from rcon_core.bridge.envelope import Envelope

    from .fleet import BridgeNode

__all__ = ["GuardedPort", "ViewOnlyError", "READ_ONLY_SERVICES"]

log = logging.getLogger(__name__)

class _Handle:
    """What ``subscribe`` / ``advertise_service`` return: only a way to end it."""

    __slots__ = ("unsubscribe", "unadvertise")

    def __init__(self, end: Callable[[], None]) -> None:
        self.unsubscribe = end
        self.unadvertise = end


class _Publisher:
    """What ``advertise`` returns: ``publish(msg)`` and ``unadvertise()``."""

    __slots__ = ("publish", "unadvertise")

    def __init__(self, publish: Callable[[dict[str, Any]], Any], end: Callable[[], None]) -> None:
        self.publish = publish
        self.unadvertise = end


class _Goal:
    """What ``send_action_goal`` returns: ``await result()``, ``cancel()``, ``status``, ``done``."""

    __slots__ = ("result", "cancel", "_status", "_done")

    def __init__(self, goal: Any) -> None:
        self.result: Callable[..., Any] = lambda timeout=None: goal.result(timeout)
        self.cancel: Callable[[], Any] = lambda: goal.cancel()
        self._status: Callable[[], Any] = lambda: goal.status
        self._done: Callable[[], Any] = lambda: goal.done

    @property
    def status(self) -> Any:
        return self._status()

    @property
    def done(self) -> bool:
        return bool(self._done())


def _noop() -> None:
    return None


class GuardedPort:
    """A widget's port onto its bridge node (see the module docstring).

    ``node``: the widget's bridge node (``client.node(widget_id)``) or anything with the same methods.
    ``notify``: called after each incoming message, service request and service response (the app
    repaints at once). ``view_only``: None, or the sentence saying why nothing may be sent.
    ``on_refused(sentence)``: told about each refusal. ``link``: an opaque, hashable key naming the
    connection (the same for every widget on one robot); the runtime keys each model's
    ``WidgetContext.shared`` objects by it (the teleop pads of one robot merge their axes through one),
    so nothing needs a way to the connection itself. ``widget_id``: the
    widget instance's id, the same across rebuilds of its model (a model may leave word for its successor).
    """

    __slots__ = ("_ops", "_notify", "view_only", "refused", "link", "widget_id")

    #: what a model publishes through this port goes to the robot (a Compound's child port composes)
    composes = False

    def __init__(
        self,
        node: BridgeNode,
        *,
        notify: Callable[[], None] | None = None,
        view_only: str | None = None,
        on_refused: Callable[[str], None] | None = None,
        link: Any = None,
        widget_id: str | None = None,
    ) -> None:
        self.link = link
        self.widget_id = widget_id
        self.view_only = view_only
        self.refused = 0
        self._notify = notify
        self._ops = _operations(self, node, notify, view_only, on_refused)

    @property
    def envelope(self) -> Envelope | None:
        """The robot's safety envelope now (an ``Envelope``, or None: no limit); read it at each use."""
        envelope: Envelope | None = self._ops["envelope"]()
        return envelope

    def changed(self) -> None:
        """The model has something new to show (any thread): the front end repaints it at once.  Called
        by ``WidgetModel`` whenever its state moves, so a value made off the loop (an image decoded in a
        worker) does not wait for the front end's next pass over every widget."""
        if self._notify is not None:
            self._notify()

    def subscribe(self, topic: str, callback: Callable[[dict[str, Any]], Any], **options: Any) -> Any:
        return self._ops["subscribe"](topic, callback, **options)

    def advertise(self, topic: str, type: str, **options: Any) -> Any:
        return self._ops["advertise"](topic, type, **options)

    async def call_service(self, name: str, args: Any = None, timeout: float | None = None) -> Any:
        return await self._ops["call_service"](name, args, timeout)

    def advertise_service(self, name: str, type: str, handler: Callable[[dict[str, Any]], Any]) -> Any:
        return self._ops["advertise_service"](name, type, handler)

    def send_action_goal(self, action: str, action_type: str, args: Any = None, feedback: Any = None,
                         **options: Any) -> Any:
        return self._ops["send_action_goal"](action, action_type, args, feedback, **options)

    def close(self) -> None:
        self._ops["close"]()

    def __repr__(self) -> str:
        return f"<GuardedPort view_only={self.view_only!r}>"


def _operations(port: GuardedPort, node: BridgeNode, notify: Callable[[], None] | None, view_only: str | None,
                on_refused: Callable[[str], None] | None) -> dict[str, Callable[..., Any]]:
    """The port's operations as closures over ``node`` (so no attribute of the port names it)."""

    def ping() -> None:
        if notify is not None:
            try:
                notify()
            except Exception:
                log.exception("activity listener failed")

    def refuse(what: str) -> str:
        port.refused += 1
        text = f"view-only: {what} was not sent ({view_only})"
        if on_refused is not None:
            try:
                on_refused(text)
            except Exception:
                log.exception("refusal listener failed")
        return text

    def subscribe(topic: str, callback: Callable[[Any], Any], **options: Any) -> _Handle:
        def watched(msg: Any) -> Any:
            try:
                return callback(msg)
            finally:
                ping()

        sub = node.subscribe(topic, watched, **options)
        return _Handle(lambda: sub.unsubscribe())

    def advertise(topic: str, type: str, **options: Any) -> _Publisher:
        if view_only is not None:
            def refused_publish(_msg: dict[str, Any]) -> bool:
                raise ViewOnlyError(refuse(f"publishing on {topic}"))

            return _Publisher(refused_publish, _noop)
        pub = node.advertise(topic, type, **options)
        return _Publisher(lambda msg: pub.publish(msg), lambda: pub.unadvertise())

    async def call_service(name: str, args: Any, timeout: float | None) -> Any:
        if view_only is not None and not read_only_service(name):
            raise ViewOnlyError(refuse(f"the call to {name}"))
        try:
            return await node.call_service(name, args, timeout=timeout)
        finally:
            if notify is not None:  # after the caller's on_response, which runs in this task step
                asyncio.get_running_loop().call_soon(ping)

    def advertise_service(name: str, type: str, handler: Callable[[Any], Any]) -> _Handle:
        if view_only is not None:
            refuse(f"serving {name}")
            return _Handle(_noop)

        def watched(request: Any) -> Any:
            result = handler(request)
            if inspect.isawaitable(result):
                async def finish() -> Any:
                    try:
                        return await result
                    finally:
                        ping()

                return finish()
            ping()
            return result

        srv = node.advertise_service(name, type, watched)
        return _Handle(lambda: srv.unadvertise())

    def send_action_goal(action: str, action_type: str, args: Any, feedback: Any, **options: Any) -> _Goal:
        if view_only is not None:
            raise ViewOnlyError(refuse(f"the goal to {action}"))
        watched = None
        if feedback is not None:
            def watched(values: Any) -> Any:  # each feedback repaints at once, like a message
                try:
                    return feedback(values)
                finally:
                    ping()

        return _Goal(node.send_action_goal(action, action_type, args, feedback=watched, **options))

    return {
        "subscribe": subscribe,
        "advertise": advertise,
        "call_service": call_service,
        "advertise_service": advertise_service,
        "send_action_goal": send_action_goal,
        "close": lambda: node.close(),
        "envelope": lambda: _envelope_of(node),
    }


@runtime_checkable
class _HasEnvelope(Protocol):
    @property
    def envelope(self) -> Envelope | None: ...


def _envelope_of(node: Any) -> Envelope | None:
    """The envelope of the node's client (a ``BridgeClient``); None for a node without one (a test's fake)."""
    client = getattr(node, "client", None)
    return client.envelope if isinstance(client, _HasEnvelope) else None
