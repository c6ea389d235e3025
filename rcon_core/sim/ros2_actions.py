"""ROS 2 actions in the sim: every ``*_action*`` op of rosbridge 2.x (rosbridge_suite 2.1.0) and its servers.

Action servers are the sim's own (``/navigate_to_fix`` on the robot, ``/fibonacci`` as in the ROS 2
tutorials) and those a client provides with ``advertise_action``.  The frames, as the ros2 branch's
capabilities send them:

* A caller's ``send_action_goal`` (``action``, ``action_type`` required; ``id``, ``args``, ``feedback``
  optional; an id may also ride on the action name as ``/name#id``) gets ``action_feedback``
  (``op, action, values[, id]``) only when it asked ``feedback: true``, then one ``action_result``
  (``op, action, values, status, result: true[, id]``) whatever way the goal ended: ``status`` is the
  action_msgs GoalStatus (4 succeeded, 5 canceled, 6 aborted) and ``values`` the whole result message.
* A goal that cannot be sent gets ``action_result`` with ``result: false``, ``status`` 0 and the error
  *text* in ``values``.
* ``cancel_action_goal`` (``id``, ``action``) cancels the caller's goal with that id.
* A client's ``advertise_action`` (``action``, ``type``) makes it the server: each goal reaches it as
  ``send_action_goal`` with the server's own id ``action_goal:<action>:<n>`` (n counts from 1 per
  advertisement), the goal message with defaults filled in and always ``feedback: true``; a cancel reaches
  it as ``cancel_action_goal`` with that id.  Its ``action_feedback`` and ``action_result`` (``id``,
  ``action``, ``values``, ``status``, ``result``) go back to the caller under the caller's id.  Its
  ``result: false`` aborts the goal: the caller gets status 6 and the result type's default message.
  Advertising a name again replaces the old server; ``unadvertise_action`` (or the advertiser's
  disconnect) aborts its goals in flight the same way.

Where the sim differs on purpose (see docs/architecture.md): a goal to an action nobody serves is answered
after the 1 s that rosbridge waits for the server with ``result: false`` and "No action server available"
(rosbridge 2.1.0 sends the goal anyway and never answers); a goal whose ``action_type`` is not the type
the server serves fails at once (ROS would never match them); goals run concurrently, as with the
server's ``send_action_goals_in_new_thread: true`` (by default 2.1.0 handles one client's goals, and
every later op of that client, one after the other); a caller's disconnect cancels its goals.
"""

from __future__ import annotations

import asyncio
import contextlib
import itertools
import logging
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from .ops import OpError, send_frame
from .ops import field as op_field

if TYPE_CHECKING:
    from .connection import Connection
    from .server import SimServer

log = logging.getLogger("rcon.sim")

STATUS_UNKNOWN, STATUS_SUCCEEDED, STATUS_CANCELED, STATUS_ABORTED = 0, 4, 5, 6
SERVER_WAIT_S = 1.0  # how long rosbridge's SendGoal waits for the action server
FIBONACCI_NAME = "/fibonacci"
FIBONACCI_TYPE = "action_tutorials_interfaces/action/Fibonacci"


def action_name(type_name: str) -> str:
    """``pkg/X`` or ``pkg/action/X`` -> ``pkg/action/X``."""
    parts = type_name.strip("/").split("/")
    if len(parts) == 2:
        return f"{parts[0]}/action/{parts[1]}"
    return type_name.strip("/")


@dataclass(eq=False)
class Goal:
    """A goal some caller sent, while it runs."""

    caller: Connection
    caller_id: Any  # None: the caller gave no id (frames then carry none)
    action: str  # the name as the caller spelled it (the frames repeat it)
    feedback: bool
    provider: Any
    server_id: str = ""  # for client-provided actions: the id the advertiser knows the goal by
    status: int = 0
    cancel_requested: bool = False
    task: asyncio.Task[None] | None = None
    extra: dict[str, Any] = field(default_factory=dict)


