"""A robot's view-only mark in the window: on its link, on its widgets, and in the canvas menu.

A robot is view-only when its URL is marked in the app config (*Canvas ▾ → View only: nothing is sent to
“NAME”*) or its own flag is set in the layout (*Robots…*). :func:`reason` words it, naming the robot.

- ``FleetUi.apply_guards`` puts the mark on each robot's link itself (``client.guard``, see
  :mod:`rcon_core.bridge.guard`): everything on that link -- widgets, the Parameters panel, service calls,
  action goals, a plugin's own use of its port -- is refused there with one sentence. Each link asks
  :func:`reason` again for every new client (a new URL may carry another mark), before it connects.
- The widgets' ports carry the same reason (``FleetUi.fleet``), so their controls show disabled with it.
- The menu action (``LockControls``, :mod:`rcon_core.app.lock_controls`) names the robot it acts on: the side panel's robot (the chip picked), never the
  connection bar's by default (on a canvas that mixes robots, "this robot" marked the other one:
  issue 21.10). Ticking it applies the mark to the link at once and saves it after; a save that fails
  (a full or read-only disk) is said on the notice bar and the mark holds for this run (issue 21.1a).
  Unticking it is an edit: the operator PIN while the lock is on.
"""

from __future__ import annotations

from typing import Protocol

from rcon_core.app.config import AppConfig
from rcon_core.app.robot_recordings import recording_reason
from rcon_core.canvas.robots import Robot

__all__ = ["reason", "find_robot", "Replaying"]


class Replaying(Protocol):
    """A recording played as the first robot (``replay_bar.ReplayBar``): its URL and its sentence."""

    url: str
    reason: str


def find_robot(robots: list[Robot], robot_id: str) -> Robot | None:
    """``robot_id`` among ``robots``; no id: the first robot (a one-robot window); else None."""
    for robot in robots:
        if robot.id == robot_id:
            return robot
    return robots[0] if not robot_id and robots else None


def reason(robot: Robot | None, url: str | None, config: AppConfig, replay: Replaying | None = None) -> str | None:
    """Why ``robot`` (at ``url``) may not be commanded, naming it; else None."""
    if robot is None:
        return None
    if robot.recording:  # a recording file played as this robot (robot_recordings.py)
        return recording_reason(robot)
    if replay is not None and url and url == replay.url:  # a recording played as the robot (replay_bar.py)
        return replay.reason
    if url and config.is_view_only(url):
        return f"robot “{robot.label}” at {url} is view-only"
    if robot.view_only:
        return f"robot “{robot.label}”{f' at {url}' if url else ''} is view-only"
    return None
