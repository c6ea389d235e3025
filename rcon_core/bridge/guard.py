"""``LinkGuard``: a robot link marked view-only sends nothing that could change the robot.

Every client has one (``client.guard``, the session's).  ``guard.set_view_only("robot “boat2” at
ws://10.0.0.6:9090 is view-only")`` (from any thread) marks the link; ``set_view_only(None)`` lifts it.
The reason is the end of every refusal's one sentence, so it names the robot.

Decision: enforced in the bridge, below every user of the link
    The app's ports (``rcon_core.canvas.port``) already refuse for a view-only canvas or robot, but the
    robot's mark is a property of the link: the Parameters panel, a service called from the side panel,
    an action goal, ``+ New topic``, Navigate here, a Compound's children and whatever a plugin does with
    its context all end in the same :class:`~rcon_core.bridge.session.Session`, so the rule sits there.
    The public calls refuse at once with :class:`ViewOnlyError` (a ``PermissionError``) carrying the
    sentence: ``publish``, ``call_service`` (except the read-only rosapi queries in
    :data:`READ_ONLY_SERVICES`, which the app needs to list topics and learn types, and a ROS 2 node's
    parameter reads, :data:`READ_ONLY_NODE_SERVICES`, through which the Parameters panel shows them), ``send_action_goal``
    and a goal's ``cancel``.  ``advertise``, ``advertise_service`` and ``advertise_action`` are kept by
    the client but not offered to the robot until the mark is lifted.  Under them, every frame the
    session writes passes :meth:`LinkGuard.admit` (the backstop): a frame of a changing op
    (:data:`CHANGE_OPS`, or any op not listed at all) is dropped and counted in ``guard.refused``.

Decision: what a view-only link still sends
    :data:`READ_OPS` (``auth``, ``subscribe``, ``unsubscribe``, ``set_level``: nothing the robot acts on),
    read-only rosapi calls, and the withdrawals in :data:`WITHDRAW_OPS` of what *this link* offered before
    the mark was set (an ``unadvertise`` of a topic it advertised...).  Marking a live link view-only
    withdraws at once every topic, service and action it offered, so nobody can publish through it or
    call it; lifting the mark offers them again.  A goal sent before the mark stays with the robot: its
    cancel is refused like any other command.

:data:`OUTGOING_OPS` lists every op the bridge writes; ``tests/test_view_only_link.py`` reads the bridge's
source for op names and fails on one missing here, then proves against the sim that a view-only link
writes none of the changing ones.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from typing import Any

from .errors import BridgeError

__all__ = ["LinkGuard", "ViewOnlyError", "READ_ONLY_SERVICES", "read_only_service", "READ_OPS", "WITHDRAW_OPS", "CHANGE_OPS",
           "OUTGOING_OPS"]

log = logging.getLogger(__name__)

#: rosapi services that only read (types, names, the graph, parameters, the time): allowed on a view-only
#: link, because the app and the widgets learn topics and message types through them. ``set_param``,
#: ``delete_param`` and every other service stay refused.
READ_ONLY_SERVICES = frozenset(
    f"/rosapi/{name}" for name in (
        "topics", "topics_for_type", "topics_and_raw_types", "topic_type", "publishers", "subscribers",
        "services", "services_for_type", "service_type", "service_providers", "service_node",
        "service_host", "nodes", "node_details", "action_servers", "action_type", "interfaces",
        "message_details", "service_request_details", "service_response_details", "get_param",
        "has_param", "search_param", "get_param_names", "get_time", "get_ros_version",
    )
)

#: the read-only parameter services every ROS 2 node serves (``rcl_interfaces/srv/*``): how ``client.params``
#: reads a ROS 2 robot's parameters (``params_ros2.py``); ``set_parameters*`` stay refused
READ_ONLY_NODE_SERVICES = ("/list_parameters", "/get_parameters", "/describe_parameters", "/get_parameter_types")


def read_only_service(name: Any) -> bool:
    """True for a service a view-only link may call: a read-only rosapi query or a node's parameter read."""
    return isinstance(name, str) and (name in READ_ONLY_SERVICES or name.endswith(READ_ONLY_NODE_SERVICES))


