"""ROS 2 actions this client provides (``advertise_action``), over rosbridge 2.x.

``node.advertise_action(name, type, handler)`` sends ``advertise_action``; the server then forwards every
goal another party sends to that action as a ``send_action_goal`` frame with the server's own id
(``action_goal:<name>:<n>``) and the goal message in ``args``.  For each goal the client calls
``handler(goal)`` (a :class:`ServedGoal`); the handler may publish feedback while it runs and returns the
result message (a dict, or an awaitable giving one):

* it returns: ``action_result`` with ``result: true`` and ``goal.status`` (SUCCEEDED unless the handler
  set ``goal.status`` to CANCELED or ABORTED first);
* it raises, or returns something other than a dict: the error is logged, ``failures`` counted, and the
  goal answered with ``result: false``, which the server turns into an aborted goal for the caller.

A ``cancel_action_goal`` from the server sets ``goal.cancel_requested``, sets the ``goal.cancelled``
event and calls ``goal.on_cancel`` when set; the handler decides how to stop (typically: return with
``goal.status = GoalStatus.CANCELED``).  Advertised actions are sent again after a reconnect; goals in
flight when the link drops are abandoned (their handler tasks are cancelled: the server has already
aborted them for their callers) and their ``status`` becomes UNKNOWN.  All of it runs on the client's loop.
"""

from __future__ import annotations

import asyncio
import inspect
import logging
from collections.abc import Awaitable, Callable
from typing import TYPE_CHECKING, Any

from .errors import BridgeError
from .nodes import GoalStatus

if TYPE_CHECKING:
    from .nodes import Node

log = logging.getLogger(__name__)

GoalHandler = Callable[["ServedGoal"], "dict[str, Any] | Awaitable[dict[str, Any]]"]


class ServedGoal:
    """One goal sent to an action this client provides."""

    def __init__(self, server: ActionServer, goal_id: str, args: dict[str, Any]) -> None:
        self.server = server
        self.id = goal_id
        self.args = args
        self.status: int = GoalStatus.SUCCEEDED
        self.cancel_requested = False
        self.cancelled = asyncio.Event()
        self.on_cancel: Callable[[], None] | None = None
        self.feedback_sent = 0
        self.done = False
        self.task: asyncio.Task[Any] | None = None

    def publish_feedback(self, values: dict[str, Any]) -> bool:
        """Send ``action_feedback`` for this goal; False when the goal ended or the link is down."""
        if self.done:
            return False
        if not isinstance(values, dict):
            raise TypeError(f"feedback must be a dict, got {type(values).__name__}")
        sent = self.server.send_frame({"op": "action_feedback", "id": self.id, "action": self.server.action,
                                  "values": values})
        self.feedback_sent += int(sent)
        return sent

    def request_cancel(self) -> None:
        if self.cancel_requested or self.done:
            return
        self.cancel_requested = True
        self.cancelled.set()
        if self.on_cancel is not None:
            try:
                self.on_cancel()
            except Exception:
                log.exception("on_cancel of goal %s raised", self.id)

    def __repr__(self) -> str:
        return f"<ServedGoal {self.id} status={self.status} done={self.done}>"


