"""A robot's view-only mark in the window: on its link, on its widgets, and in the canvas menu.

A robot is view-only when its URL is marked in the app config (*Canvas ▾ → View only: nothing is sent to
“NAME”*) or its own flag is set in the layout (*Robots…*). :func:`reason` words it, naming the robot.

- :func:`guard_links` puts the mark on each robot's link itself (``client.guard``, see
  :mod:`rcon_core.bridge.guard`): everything on that link -- widgets, the Parameters panel, service calls,
  action goals, a plugin's own use of its port -- is refused there with one sentence. Each link asks
  :func:`reason` again for every new client (a new URL may carry another mark), before it connects.
- The widgets' ports carry the same reason (``FleetUi.fleet``), so their controls show disabled with it.
- The menu action names the robot it acts on: the side panel's robot (the chip picked), never the
  connection bar's by default (on a canvas that mixes robots, "this robot" marked the other one:
  issue 21.10). Ticking it applies the mark to the link at once and saves it after; a save that fails
  (a full or read-only disk) is said on the notice bar and the mark holds for this run (issue 21.1a).
  Unticking it is an edit: the operator PIN while the lock is on.
"""

from __future__ import annotations

from functools import partial
from typing import Any

from rcon_core.app.robot_recordings import recording_reason

__all__ = ["reason", "guard_links", "target", "toggle", "show_action"]


def _robot(fleet_ui: Any, robot_id: str) -> Any:
    robots = fleet_ui.robots
    for robot in robots:
        if robot.id == robot_id:
            return robot
    return robots[0] if not robot_id and robots else None


def reason(fleet_ui: Any, robot_id: str, url: str | None = None) -> str | None:
    """Why ``robot_id`` (at ``url``, default: where it is) may not be commanded, naming it; else None."""
    robot = _robot(fleet_ui, robot_id)
    if robot is None:
        return None
    if robot.recording:  # a recording file played as this robot (robot_recordings.py)
        return recording_reason(robot)
    url = url if url is not None else fleet_ui.robot_url(robot.id)
    replay = getattr(fleet_ui.window, "replay", None)  # a recording played as the robot (replay_bar.py)
    if replay is not None and url and url == replay.url:
        return replay.reason
    if url and fleet_ui.window.config.is_view_only(url):
        return f"robot “{robot.label}” at {url} is view-only"
    if robot.view_only:
        return f"robot “{robot.label}”{f' at {url}' if url else ''} is view-only"
    return None


def guard_links(fleet_ui: Any) -> None:
    """Each robot's link refuses, or stops refusing, to send anything that changes the robot."""
    for robot, link in fleet_ui.links.items():
        link.guard_for = partial(reason, fleet_ui, robot.id)
        link.apply_guard()


def target(window: Any) -> tuple[Any, str]:
    """The robot the menu's view-only action acts on (the side panel's) and its URL ("" when none yet)."""
    fleet_ui = window.fleet_ui
    robot = _robot(fleet_ui, fleet_ui.side_robot)
    return robot, (fleet_ui.robot_url(robot.id) or "") if robot is not None else ""


def show_action(window: Any) -> None:
    """The action's words (naming the robot), tick and state."""
    action = window.canvas_actions["robot_view_only"]
    robot, url = target(window)
    name = robot.label if robot is not None else "this robot"
    action.setText(f"View only: nothing is sent to “{name}”")
    action.setEnabled(bool(url))
    action.setToolTip(f"{name} at {url}: marked in this app's settings, for every canvas" if url
                      else f"{name} has no URL yet: connect it first")
    action.setChecked(bool(url) and window.config.is_view_only(url))


def toggle(window: Any, on: bool) -> None:
    """The menu action: mark (or, with the PIN while locked, unmark) the side panel's robot."""
    robot, url = target(window)
    if robot is None or not url:
        show_action(window)
        return

    def apply(value: bool) -> None:
        window.config.set_view_only(url, value, save=False)
        window.apply_view_only()  # the link first: from here on nothing reaches the robot
        window.config.save_view_only(url)  # a failure is said by the config's listeners
        show_action(window)

    if on:
        apply(True)
    else:
        window.canvas_actions["robot_view_only"].setChecked(True)  # until the PIN (if asked) is right
        window.operator_lock.guard(f"let “{robot.label}” be commanded", lambda: apply(False))