#: ops that never change the robot
READ_OPS = frozenset({"auth", "subscribe", "unsubscribe", "set_level"})
#: ops that take back what this link offered (allowed only for what it did offer)
WITHDRAW_OPS = frozenset({"unadvertise", "unadvertise_service", "unadvertise_action"})
#: ops that change the robot or offer it something to use (``call_service``: unless read-only)
CHANGE_OPS = frozenset({"publish", "advertise", "call_service", "advertise_service", "service_response",
                        "send_action_goal", "cancel_action_goal", "advertise_action", "action_feedback",
                        "action_result"})
OUTGOING_OPS = READ_OPS | WITHDRAW_OPS | CHANGE_OPS

#: an offering op -> the field naming what is offered; a withdrawal -> the offering op it takes back
_OFFERS = {"advertise": "topic", "advertise_service": "service", "advertise_action": "action"}
_WITHDRAWS = {"unadvertise": "advertise", "unadvertise_service": "advertise_service",
              "unadvertise_action": "advertise_action"}
#: a frame's words in a sentence
_WORDS = {"publish": "publishing on {}", "advertise": "advertising {}", "advertise_service": "serving {}",
          "advertise_action": "serving the action {}", "service_response": "the answer to a call of {}",
          "send_action_goal": "the goal to {}", "cancel_action_goal": "cancelling the goal to {}",
          "action_feedback": "feedback of the action {}", "action_result": "the result of the action {}",
          "call_service": "the call to {}"}
#: refusals logged one by one before only every LOG_EVERY-th is
LOG_FIRST, LOG_EVERY = 10, 1000


class ViewOnlyError(BridgeError, PermissionError):
    """Something was about to be sent to a view-only robot (or through a view-only port); nothing was sent.
    ``str(error)`` is one sentence naming what and why (the robot)."""


def _target(op: dict[str, Any]) -> str:
    name = op.get("topic") or op.get("service") or op.get("action") or ""
    return name if isinstance(name, str) else repr(name)[:80]


def describe_call(name: str, args: Any) -> str:
    """A service call in the operator's words (a parameter write says which parameter)."""
    param = args.get("name") if isinstance(args, dict) else None
    if name == "/rosapi/set_param" and isinstance(param, str):
        return f"setting parameter {param}"
    if name == "/rosapi/delete_param" and isinstance(param, str):
        return f"deleting parameter {param}"
    if name.endswith("/set_parameters") and isinstance(args, dict):  # a ROS 2 node's own (params_ros2.py)
        items = [p for p in args.get("parameters") or [] if isinstance(p, dict) and isinstance(p.get("name"), str)]
        if len(items) == 1:
            value = items[0].get("value")
            verb = "deleting" if isinstance(value, dict) and value.get("type") == 0 else "setting"
            return f"{verb} parameter {name[: -len('/set_parameters')]}:{items[0]['name']}"
    return f"the call to {name}"