class ActionHub:
    """Routes the action ops between callers and action servers."""

    def __init__(self, server: SimServer) -> None:
        self.server = server
        self.providers: dict[str, Any] = {}
        self.goals: list[Goal] = []

    # -- bookkeeping ----------------------------------------------------------------------------------

    def add(self, provider: Any) -> None:
        self.providers[provider.name] = provider

    def names(self) -> list[str]:
        return sorted(self.providers)

    def ops(self) -> dict[str, Any]:
        return {"send_action_goal": self.op_send_goal, "cancel_action_goal": self.op_cancel_goal,
                "advertise_action": self.op_advertise, "unadvertise_action": self.op_unadvertise,
                "action_feedback": self.op_feedback, "action_result": self.op_result}

    async def stop(self) -> None:
        for provider in list(self.providers.values()):
            stop = getattr(provider, "stop", None)
            if stop is not None:
                await stop()
        for goal in list(self.goals):
            if goal.task is not None:
                goal.task.cancel()
                with contextlib.suppress(asyncio.CancelledError, Exception):
                    await goal.task

    def connection_closed(self, conn: Connection) -> None:
        """The advertiser's actions end (their goals abort); the caller's goals are cancelled."""
        for name, provider in list(self.providers.items()):
            if getattr(provider, "conn", None) is conn:
                del self.providers[name]
                provider.shutdown("the advertising client disconnected")
        for goal in [g for g in self.goals if g.caller is conn]:
            goal.cancel_requested = True
            goal.provider.cancel(goal)

    # -- frames to callers ----------------------------------------------------------------------------

    def _frame(self, goal: Goal, frame: dict[str, Any]) -> None:
        if goal.caller_id is not None:
            frame["id"] = goal.caller_id
        send_frame(goal.caller, frame)

    def send_feedback(self, goal: Goal, values: Any) -> None:
        if goal.feedback and goal in self.goals:
            self._frame(goal, {"op": "action_feedback", "action": goal.action, "values": values})

    def finish(self, goal: Goal, status: int, values: Any) -> None:
        """End ``goal`` with a terminal status: ``action_result`` with ``result: true``."""
        if goal not in self.goals:
            return
        self.goals.remove(goal)
        goal.status = status
        self._frame(goal, {"op": "action_result", "action": goal.action, "values": values, "status": status,
                           "result": True})

    def fail(self, conn: Connection, cid: Any, action: str, text: str) -> None:
        """A goal that could not be sent: ``result: false``, status 0, the error as a string."""
        log.error("[Client %s] send_action_goal %s: %s", conn.id, cid, text)
        frame: dict[str, Any] = {"op": "action_result", "action": action, "values": text,
                                 "status": STATUS_UNKNOWN, "result": False}
        if cid is not None:
            frame["id"] = cid
        send_frame(conn, frame)

    # -- caller ops -----------------------------------------------------------------------------------

    def op_send_goal(self, conn: Connection, msg: dict[str, Any]) -> None:
        action = op_field(msg, "action", str)
        action_type = op_field(msg, "action_type", str)
        cid = msg.get("id")
        name = action
        if "#" in action:
            name, tail = action.split("#", 1)
            if cid is None:
                cid = tail
        canonical = action_name(action_type)
        if not self.server.types.has(f"{canonical}_Goal"):
            self.fail(conn, cid, action, f"Unable to load the action type {action_type}")
            return
        provider = self.providers.get(name)
        if provider is None:
            asyncio.get_running_loop().call_later(SERVER_WAIT_S, self.fail, conn, cid, action,
                                                  "No action server available")
            return
        if action_name(provider.type) != canonical:
            self.fail(conn, cid, action, f"{name} serves {provider.type}, not {action_type}")
            return
        if hasattr(provider, "op_send_goal"):  # the robot's own server speaks the frames itself
            provider.op_send_goal(conn, msg)
            return
        args = msg.get("args")
        goal_args = self._goal_args(canonical, args)
        if isinstance(goal_args, str):
            self.fail(conn, cid, action, goal_args)
            return
        goal = Goal(conn, cid, action, bool(msg.get("feedback", False)), provider)
        self.goals.append(goal)
        provider.start(goal, goal_args)

    def _goal_args(self, canonical: str, args: Any) -> dict[str, Any] | str:
        """The goal message from ``args`` (a dict, or a list in field order), defaults filled in; or the
        reason it cannot be made."""
        from .convert import ConversionError

        converter = self.server.types.converter(f"{canonical}_Goal")
        if converter is None:
            return args if isinstance(args, dict) else {}
        if isinstance(args, list):
            td = converter.defs[converter.root]
            args = dict(zip(td["fieldnames"], args, strict=False))
        elif not isinstance(args, dict):
            args = {}
        try:
            return converter.convert(args)
        except ConversionError as exc:
            return str(exc)

    def default_result(self, type_name: str) -> dict[str, Any]:
        converter = self.server.types.converter(f"{action_name(type_name)}_Result")
        return converter.default() if converter is not None else {}

    def op_cancel_goal(self, conn: Connection, msg: dict[str, Any]) -> None:
        action = op_field(msg, "action", str)
        cid = msg.get("id")
        name = action
        if "#" in action:
            name, tail = action.split("#", 1)
            cid = tail if cid is None else cid
        provider = self.providers.get(name)
        if provider is None:  # no such action: no goal of it to cancel
            return
        if hasattr(provider, "op_cancel_goal"):
            provider.op_cancel_goal(conn, msg)
            return
        for goal in self.goals:
            if goal.caller is conn and goal.caller_id == cid and goal.provider is provider:
                if not goal.cancel_requested:
                    goal.cancel_requested = True
                    goal.provider.cancel(goal)
                return

    # -- advertiser ops -------------------------------------------------------------------------------

    def op_advertise(self, conn: Connection, msg: dict[str, Any]) -> None:
        name = op_field(msg, "action", str)
        type_name = op_field(msg, "type", str)
        if not self.server.types.has(f"{action_name(type_name)}_Goal"):
            raise OpError(f"Unable to load the action type {type_name}")
        old = self.providers.get(name)
        if old is not None:
            if not isinstance(old, ClientAction):
                raise OpError(f"Action {name} is already provided by the robot")
            log.warning("[Client %s] Duplicate action advertised. Overwriting %s.", conn.id, name)
            old.shutdown("the action was advertised again")
        self.providers[name] = ClientAction(self, conn, name, type_name)
        log.info("[Client %s] Advertised action %s", conn.id, name)

    def op_unadvertise(self, conn: Connection, msg: dict[str, Any]) -> None:
        name = op_field(msg, "action", str)
        provider = self.providers.get(name)
        if not isinstance(provider, ClientAction) or provider.conn is not conn:
            raise OpError(f"Action {name} has not been advertised via rosbridge, can't unadvertise.")
        del self.providers[name]
        provider.shutdown("the action was unadvertised")
        log.info("[Client %s] Unadvertised action %s", conn.id, name)

    def _advertised(self, conn: Connection, msg: dict[str, Any]) -> tuple[ClientAction, Goal]:
        name = op_field(msg, "action", str)
        provider = self.providers.get(name)
        if not isinstance(provider, ClientAction) or provider.conn is not conn:
            raise OpError(f"Action {name} has not been advertised via rosbridge.")
        goal = provider.goals.get(msg.get("id"))  # type: ignore[arg-type]
        if goal is None:
            raise OpError(f"no goal in flight with id {msg.get('id')!r} on {name}")
        return provider, goal

    def _typed(self, provider: ClientAction, part: str, values: Any) -> Any:
        """The advertiser's values as a whole ``part`` message (defaults filled in), as rosbridge fills a
        ROS message from them; refused with the reason when they do not fit."""
        from .convert import ConversionError
        converter = self.server.types.converter(f"{action_name(provider.type)}_{part}")
        if converter is None:
            return values
        if not isinstance(values, dict):
            raise OpError(f"Expected field values to be one of (<class 'dict'>,). Invalid value: {values}")
        try:
            return converter.convert(values)
        except ConversionError as exc:
            raise OpError(str(exc)) from exc

    def op_feedback(self, conn: Connection, msg: dict[str, Any]) -> None:
        provider, goal = self._advertised(conn, msg)
        self.send_feedback(goal, self._typed(provider, "Feedback", msg.get("values", {})))

    def op_result(self, conn: Connection, msg: dict[str, Any]) -> None:
        op_field(msg, "status", int)
        result = msg.get("result")
        if not isinstance(result, bool):
            raise OpError(f"Expected field result to be one of (<class 'bool'>,). Invalid value: {result}")
        provider, goal = self._advertised(conn, msg)
        if not result:
            del provider.goals[goal.server_id]
            self.finish(goal, STATUS_ABORTED, self.default_result(provider.type))
            return
        values = self._typed(provider, "Result", msg.get("values", {}))  # a bad result leaves the goal open
        del provider.goals[goal.server_id]
        status = msg["status"] if msg["status"] in (STATUS_SUCCEEDED, STATUS_CANCELED) else STATUS_ABORTED
        self.finish(goal, status, values)