class ActionServer:
    """An action this client provides.  ``unadvertise()`` is idempotent."""

    def __init__(self, node: Node, action: str, type: str, handler: GoalHandler,
                 send: Callable[[dict[str, Any]], bool]) -> None:
        self.node = node
        self.action = action
        self.type = type
        self.handler = handler
        self.active = True
        self.goals: dict[str, ServedGoal] = {}
        self.received = 0
        self.failures = 0
        self.send_frame = send

    def advertise_op(self) -> dict[str, Any]:
        return {"op": "advertise_action", "action": self.action, "type": self.type}

    def unadvertise(self) -> None:
        if self.active:
            self.active = False
            self.node.action_servers.discard(self)
            self.node.client.provided_actions.remove(self)

    def abandon(self) -> None:
        """Drop every goal in flight without answering (link lost, unadvertised): status UNKNOWN."""
        for goal in list(self.goals.values()):
            goal.done = True
            goal.status = GoalStatus.UNKNOWN
            if goal.task is not None:
                goal.task.cancel()
        self.goals.clear()

    # -- one goal -------------------------------------------------------------------------------------

    def start_goal(self, goal_id: str, args: Any) -> None:
        goal = ServedGoal(self, goal_id, args if isinstance(args, dict) else {})
        self.goals[goal_id] = goal
        self.received += 1
        try:
            result = self.handler(goal)
        except Exception as exc:
            self._failed(goal, exc)
            return
        if inspect.isawaitable(result):
            goal.task = asyncio.ensure_future(self._finish_later(goal, result))
        else:
            self._answer(goal, result)

    async def _finish_later(self, goal: ServedGoal, pending: Awaitable[Any]) -> None:
        try:
            result = await pending
        except asyncio.CancelledError:
            if goal.done:
                return  # abandoned (link lost or unadvertised)
            self._failed(goal, BridgeError("the goal handler was cancelled"))
            return
        except Exception as exc:
            self._failed(goal, exc)
            return
        self._answer(goal, result)

    def _answer(self, goal: ServedGoal, result: Any) -> None:
        if result is None:
            result = {}
        if not isinstance(result, dict):
            self._failed(goal, TypeError(f"handler returned {type(result).__name__}, expected a dict"))
            return
        status = int(goal.status)
        if status not in (GoalStatus.SUCCEEDED, GoalStatus.CANCELED, GoalStatus.ABORTED):
            log.warning("goal %s ended with status %s, which is not terminal; sending ABORTED", goal.id, status)
            status = GoalStatus.ABORTED
        goal.status = status
        self._result(goal, {"values": result, "status": status, "result": True})

    def _failed(self, goal: ServedGoal, exc: BaseException) -> None:
        self.failures += 1
        log.error("handler of action %s (node %s) failed on goal %s: %s: %s", self.action, self.node.id, goal.id,
                  type(exc).__name__, exc, exc_info=exc)
        goal.status = GoalStatus.ABORTED
        self._result(goal, {"values": {}, "status": GoalStatus.ABORTED, "result": False})

    def _result(self, goal: ServedGoal, body: dict[str, Any]) -> None:
        if goal.done:
            return
        goal.done = True
        self.goals.pop(goal.id, None)
        self.send_frame({"op": "action_result", "id": goal.id, "action": self.action, **body})

    def __repr__(self) -> str:
        return f"<ActionServer {self.action} [{self.type}] node={self.node.id} active={self.active}>"


class ProvidedActions:
    """The client's table of advertised actions; it takes the server's goal and cancel frames."""

    def __init__(self, send: Callable[[dict[str, Any]], bool]) -> None:
        self._send = send
        self.servers: dict[str, ActionServer] = {}

    def create(self, node: Node, action: str, type: str, handler: GoalHandler) -> ActionServer:
        if not isinstance(action, str) or not action:
            raise ValueError(f"action must be a non-empty string, got {action!r}")
        if not isinstance(type, str) or "/" not in type:
            raise ValueError(f"type must be an action type like 'pkg/action/Type', got {type!r}")
        if not callable(handler):
            raise TypeError("handler must be callable")
        other = self.servers.get(action)
        if other is not None:
            raise BridgeError(f"action {action} is already advertised by node {other.node.id}")
        srv = self.servers[action] = ActionServer(node, action, type, handler, self._send)
        self._send(srv.advertise_op())
        return srv

    def remove(self, srv: ActionServer) -> None:
        if self.servers.get(srv.action) is srv:
            del self.servers[srv.action]
            srv.abandon()
            self._send({"op": "unadvertise_action", "action": srv.action})

    def restore(self) -> None:
        """Advertise every action again on a fresh connection."""
        for srv in self.servers.values():
            self._send(srv.advertise_op())

    def disconnected(self) -> None:
        for srv in self.servers.values():
            srv.abandon()

    # -- frames from the server -----------------------------------------------------------------------

    def on_goal(self, m: dict[str, Any]) -> None:
        action, goal_id = m["action"], m["id"]
        if not isinstance(action, str) or not isinstance(goal_id, str):
            raise TypeError("send_action_goal needs string 'action' and 'id'")
        srv = self.servers.get(action)
        if srv is None:
            log.warning("server sent a goal for %s, which this client does not provide; answered as failed", action)
            self._send({"op": "action_result", "id": goal_id, "action": action, "values": {},
                        "status": GoalStatus.ABORTED, "result": False})
            return
        srv.start_goal(goal_id, m.get("args"))

    def on_cancel(self, m: dict[str, Any]) -> None:
        srv = self.servers.get(m["action"])
        goal = srv.goals.get(m.get("id")) if srv is not None else None  # type: ignore[arg-type]
        if goal is None:
            log.debug("cancel_action_goal for an unknown or finished goal %r", m.get("id"))
            return
        goal.request_cancel()
