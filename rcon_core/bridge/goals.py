"""ROS 2 action goals this client sends (``node.send_action_goal``): the session's table of goals in flight.

Decisions:

* ``send_action_goal`` always carries ``feedback: true``: feedback is how a running goal shows it was
  accepted (rosbridge acknowledges nothing else), and it reaches the caller only when a feedback callback
  was given.  rosbridge answers a goal that *ran* -- succeeded, cancelled or aborted -- with
  ``result: true`` and the GoalStatus in ``status``: ``goal.result()`` returns the result message and
  ``goal.status`` tells how it ended.
* A goal the action server **rejects** gets no answer at all from rosbridge 2.1.0 -- no feedback, no result
  (``rosbridge-ros2-2.1.0/actions.jsonl:14-15``; a goal to an action nobody serves: ``:16-17``).  So a goal
  that hears nothing within ``answer_timeout`` (5 s by default) ends with :class:`ActionNoAnswerError`, "no
  answer from the action server (rejected?)", instead of reading "running" forever; any feedback or result
  before that is a sign of life and stops the clock.  A result that still comes later is kept
  (``goal.status``, ``goal.late_result``) and ``outcome`` says how the goal really ended.  From 2.5.0 on
  (#1139) rosbridge answers a rejection with ``result: false`` and "Action goal was rejected"; the outcome
  is then ``rejected``.
* ``result: false`` (the goal could not be sent: no action server, bad args; ``values`` is then the error
  string), an error ``status`` naming the goal, or the optional client-side ``timeout`` raise
  ``ActionError`` (the timeout also cancels the goal on the server).
* By default the client also asks ``/rosapi/action_servers`` and fails a goal to an unlisted action within
  ``call_timeout``, because a ROS 1 rosbridge drops ``send_action_goal`` without any answer.
* Goals active when the link drops fail with ``ConnectionLostError`` (their outcome is unknown).

The timers of the goals' client-side timeouts live here, not in the goals.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Awaitable, Callable
from typing import TYPE_CHECKING, Any

from .errors import (
    ActionError,
    ActionNoAnswerError,
    ActionTimeoutError,
    ConnectionLostError,
    NotConnectedError,
    ServiceError,
    ServiceTimeoutError,
)
from .nodes import ActionGoal
from .safety import bounded_repr

if TYPE_CHECKING:
    from .nodes import Node

log = logging.getLogger(__name__)

#: seconds a goal may go without any feedback or result before it reads "no answer (rejected?)"
ANSWER_TIMEOUT = 5.0
NO_ANSWER = "no answer from the action server (rejected?)"


class Goals:
    """Goals in flight: frames out through ``send``, the server's feedback and result frames in."""

    def __init__(self, send: Callable[[dict[str, Any]], bool], spawn: Callable[[Awaitable[Any]], Any],
                 host: Any) -> None:
        self._send = send
        self._spawn = spawn
        self._host = host  # url, rosapi (see session.Host)
        self.active: dict[str, ActionGoal] = {}
        self._timers: dict[str, asyncio.TimerHandle] = {}
        self._silence: dict[str, asyncio.TimerHandle] = {}  # answer_timeout clocks
        self.unanswered: dict[str, ActionGoal] = {}  # ended with "no answer"; a late result is still taken
        self._seq = 0

    def send(self, node: Node, action: str, action_type: str, args: dict[str, Any] | list | None,
             feedback: Callable[[Any], None] | None, timeout: float | None, check: bool,
             answer_timeout: float | None = ANSWER_TIMEOUT) -> ActionGoal:
        self._seq += 1
        goal = ActionGoal(node, action, action_type, f"goal:{action}:{self._seq}", feedback)
        op = {"op": "send_action_goal", "id": goal.id, "action": action, "action_type": action_type,
              "args": {} if args is None else args, "feedback": True}
        if not self._send(op):
            goal.settle(error=NotConnectedError(f"not connected to {self._host.url}"))
            return goal
        self.active[goal.id] = goal
        loop = asyncio.get_running_loop()
        if timeout is not None:
            self._timers[goal.id] = loop.call_later(timeout, self._timed_out, goal, timeout)
        if answer_timeout is not None:
            self._silence[goal.id] = loop.call_later(answer_timeout, self._no_answer, goal, answer_timeout)
        if check:
            self._spawn(self._check_exists(goal))
        return goal

    def cancel(self, goal: ActionGoal) -> None:
        """Ask the server to cancel ``goal`` (the result arrives as usual)."""
        self._send({"op": "cancel_action_goal", "id": goal.id, "action": goal.action})

    def _settle(self, goal: ActionGoal, result: dict[str, Any] | None = None,
                error: BaseException | None = None) -> bool:
        for timers in (self._timers, self._silence):
            timer = timers.pop(goal.id, None)
            if timer is not None:
                timer.cancel()
        return goal.settle(result, error)

    def _heard(self, goal: ActionGoal) -> None:
        """A sign of life: the goal was accepted, so silence no longer means a rejection."""
        timer = self._silence.pop(goal.id, None)
        if timer is not None:
            timer.cancel()

    def _no_answer(self, goal: ActionGoal, after: float) -> None:
        self._silence.pop(goal.id, None)
        if goal.done or self.active.get(goal.id) is not goal:
            return
        del self.active[goal.id]
        self.unanswered[goal.id] = goal
        while len(self.unanswered) > 64:  # bounded: the oldest are forgotten
            self.unanswered.pop(next(iter(self.unanswered)))
        if self._settle(goal, error=ActionNoAnswerError(f"{NO_ANSWER}: nothing came back within {after:g} s",
                                                        goal.action)):
            log.warning("goal %s to %s: %s within %g s", goal.id, goal.action, NO_ANSWER, after)

    def fail(self, goal: ActionGoal, error: ActionError, cancel: bool) -> None:
        if self.active.get(goal.id) is goal:
            del self.active[goal.id]
        if cancel and not goal.done:
            self.cancel(goal)
        if self._settle(goal, error=error):
            log.warning("%s", error)

    def _timed_out(self, goal: ActionGoal, timeout: float) -> None:
        self._timers.pop(goal.id, None)
        self.fail(goal, ActionTimeoutError(f"no result within {timeout:g} s; goal cancelled", goal.action),
                  cancel=True)

    async def _check_exists(self, goal: ActionGoal) -> None:
        """Fail the goal with a clear error when rosapi says the action does not exist (or cannot)."""
        try:
            servers = await self._host.rosapi.action_servers()
        except (ServiceTimeoutError, ConnectionLostError, NotConnectedError) as exc:
            log.debug("could not check that %s exists: %s", goal.action, exc)
            return
        except ServiceError as exc:
            if not goal.done:
                self.fail(goal, ActionError(
                    f"cannot check that the action exists ({exc}); a rosbridge without /rosapi/action_servers "
                    "(ROS 1) has no ROS 2 actions (pass check=False to send anyway)", goal.action), cancel=True)
            return
        if goal.done or goal.action in servers or goal.action.lstrip("/") in (s.lstrip("/") for s in servers):
            return
        listed = ", ".join(servers) if servers else "none"
        self.fail(goal, ActionError(f"action does not exist (action servers: {listed})", goal.action), cancel=True)

    # -- frames from the server -------------------------------------------------------------------

    def on_feedback(self, m: dict[str, Any]) -> None:
        goal = self.active.get(m["id"])
        if goal is None:
            log.debug("action_feedback for unknown goal %r", m.get("id"))
            return
        self._heard(goal)
        if goal.feedback_callback is not None:  # asked for on the wire in any case (see the docstring)
            goal.feedback_count += 1
            goal.last_feedback = m.get("values")
            values = m.get("values")
            try:
                goal.feedback_callback({} if values is None else values)
            except Exception:
                log.exception("feedback callback of %s raised", goal.action)

    def on_result(self, m: dict[str, Any]) -> None:
        goal = self.active.pop(m["id"], None)
        late = self.unanswered.pop(m["id"], None) if goal is None else None
        if late is not None:  # it was accepted after all: say how it really ended
            status = m.get("status")
            late.status = status if isinstance(status, int) and not isinstance(status, bool) else None
            late.late_result = m.get("values") if m.get("result", True) is not False else None
            log.info("goal %s to %s answered after all (status %s)", late.id, late.action, late.status)
            return
        if goal is None or goal.done:
            log.debug("action_result for unknown or finished goal %r", m.get("id"))
            return
        values = m.get("values")
        status = m.get("status")
        goal.status = status if isinstance(status, int) and not isinstance(status, bool) else None
        if m.get("result", True) is False:
            text = values if isinstance(values, str) else bounded_repr(values, 200)
            self._settle(goal, error=ActionError(text or "the server could not run the goal", goal.action,
                                                 goal.status))
        else:
            self._settle(goal, {} if values is None else values)

    def on_error_status(self, sid: str, text: str) -> None:
        """An error ``status`` naming a goal fails it."""
        goal = self.active.get(sid)
        if goal is not None:
            self.fail(goal, ActionError(text, goal.action), cancel=False)

    def disconnected(self) -> None:
        for gid, goal in list(self.active.items()):
            self._settle(goal, error=ConnectionLostError(f"connection lost while goal {gid} was active"))
        self.active.clear()
