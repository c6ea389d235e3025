"""Nodes: every consumer of the bridge (a widget, a CLI command, a panel) is a node with a unique id.

A node owns what it asked for (subscriptions, publishers, advertised services and actions, action goals) and
``node.close()`` ends all of it.  Messages are routed only to the nodes that subscribed; nodes on the
same topic share one rosbridge subscription (see ``topics.py``).  All methods run on the client's loop.
"""

from __future__ import annotations

import asyncio
import enum
import logging
from collections.abc import Awaitable, Callable
from typing import TYPE_CHECKING, Any

from .errors import BridgeError
from .freshness import AUTO, resolve_max_age
from .guard import ViewOnlyError
from .protocol import COMPRESSIONS

if TYPE_CHECKING:
    from .host import NodeClient

log = logging.getLogger(__name__)

MessageCallback = Callable[[dict[str, Any]], None]
ServiceHandler = Callable[[dict[str, Any]], "dict[str, Any] | Awaitable[dict[str, Any]]"]


class Subscription:
    """One node's interest in a topic.  ``unsubscribe()`` is idempotent."""

    __slots__ = ("node", "topic", "callback", "type", "throttle_rate", "queue_length", "compression",
                 "fragment_size", "active", "raw")

    def __init__(self, node: Node, topic: str, callback: MessageCallback, type: str | None, throttle_rate: int,
                 queue_length: int, compression: str, fragment_size: int | None, raw: bool = False) -> None:
        #: the callback takes the recorded form: a ``topics.RawPayload`` (the server's bytes, undecoded)
        #: while the topic arrives as ``cbor-raw``, else the decoded dict (see ``Node.subscribe``)
        self.raw = raw
        self.node = node
        self.topic = topic
        self.callback = callback
        self.type = type
        self.throttle_rate = throttle_rate
        self.queue_length = queue_length
        self.compression = compression
        self.fragment_size = fragment_size
        self.active = True

    def unsubscribe(self) -> None:
        if self.active:
            self.active = False
            self.node.subscriptions.discard(self)
            self.node.session.remove_subscription(self)

    def __repr__(self) -> str:
        return f"<Subscription {self.topic} node={self.node.id} active={self.active}>"


class Publisher:
    """One node's right to publish on a topic.  ``publish`` never blocks.

    While the link is down a publish is not queued, except for latched topics whose latest value is kept
    and sent once the advertisement is restored after a reconnect; ``dropped`` counts the others.
    ``max_age`` is the freshness limit in seconds (None: none): a publish that cannot be written within it
    -- the link is DEGRADED or stalling, or the frame waited that long in the outgoing queue -- is dropped
    and counted in ``dropped`` too (see ``freshness.py``).
    """

    __slots__ = ("node", "topic", "type", "latch", "queue_size", "max_age", "active", "sent", "dropped", "_session")

    def __init__(self, node: Node, topic: str, type: str, latch: bool, queue_size: int,
                 max_age: float | None = None) -> None:
        self.node = node
        self._session = node.session
        self.topic = topic
        self.type = type
        self.latch = latch
        self.queue_size = queue_size
        self.max_age = max_age
        self.active = True
        self.sent = 0
        self.dropped = 0

    def publish(self, msg: dict[str, Any]) -> bool:
        """Send ``msg``; returns False when it was dropped (link down and not latched)."""
        if not self.active:
            raise BridgeError(f"publish on {self.topic} after unadvertise")
        if not isinstance(msg, dict):
            raise TypeError(f"publish on {self.topic}: msg must be a dict, got {type(msg).__name__}")
        tap = self._session.tap
        if not tap.listeners:
            return self._session.publish(self, msg)
        try:
            ok = self._session.publish(self, msg)
        except Exception as exc:
            tap.emit("publish", self.node.id, self.topic, self.type, msg, f"refused: {exc}")
            raise
        tap.emit("publish", self.node.id, self.topic, self.type, msg, "sent" if ok else "dropped")
        return ok

    def unadvertise(self) -> None:
        if self.active:
            self.active = False
            self.node.publishers.discard(self)
            self._session.remove_publisher(self)

    def __repr__(self) -> str:
        return f"<Publisher {self.topic} [{self.type}] node={self.node.id} active={self.active}>"


class ServiceServer:
    """A service this client provides.  Incoming calls are answered with the handler's dict.

    A handler that raises (or returns something other than a dict) is logged and answered with the
    response type's default message, the error text in its ``message`` field when it has a string one;
    ``failures`` counts those answers.
    """

    __slots__ = ("node", "service", "type", "handler", "active", "calls", "failures")

    def __init__(self, node: Node, service: str, type: str, handler: ServiceHandler) -> None:
        self.node = node
        self.service = service
        self.type = type
        self.handler = handler
        self.active = True
        self.calls = 0
        self.failures = 0

    def unadvertise(self) -> None:
        if self.active:
            self.active = False
            self.node.services.discard(self)
            self.node.session.services.remove(self)