class ClientAction:
    """An action a client advertised: goals are forwarded to it and its answers back to the callers."""

    def __init__(self, hub: ActionHub, conn: Connection, name: str, type_name: str) -> None:
        self.hub = hub
        self.conn = conn
        self.name = name
        self.type = type_name
        self.goals: dict[str, Goal] = {}
        self._ids = itertools.count(1)

    def start(self, goal: Goal, args: dict[str, Any]) -> None:
        goal.server_id = f"action_goal:{self.name}:{next(self._ids)}"
        self.goals[goal.server_id] = goal
        send_frame(self.conn, {"op": "send_action_goal", "id": goal.server_id, "action": self.name,
                               "action_type": self.type, "args": args, "feedback": True})

    def cancel(self, goal: Goal) -> None:
        if goal.server_id in self.goals:
            log.warning("Canceling action %s", goal.server_id)
            send_frame(self.conn, {"op": "cancel_action_goal", "id": goal.server_id, "action": self.name})

    def shutdown(self, reason: str) -> None:
        if self.goals:
            log.warning("Action %s ended (%s) with goals in flight, aborting %s", self.name, reason,
                        ", ".join(self.goals))
        default = self.hub.default_result(self.type)
        for goal in list(self.goals.values()):
            self.hub.finish(goal, STATUS_ABORTED, dict(default))
        self.goals.clear()