class LinkGuard:
    """Whether one link is view-only, and what it offered the robot (see the module docstring)."""

    def __init__(self, url: str = "") -> None:
        self.url = url
        #: why nothing may be sent (the end of each refusal's sentence), or None
        self.reason: str | None = None
        #: frames and calls refused so far
        self.refused = 0
        #: (offering op, name) this link offered the robot on the current connection (loop thread only)
        self.offered: set[tuple[str, str]] = set()
        #: the asyncio loop of the current connection (listeners run there; handed over by the shell, so this
        #: module, which the sans-I/O session uses, imports no asyncio)
        self.loop: Any = None
        self._thread: int | None = None  # the thread that loop runs on
        self._listeners: list[Callable[[bool], None]] = []

    @property
    def view_only(self) -> bool:
        return self.reason is not None

    def __repr__(self) -> str:
        return f"<LinkGuard {self.url} view_only={self.reason!r} refused={self.refused}>"

    # ------------------------------------------------------------------------------------ the mark
    def set_view_only(self, reason: str | None) -> None:
        """Mark the link view-only (``reason``: why, naming the robot) or lift the mark (None); any thread.
        Takes effect for every later op at once; the withdrawal (or the new offer) of topics, services and
        actions runs on the link's loop."""
        if reason is not None and not (isinstance(reason, str) and reason.strip()):
            raise ValueError("a view-only mark needs its reason in words (it ends each refusal's sentence)")
        before = self.reason is not None
        self.reason = reason
        if before != (reason is not None):
            self._notify()

    def add_listener(self, fn: Callable[[bool], None]) -> None:
        """``fn(view_only)`` on the link's loop after the mark changed (the session withdraws or offers)."""
        self._listeners.append(fn)

    def attached(self, loop: Any) -> None:
        """A fresh connection on ``loop`` (the running asyncio loop, called on its thread): nothing is
        offered on it yet."""
        self.loop = loop
        self._thread = threading.get_ident()
        self.offered.clear()

    def _notify(self) -> None:
        loop = self.loop
        if loop is None or loop.is_closed():
            return  # never connected: nothing was offered, the next connection starts under the new mark
        if threading.get_ident() == self._thread and loop.is_running():  # on the loop, inside it
            self._changed()
        else:
            try:
                loop.call_soon_threadsafe(self._changed)
            except RuntimeError:  # the loop closed meanwhile
                pass

    def _changed(self) -> None:
        for fn in list(self._listeners):
            try:
                fn(self.reason is not None)
            except Exception:
                log.exception("view-only listener of %s failed", self.url)

    # ------------------------------------------------------------------------------------ refusing
    def sentence(self, what: str) -> str:
        """One sentence: ``what`` was not sent, and why (the reason names the robot)."""
        what = what[:1].upper() + what[1:]
        return f"{what} was not sent: {self.reason}."

    def refuse(self, what: str) -> ViewOnlyError:
        """Count a refusal and make its error (for the caller to raise)."""
        self.refused += 1
        text = self.sentence(what)
        if self.refused <= LOG_FIRST or self.refused % LOG_EVERY == 0:
            log.info("%s (%d refused so far)", text, self.refused)
        return ViewOnlyError(text)

    def check(self, what: str) -> None:
        """Raise :class:`ViewOnlyError` (counted) when the link is view-only; ``what`` in words."""
        if self.reason is not None:
            raise self.refuse(what)

    def check_call(self, name: str, args: Any = None) -> None:
        """Raise when calling service ``name`` would change a view-only robot (read-only rosapi passes)."""
        if self.reason is not None and not read_only_service(name):
            raise self.refuse(describe_call(name, args))

    def admit(self, op: dict[str, Any]) -> bool:
        """The backstop, for each frame about to be written (loop thread): False (dropped, counted) when a
        view-only link may not send it. Keeps track of what the link offers the robot."""
        kind = op.get("op")
        offer = _OFFERS.get(kind) if isinstance(kind, str) else None
        if offer is not None:
            if self.reason is not None:
                self.refuse(_WORDS[str(kind)].format(_target(op)))
                return False
            self.offered.add((str(kind), _target(op)))
            return True
        taken_back = _WITHDRAWS.get(kind) if isinstance(kind, str) else None
        if taken_back is not None:
            key = (taken_back, _target(op))
            if key in self.offered:
                self.offered.discard(key)
                return True
            return self.reason is None  # a view-only link offered nothing of that name: nothing to send
        if kind in READ_OPS or self.reason is None:
            return True
        if kind == "call_service" and read_only_service(op.get("service")):
            return True
        words = _WORDS.get(kind, "the op {}") if isinstance(kind, str) else "a frame {}"
        self.refuse(words.format(_target(op) or repr(kind)[:40]))
        return False

    def withdrawals(self) -> list[dict[str, Any]]:
        """The frames that take back everything this link offered (sent when the mark is set)."""
        ops = []
        for kind, name in sorted(self.offered):
            if kind == "advertise":
                ops.append({"op": "unadvertise", "id": f"adv:{name}", "topic": name})
            elif kind == "advertise_service":
                ops.append({"op": "unadvertise_service", "service": name})
            else:
                ops.append({"op": "unadvertise_action", "action": name})
        return ops