class GoalStatus(enum.IntEnum):
    """``action_msgs/msg/GoalStatus`` codes, as ``action_result.status`` carries them."""

    UNKNOWN = 0
    ACCEPTED = 1
    EXECUTING = 2
    CANCELING = 3
    SUCCEEDED = 4
    CANCELED = 5
    ABORTED = 6

    @property
    def word(self) -> str:
        """The status in words: ``"succeeded"``, ``"canceled"``, ``"aborted"``, ``"executing"``..."""
        return self.name.lower()


class ActionGoal:
    """A goal sent with ``send_action_goal``.  ``await goal.result()``; ``goal.cancel()``.

    ``result()`` returns the result message (``values``) of a goal that ended -- check ``status``
    (``GoalStatus.SUCCEEDED``, ``CANCELED``, ``ABORTED``) or ``succeeded``.  It raises ``ActionError``
    when the goal could not be run (``ActionTimeoutError`` after the client-side timeout) and
    ``ConnectionLostError`` when the link dropped while the goal was active.
    """

    def __init__(self, node: Node, action: str, action_type: str, goal_id: str,
                 feedback: MessageCallback | None) -> None:
        self.node = node
        self.action = action
        self.action_type = action_type
        self.id = goal_id
        self.feedback_callback = feedback
        self.feedback_count = 0
        self.last_feedback: dict[str, Any] | None = None
        self.status: int | None = None
        self.cancel_requested = False
        #: the result of a goal that first ended with "no answer" and was answered later (goals.py)
        self.late_result: dict[str, Any] | None = None
        self._future: asyncio.Future[dict[str, Any]] = asyncio.get_running_loop().create_future()

    @property
    def done(self) -> bool:
        return self._future.done()

    @property
    def outcome(self) -> str:
        """How the goal stands, in words: ``running``, ``canceling``, ``succeeded``, ``canceled``,
        ``aborted``, ``timed out``, ``no answer (rejected?)`` (nothing came back: ``goals.py``),
        ``rejected``, ``failed`` (could not be run) or ``unknown (link lost)``: a goal whose link dropped
        never reads as a success."""
        if not self._future.done():
            return "canceling" if self.cancel_requested else "running"
        if self._future.cancelled():
            return "failed"
        error = self._future.exception()
        if error is None:
            if self.status is not None:
                try:
                    return GoalStatus(self.status).word
                except ValueError:
                    pass
            return f"ended with status {self.status}"
        from .errors import ActionError, ActionNoAnswerError, ActionTimeoutError, ConnectionLostError

        if isinstance(error, ConnectionLostError):
            return "unknown (link lost)"
        if isinstance(error, ActionNoAnswerError):
            if self.status is not None:  # answered after all
                try:
                    return GoalStatus(self.status).word
                except ValueError:
                    return f"ended with status {self.status}"
            return "no answer (rejected?)"
        if isinstance(error, ActionTimeoutError):
            return "timed out"
        if isinstance(error, ActionError) and "rejected" in error.message.lower():
            return "rejected"  # rosbridge 2.5.0 and later say so (#1139)
        return "failed"

    @property
    def succeeded(self) -> bool:
        """True once the goal ended with ``GoalStatus.SUCCEEDED``."""
        return self._future.done() and self.status == GoalStatus.SUCCEEDED

    async def result(self, timeout: float | None = None) -> dict[str, Any]:
        """The result ``values`` once the goal ended (see the class docstring for what raises)."""
        if timeout is None:
            return await asyncio.shield(self._future)
        return await asyncio.wait_for(asyncio.shield(self._future), timeout)

    @property
    def values(self) -> dict[str, Any] | None:
        """The result message of a goal that ended with one, else None (for the operator tap)."""
        f = self._future
        if f.done() and not f.cancelled() and f.exception() is None:
            return f.result()
        return None

    def cancel(self) -> None:
        """Ask the server to cancel the goal (the result arrives as usual, with status CANCELED).  Raises
        ``ViewOnlyError`` when the link was marked view-only since the goal was sent (``guard.py``)."""
        if not self._future.done():
            self.node.session.guard.check(f"cancelling the goal to {self.action}")
            self.cancel_requested = True
            tap = self.node.session.tap
            if tap.listeners:
                tap.emit("cancel", self.node.id, self.action, self.action_type, {"goal_id": self.id})
            self.node.session.goals.cancel(self)

    def add_done_callback(self, fn: Callable[[ActionGoal], None]) -> None:
        """Call ``fn(goal)`` once the goal ended, however it ended."""
        self._future.add_done_callback(lambda _f: fn(self))

    def settle(self, result: dict[str, Any] | None = None, error: BaseException | None = None) -> bool:
        """Finish the goal once (the session calls this when the answer, an error or the timeout comes);
        False when it was already finished."""
        if self._future.done():
            return False
        if error is not None:
            self._future.set_exception(error)
            self._future.exception()  # retrieved: a caller that never awaits gets no "never retrieved" noise
        else:
            self._future.set_result({} if result is None else result)
        return True

    def __repr__(self) -> str:
        return f"<ActionGoal {self.id} status={self.status} done={self.done}>"


