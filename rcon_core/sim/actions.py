"""The robot's ROS 2 action: drive to a GPS fix (``send_action_goal`` ... ``action_result``).

``ros2_actions.ActionHub`` routes the goals for ``/navigate_to_fix`` here (after its checks of the action
type and name); the other action servers of the sim live in ``ros2_actions.py``.  Frames follow ROSBRIDGE_PROTOCOL.md and rosbridge_suite's ROS 2 ``send_action_goal`` capability:

* ``action_feedback`` (``id``, ``action``, ``values``) only when the goal asked ``feedback: true`` (the
  spec's default is false); 5 Hz scaled by rate_scale while the vessel steers toward the goal.
* A goal that ran to an end -- succeeded, cancelled or aborted -- gets ``action_result`` with
  ``result: true``, the GoalStatus code in ``status`` (4, 5, 6) and the result message in ``values``.
* A goal that could not be sent at all (unknown action or action type, unusable args) gets
  ``action_result`` with ``result: false``, ``status`` 0 (STATUS_UNKNOWN) and the error *string* in
  ``values``: the real server's failure shape ("No action server available", after the real server's
  1 s wait for the action server, for an unknown action).

A new goal aborts the running one; ``cancel_action_goal`` or the client's disconnect cancels it.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import math
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from rcon_core.msgs.names import pkg_type

from .ops import field, send_frame

if TYPE_CHECKING:
    from .connection import Connection
    from .robot_node import RobotNode
    from .server import SimServer

ACTION_NAME = "/navigate_to_fix"
ACTION_TYPE = "rcon_sim/action/NavigateToFix"
log = logging.getLogger("rcon.sim")
STATUS_UNKNOWN, STATUS_SUCCEEDED, STATUS_CANCELED, STATUS_ABORTED = 0, 4, 5, 6
SERVER_WAIT_S = 1.0  # rosbridge's SendGoal.server_timeout_time


@dataclass
class _Goal:
    conn: Connection
    goal_id: Any
    x: float
    y: float
    tolerance: float
    max_speed: float
    feedback: bool
    task: asyncio.Task[None] | None = None
    status: int = 0


def _finite_number(value: Any) -> float | None:
    """``value`` as a float when it is a finite JSON number (not a bool), else None."""
    if isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value):
        return float(value)
    return None


class NavigateActionServer:
    """Serves ``/navigate_to_fix`` on the sim's robot (``/NAME/navigate_to_fix`` for a named vessel)."""

    def __init__(self, server: SimServer, node: RobotNode) -> None:
        self.server = server
        self.node = node
        self.name = node.ns(ACTION_NAME)
        self.type = ACTION_TYPE
        self.goal: _Goal | None = None

    async def stop(self) -> None:
        if self.goal is not None and self.goal.task is not None:
            self.goal.task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self.goal.task

    def op_send_goal(self, conn: Connection, msg: dict[str, Any]) -> None:
        action = field(msg, "action", str)
        action_type = field(msg, "action_type", str)
        goal_id = msg.get("id")
        if pkg_type(action_type) != pkg_type(ACTION_TYPE):  # either spelling matches
            self._fail(conn, goal_id, action, f"Unable to load the action type {action_type}")
            return
        if action != self.name:  # rosbridge waits 1 s for the server (wait_for_server) before it gives up
            asyncio.get_running_loop().call_later(SERVER_WAIT_S, self._fail, conn, goal_id, action,
                                                  "No action server available")
            return
        args = msg.get("args") or {}
        if isinstance(args, list):
            args = dict(zip(("target",), args, strict=False))
        target = args.get("target") if isinstance(args, dict) else None
        if not isinstance(target, dict):
            self._fail(conn, goal_id, action, "send_action_goal args must be an object with a "
                       "sensor_msgs/NavSatFix 'target'")
            return
        lat, lon = _finite_number(target.get("latitude")), _finite_number(target.get("longitude"))
        if lat is None or lon is None:
            self._fail(conn, goal_id, action, "target latitude and longitude must be numbers")
            return
        x, y = self.node.vessel.local_from_lat_lon(lat, lon)
        tolerance = 2.0
        max_speed = 1.5
        if self.goal is not None and self.goal.task is not None and not self.goal.task.done():
            self._finish(self.goal, STATUS_ABORTED, False, "preempted by a new goal")
        goal = _Goal(conn, goal_id, x, y, max(0.5, tolerance), max(0.1, max_speed), bool(msg.get("feedback", False)))
        self.goal = goal
        goal.task = asyncio.get_running_loop().create_task(self._drive(goal))
        self.server.log(self.node.node, "info", f"Navigating to {lat:.6f}, {lon:.6f} "
                        f"({math.hypot(x - self.node.vessel.x, y - self.node.vessel.y):.1f} m away)",
                        function="navigate_to_fix")

    def _fail(self, conn: Connection, goal_id: Any, action: str, text: str) -> None:
        """The real server's answer to a goal it could not send: ``result: false``, status 0, a string."""
        log.error("%s send_action_goal %s: %s", conn.label, goal_id, text)
        frame: dict[str, Any] = {"op": "action_result", "action": action, "values": text,
                                 "status": STATUS_UNKNOWN, "result": False}
        if goal_id is not None:
            frame["id"] = goal_id
        send_frame(conn, frame)

    def op_cancel_goal(self, conn: Connection, msg: dict[str, Any]) -> None:
        goal = self.goal
        if goal is None or goal.task is None or goal.task.done():
            return
        if msg.get("id") not in (None, goal.goal_id):
            return
        self._finish(goal, STATUS_CANCELED, False, "canceled")

    def _distance(self, goal: _Goal) -> float:
        v = self.node.vessel
        return math.hypot(goal.x - v.x, goal.y - v.y)

    async def _drive(self, goal: _Goal) -> None:
        v = self.node.vessel
        period = 0.2 / self.server.rate_scale
        while goal.conn in self.server.connections:
            dist = self._distance(goal)
            if dist <= goal.tolerance:
                v.command(0.0, 0.0, time.monotonic())
                self._finish(goal, STATUS_SUCCEEDED, True, f"arrived within {dist:.1f} m", cancel=False)
                return
            bearing = math.atan2(goal.y - v.y, goal.x - v.x)
            error = (bearing - v.yaw + math.pi) % (2 * math.pi) - math.pi
            speed = min(goal.max_speed, 0.4 * dist) if abs(error) < 0.7 else 0.2
            v.command(speed, 1.5 * error, time.monotonic())
            if goal.feedback:
                send_frame(goal.conn, {"op": "action_feedback", "id": goal.goal_id, "action": self.name,
                                       "values": {"distance_remaining": dist,
                                                  "current": self.node.fix_message()}})
            await asyncio.sleep(period)
        v.command(0.0, 0.0, time.monotonic())  # the client went away: stop

    def _finish(self, goal: _Goal, status: int, success: bool, message: str, *, cancel: bool = True) -> None:
        if goal.status:
            return
        goal.status = status
        if cancel and goal.task is not None:
            goal.task.cancel()
            self.node.vessel.command(0.0, 0.0, time.monotonic())
        dist = self._distance(goal)
        self._result(goal.conn, goal.goal_id, status, {"success": success, "message": message, "distance": dist})
        level = "info" if success else "warn"
        self.server.log(self.node.node, level, f"navigate_to_fix {message}", function="navigate_to_fix")

    def _result(self, conn: Connection, goal_id: Any, status: int, values: dict[str, Any]) -> None:
        """A goal that ended (any terminal status): ``result: true``, as rosbridge's ``_success`` sends."""
        frame: dict[str, Any] = {"op": "action_result", "id": goal_id, "action": self.name, "values": values,
                                 "status": status, "result": True}
        if goal_id is None:
            del frame["id"]
        send_frame(conn, frame)
