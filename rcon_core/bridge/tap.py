"""The operator tap: what leaves this client for the robot, told to whoever listens (the flight recorder).

Every command a consumer sends goes through a :class:`~rcon_core.bridge.nodes.Node` (widgets, through
their ``GuardedPort``; a lab's widget included) or through ``client.params`` (the parameter panel), so the
tap sits there, below every widget, and not in any widget:

* ``publish``: ``Publisher.publish`` -- the message, and whether it was ``sent`` or ``dropped``
  (link down, freshness limit) or ``refused`` (it raised: a guard on the outgoing path);
* ``call`` and ``response``: ``Node.call_service`` -- the request, then the answer or the error;
* ``goal``, ``feedback``, ``result``, ``cancel``: ``Node.send_action_goal`` and ``ActionGoal.cancel``;
* ``param``: ``Params.set`` -- the name, the value and whether the node took it.

``session.tap`` (one per client) holds the listeners; with none the cost of a send is one truth test.
Listeners are called on the bridge loop thread, right after the send, with one :class:`OperatorEvent`;
they must be quick (the recorder only queues it) and an exception in one is logged, never raised into
the sender: recording must never stop a command.  The event's ``data`` is the very dict that was sent:
listeners must not change it.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from typing import Any, NamedTuple

log = logging.getLogger(__name__)

__all__ = ["OperatorEvent", "OperatorTap", "KINDS"]

KINDS = ("publish", "call", "response", "goal", "feedback", "result", "cancel", "param")


class OperatorEvent(NamedTuple):
    """One thing the operator's side sent (or got back for it)."""

    time_ns: int  #: wall clock (``time.time_ns()``) when it left
    kind: str  #: one of :data:`KINDS`
    node: str  #: the sending node's id: the widget instance id for a widget, else the consumer's label
    name: str  #: the topic, service, action or parameter
    type: str  #: the message, service or action type ("" when not known)
    data: Any  #: the message, request, answer, goal, feedback, result or value
    outcome: str = ""  #: "sent", "dropped", "refused: ...", "ok", "error: ...", a goal's outcome word


class OperatorTap:
    """The listeners of one client's outgoing commands (see the module docstring)."""

    __slots__ = ("listeners", "errors")

    def __init__(self) -> None:
        self.listeners: list[Callable[[OperatorEvent], None]] = []
        self.errors = 0

    def add(self, fn: Callable[[OperatorEvent], None]) -> Callable[[], None]:
        """Listen; returns the function that stops listening."""
        self.listeners.append(fn)

        def remove() -> None:
            if fn in self.listeners:
                self.listeners.remove(fn)

        return remove

    def emit(self, kind: str, node: str, name: str, type: str, data: Any, outcome: str = "") -> None:
        event = OperatorEvent(time.time_ns(), kind, node, name, type or "", data, outcome)
        for fn in list(self.listeners):
            try:
                fn(event)
            except Exception:  # noqa: BLE001 - recording never stops a command
                self.errors += 1
                log.exception("operator tap listener failed on a %s of %s", kind, name)