class Node:
    """A consumer of the bridge.  Create with ``client.node(label)``."""

    def __init__(self, client: NodeClient, node_id: str) -> None:
        self.client = client
        self.session = client.session
        self.id = node_id
        #: what the node owns; each item removes itself when it ends
        self.subscriptions: set[Subscription] = set()
        self.publishers: set[Publisher] = set()
        self.services: set[ServiceServer] = set()
        self.goals: set[ActionGoal] = set()
        self.action_servers: set[Any] = set()  # provided actions (action_server.ActionServer)
        self.closed = False

    def __repr__(self) -> str:
        return f"<Node {self.id}>"

    def _check(self) -> None:
        if self.closed:
            raise BridgeError(f"node {self.id} is closed")

    def subscribe(self, topic: str, callback: MessageCallback, type: str | None = None, throttle_rate: int = 0,
                  queue_length: int = 0, compression: str = "none",
                  fragment_size: int | None = None, raw: bool = False) -> Subscription:
        """Receive ``topic``'s messages as dicts in ``callback`` (called on the loop thread; keep it quick).

        ``compression="cbor"`` on a type with fixed-size arrays is switched to ``"cbor-raw"`` because
        rosbridge's cbor encoder sends nothing for those types (Imu, Odometry, NavSatFix, ...).

        ``raw=True`` (the flight recorder) asks for ``cbor-raw`` and gets each payload undecoded, as a
        ``topics.RawPayload`` (type, server time, bytes), while the topic arrives that way; when it does
        not (the server could not prepare it, or another consumer's ``cbor`` won the merge) the callback
        gets the decoded dict as everyone else does.
        """
        self._check()
        if raw:
            compression = "cbor-raw"
        if not isinstance(topic, str) or not topic:
            raise ValueError(f"topic must be a non-empty string, got {topic!r}")
        if not callable(callback):
            raise TypeError("callback must be callable")
        if compression not in COMPRESSIONS:
            raise ValueError(f"compression must be one of {', '.join(COMPRESSIONS)}; got {compression!r}")
        for name, value in (("throttle_rate", throttle_rate), ("queue_length", queue_length)):
            if isinstance(value, bool) or not isinstance(value, int) or value < 0:
                raise ValueError(f"{name} must be a non-negative integer, got {value!r}")
        if fragment_size is not None and (not isinstance(fragment_size, int) or fragment_size <= 0):
            raise ValueError(f"fragment_size must be a positive integer, got {fragment_size!r}")
        sub = Subscription(self, topic, callback, type, throttle_rate, queue_length, compression, fragment_size,
                           bool(raw))
        self.subscriptions.add(sub)
        self.session.add_subscription(sub)
        return sub

    def advertise(self, topic: str, type: str, latch: bool = False, queue_size: int = 100,
                  max_age: Any = AUTO) -> Publisher:
        """Advertise ``topic``.  ``max_age``: the freshness limit of each publish in seconds; by default
        0.25 s for a non-latched topic (a command) and None (no limit) for a latched one."""
        self._check()
        if not isinstance(topic, str) or not topic:
            raise ValueError(f"topic must be a non-empty string, got {topic!r}")
        if not isinstance(type, str) or "/" not in type:
            raise ValueError(f"type must be a message type name like 'std_msgs/String', got {type!r}")
        pub = Publisher(self, topic, type, bool(latch), int(queue_size), resolve_max_age(max_age, bool(latch)))
        self.session.add_publisher(pub)  # may raise on a type conflict
        self.publishers.add(pub)
        return pub

    async def call_service(self, name: str, args: dict[str, Any] | list | None = None,
                           timeout: float | None = None) -> dict[str, Any]:
        self._check()
        tap = self.session.tap
        if not tap.listeners:
            return await self.client.call_service(name, args, timeout=timeout)
        tap.emit("call", self.id, name, "", args)
        try:
            values = await self.client.call_service(name, args, timeout=timeout)
        except Exception as exc:
            tap.emit("response", self.id, name, "", None, f"error: {exc}")
            raise
        tap.emit("response", self.id, name, "", values, "ok")
        return values

    def advertise_service(self, name: str, type: str, handler: ServiceHandler) -> ServiceServer:
        self._check()
        if not callable(handler):
            raise TypeError("handler must be callable")
        srv = ServiceServer(self, name, type, handler)
        self.session.services.add(srv)
        self.services.add(srv)
        return srv

    def send_action_goal(self, action: str, action_type: str, args: dict[str, Any] | list | None = None,
                         feedback: MessageCallback | None = None, *, timeout: float | None = None,
                         check: bool = True, answer_timeout: float | None = 5.0) -> ActionGoal:
        """Send a ROS 2 action goal; ``feedback(values)`` gets each ``action_feedback``.

        ``answer_timeout``: a goal that hears nothing (no feedback, no result) for that long ends with
        ``ActionNoAnswerError``, "no answer from the action server (rejected?)" -- rosbridge 2.1.0 answers a
        rejected goal with silence (``goals.py``); None waits for ever.
        ``timeout``: client-side budget for the result in seconds (None: no limit); when it runs out the
        goal is cancelled on the server and fails with ``ActionTimeoutError``.  ``check``: also ask
        ``/rosapi/action_servers`` (within ``call_timeout``) and fail the goal at once with a clear
        ``ActionError`` when the action is not listed or the server has no ROS 2 actions at all (a
        ROS 1 rosbridge ignores ``send_action_goal`` without a word).
        """
        self._check()
        if not isinstance(action, str) or not action:
            raise ValueError(f"action must be a non-empty string, got {action!r}")
        if not isinstance(action_type, str) or "/" not in action_type:
            raise ValueError(f"action_type must be a type name like 'pkg/action/Type', got {action_type!r}")
        if args is not None and not isinstance(args, dict | list):
            raise TypeError(f"args must be a dict or list, got {type(args).__name__}")
        if feedback is not None and not callable(feedback):
            raise TypeError("feedback must be callable")
        if timeout is not None and (isinstance(timeout, bool) or not isinstance(timeout, int | float)
                                    or not timeout > 0):
            raise ValueError(f"timeout must be a positive number of seconds, got {timeout!r}")
        if answer_timeout is not None and (isinstance(answer_timeout, bool) or not isinstance(answer_timeout, int | float)
                                           or not answer_timeout > 0):
            raise ValueError(f"answer_timeout must be a positive number of seconds, got {answer_timeout!r}")
        tap = self.session.tap
        try:
            self.session.guard.check(f"the goal to {action}")  # ViewOnlyError on a view-only link
        except Exception as exc:
            if tap.listeners:
                tap.emit("goal", self.id, action, action_type, args, f"refused: {exc}")
            raise
        if tap.listeners:
            feedback = _tapped_feedback(tap, self.id, action, action_type, feedback)
        goal = self.session.goals.send(self, action, action_type, args, feedback, timeout, check, answer_timeout)
        self.goals.add(goal)
        goal.add_done_callback(self.goals.discard)
        if tap.listeners:
            tap.emit("goal", self.id, action, action_type, args, goal.id)
            goal.add_done_callback(lambda g: tap.emit("result", self.id, action, action_type, g.values, g.outcome))
        return goal

    def advertise_action(self, action: str, type: str, handler: Callable[[Any], Any]) -> Any:
        """Provide the ROS 2 action ``action`` (``advertise_action``); ``handler(goal)`` runs each goal other
        parties send and returns the result message.  Returns an ``action_server.ActionServer``; see that
        module for feedback, cancel and failure handling."""
        self._check()
        srv = self.session.provided_actions.create(self, action, type, handler)
        self.action_servers.add(srv)
        return srv

    def close(self) -> None:
        """End every subscription, advertisement, service, provided action and goal of this node."""
        if self.closed:
            return
        for s in list(self.subscriptions):
            s.unsubscribe()
        for p in list(self.publishers):
            p.unadvertise()
        for srv in list(self.services):
            srv.unadvertise()
        for action in list(self.action_servers):
            action.unadvertise()
        for g in list(self.goals):
            try:
                g.cancel()
            except ViewOnlyError:  # a view-only link sends no cancel either (guard.py)
                pass
        self.closed = True
        self.session.node_closed(self)


def _tapped_feedback(tap: Any, node_id: str, action: str, action_type: str,
                     feedback: MessageCallback | None) -> MessageCallback | None:
    """The goal's feedback callback, telling the operator tap first (``tap.py``)."""
    if feedback is None:
        return None

    def told(values: dict[str, Any]) -> None:
        tap.emit("feedback", node_id, action, action_type, values)
        feedback(values)

    return told