class FibonacciServer:
    """``/fibonacci`` (``action_tutorials_interfaces/action/Fibonacci``), as the ROS 2 tutorial serves it:
    feedback ``partial_sequence`` grows by one number every 0.5 s (scaled by rate_scale), starting from
    ``[0, 1]``; a cancel ends the goal with status 5 and an empty sequence."""

    name = FIBONACCI_NAME
    type = FIBONACCI_TYPE

    def __init__(self, hub: ActionHub) -> None:
        self.hub = hub

    def start(self, goal: Goal, args: dict[str, Any]) -> None:
        order = args.get("order", 0)
        goal.task = asyncio.get_running_loop().create_task(self._run(goal, int(order)))

    def cancel(self, goal: Goal) -> None:
        goal.cancel_requested = True  # the loop notices at its next step

    async def _run(self, goal: Goal, order: int) -> None:
        period = 0.5 / self.hub.server.rate_scale
        sequence = [0, 1]
        for i in range(1, order):
            if goal.cancel_requested:
                self.hub.finish(goal, STATUS_CANCELED, {"sequence": []})
                return
            sequence.append(sequence[i] + sequence[i - 1])
            self.hub.send_feedback(goal, {"partial_sequence": list(sequence)})
            await asyncio.sleep(period)
        if goal.cancel_requested:
            self.hub.finish(goal, STATUS_CANCELED, {"sequence": []})
            return
        self.hub.finish(goal, STATUS_SUCCEEDED, {"sequence": sequence})
