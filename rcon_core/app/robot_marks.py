"""Which robot a widget belongs to, shown on its frame when its canvas mixes robots.

On a canvas whose widgets talk to more than one robot, each frame gets its robot's colour as its edge
and the robot's name before its title ("Bravo · Front camera"). A canvas of one robot (every one-robot
layout) shows no mark, as before. A widget that shows every robot has none either. The marks are
recomputed after every change of the workspace and whenever the widgets' models are built or replaced.
"""

from __future__ import annotations

from typing import Any

from rcon_core.canvas.robots import mixes_robots, robot_colour, robot_label

__all__ = ["apply_marks", "marks_for"]


def marks_for(workspace: Any) -> dict[str, tuple[str, str]]:
    """widget id -> (robot name, colour) for the widgets of canvases that mix robots."""
    robots = workspace.robots
    out: dict[str, tuple[str, str]] = {}
    for canvas in workspace.canvases:
        if not mixes_robots(robots, [w.binding for w in canvas.widgets]):
            continue
        for w in canvas.widgets:
            out[w.id] = (robot_label(robots, w.binding.robot), robot_colour(robots, w.binding.robot))
    return out


def _frame_style(colour: str) -> str:
    return (f"QFrame#widgetFrame {{ border: 4px solid {colour}; }}"
            f" QLabel#frameTitle {{ border-left: 12px solid {colour}; }}")


def apply_marks(host: Any, workspace: Any) -> None:
    """Give every hosted frame its robot mark (or take it away), title and edge. A widget whose model
    shows every robot (``model.shows_every_robot``: the map of every robot's fix) gets none: its binding
    names one robot, but what it shows is the fleet's."""
    marks = marks_for(workspace)
    for widget_id, hosted in host.hosted.items():
        try:
            every = bool(hosted.model is not None and hosted.model.shows_every_robot)
        except Exception:  # noqa: BLE001 - a widget that cannot say keeps its mark; the others go on
            every = False
        if every:
            marks.pop(widget_id, None)
    host.robot_marks = marks
    for widget_id, hosted in host.hosted.items():
        mark = marks.get(widget_id)
        frame = hosted.frame
        key = "|".join(mark) if mark else ""
        if (frame.property("robotMark") or "") == key:
            continue  # already shown (a frame built since has none yet)
        frame.setProperty("robotMark", key)
        frame.set_title(host.title_of(hosted.widget))
        frame.setStyleSheet(_frame_style(mark[1]) if mark else "")
