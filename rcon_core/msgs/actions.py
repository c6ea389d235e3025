"""ROS 1 actionlib wrapper messages generated for an action (``XActionGoal``, ``XActionResult``, ...).

A ROS 1 action server talks over topics ``<ns>/goal``, ``<ns>/cancel``, ``<ns>/status``,
``<ns>/feedback`` and ``<ns>/result``; the goal, result and feedback topics carry these wrappers.
"""

from __future__ import annotations

from . import names
from .fielddefs import FieldDef, MsgDef

__all__ = ["actionlib_wrappers"]


def actionlib_wrappers(action: str) -> list[MsgDef]:
    """The wrapper messages of the action ``pkg/action/X``: ``pkg/msg/XActionGoal`` and friends."""
    pkg, kind, typ = names.split(names.normalize(action))
    if kind != "action":
        raise ValueError(f"not an action: {action!r}")
    header = FieldDef.make("header", "std_msgs/msg/Header", None)
    status = FieldDef.make("status", "actionlib_msgs/msg/GoalStatus", None)
    goal = MsgDef(
        f"{pkg}/msg/{typ}ActionGoal",
        (header, FieldDef.make("goal_id", "actionlib_msgs/msg/GoalID", None),
         FieldDef.make("goal", f"{pkg}/action/{typ}_Goal", None)),
    )
    result = MsgDef(
        f"{pkg}/msg/{typ}ActionResult", (header, status, FieldDef.make("result", f"{pkg}/action/{typ}_Result", None))
    )
    feedback = MsgDef(
        f"{pkg}/msg/{typ}ActionFeedback",
        (header, status, FieldDef.make("feedback", f"{pkg}/action/{typ}_Feedback", None)),
    )
    whole = MsgDef(
        f"{pkg}/msg/{typ}Action",
        (FieldDef.make("action_goal", goal.name, None), FieldDef.make("action_result", result.name, None),
         FieldDef.make("action_feedback", feedback.name, None)),
    )
    return [whole, goal, result, feedback]
