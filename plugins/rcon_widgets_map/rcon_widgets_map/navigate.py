"""Navigate here": a goal to a ROS 2 action from a point of the map (a long press, then confirm). No Qt.

``MapSettings.navigate_action`` names the action (``/navigate_to_fix``) and ``navigate_type`` its type
(``rcon_sim/action/NavigateToFix``). The goal is the point's latitude and longitude set into the first
message of the goal type that has both (``target`` of NavigateToFix; the goal itself when it has them);
only those two fields are sent, the server fills in the rest. While the goal runs, :class:`Navigation`
holds the distance remaining (the feedback's first number named like ``distance_remaining``); how it
ended is said in words (succeeded, canceled, aborted, failed; *unknown* when the link dropped while it
ran -- never a success). A goal still running when the map stops (its canvas is left) is cancelled.
"""

from __future__ import annotations

import asyncio
import math
from collections.abc import Callable
from typing import Any

import attrs

from rcon_core.plugins import GoalPhase

__all__ = ["Navigation", "Navigator", "geo_goal_path"]

STATUS_PHASE = {4: GoalPhase.SUCCEEDED, 5: GoalPhase.CANCELED, 6: GoalPhase.ABORTED}
REMAINING_WORDS = ("distance_remaining", "remaining", "distance_left", "distance")


@attrs.frozen
class Navigation:
    lat: float
    lon: float
    action: str
    phase: GoalPhase = attrs.field(converter=GoalPhase)  #: active, canceling, then a final one
    text: str = ""
    remaining_m: float | None = None

    @property
    def running(self) -> bool:
        return self.phase.running


def geo_goal_path(types: Any, action_type: str) -> str:
    """Where latitude/longitude go in the goal of ``action_type``: ``"target"``, ``""`` (the goal itself).

    Raises ValueError naming the problem (unknown type, no latitude/longitude anywhere in the goal)."""
    try:
        root = types.action_part_name(action_type, "goal")
    except (KeyError, ValueError, AttributeError) as exc:
        raise ValueError(f"unknown action type {action_type!r}: {exc}") from None

    def find(type_name: str, prefix: str, depth: int) -> str | None:
        fields = types.fields(type_name)
        names = {f.name for f in fields}
        if {"latitude", "longitude"} <= names:
            return prefix
        if depth >= 4:
            return None
        for f in fields:
            if not f.is_builtin and f.array_len is None:
                found = find(f.base, f"{prefix}.{f.name}" if prefix else f.name, depth + 1)
                if found is not None:
                    return found
        return None

    path = find(root, "", 0)
    if path is None:
        raise ValueError(f"the goal of {action_type} has no latitude/longitude to navigate to")
    return path


def _remaining(values: Any) -> float | None:
    if not isinstance(values, dict):
        return None
    for word in REMAINING_WORDS:
        for key, v in values.items():
            if word in str(key).lower() and isinstance(v, int | float) and not isinstance(v, bool) \
                    and math.isfinite(v):
                return float(v)
    return None


class Navigator:
    """Sends and follows one navigation goal for a map model. ``changed()`` is called on every change
    (bridge thread); ``state`` is the current :class:`Navigation` or None."""

    def __init__(self, settings: Any, port: Any, types: Any, dispatch: Callable[[Callable[[], Any]], Any],
                 changed: Callable[[], None], error: Callable[[str], None]) -> None:
        self.settings = settings
        self.port = port
        self.types = types
        self._dispatch = dispatch
        self._changed = changed
        self._error = error
        self._goal: Any = None
        self._tasks: set[asyncio.Task[Any]] = set()
        self.state: Navigation | None = None

    @property
    def action(self) -> str:
        return str(getattr(self.settings, "navigate_action", "") or "").strip()

    @property
    def action_type(self) -> str:
        return str(getattr(self.settings, "navigate_type", "") or "").strip()

    def goal_args(self, lat: float, lon: float) -> dict[str, Any]:
        """The goal sent for a point (ValueError when it cannot be made)."""
        if not (-90.0 <= lat <= 90.0 and -180.0 <= lon <= 180.0):
            raise ValueError(f"({lat}, {lon}) is not a valid latitude/longitude")
        point: dict[str, Any] = {"latitude": float(lat), "longitude": float(lon)}
        path = geo_goal_path(self.types, self.action_type)
        for part in reversed(path.split(".") if path else []):
            point = {part: point}
        return point

    # -- any thread -------------------------------------------------------------------------------
    def start(self, lat: float, lon: float) -> bool:
        """Send a goal to navigate to ``lat``/``lon``; False (and an error) when it cannot be sent."""
        if not self.action:
            self._error("no navigation action set: choose one in the map's settings")
            return False
        try:
            args = self.goal_args(lat, lon)
        except ValueError as exc:
            self._error(f"not sent: {exc}")
            return False
        self._dispatch(lambda: self._send_now(args, lat, lon))
        return True

    def cancel(self) -> None:
        self._dispatch(self._cancel_now)

    # -- bridge thread ----------------------------------------------------------------------------
    def _show(self, nav: Navigation | None) -> None:
        self.state = nav
        self._changed()

    def _send_now(self, args: dict[str, Any], lat: float, lon: float) -> None:
        if self._goal is not None and not self._goal.done:
            self._goal.cancel()
        try:
            handle = self.port.send_action_goal(self.action, self.action_type, args, feedback=self._feedback)
        except Exception as exc:
            self._show(Navigation(lat, lon, self.action, GoalPhase.FAILED, f"not sent: {exc}"))
            return
        self._goal = handle
        self._show(Navigation(lat, lon, self.action, GoalPhase.ACTIVE, "goal sent"))
        task = asyncio.get_running_loop().create_task(self._wait(handle))
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)

    def _cancel_now(self) -> None:
        if self._goal is None or self._goal.done or self.state is None:
            return
        self._goal.cancel()
        self._show(attrs.evolve(self.state, phase=GoalPhase.CANCELING, text="cancel requested"))

    def _feedback(self, values: Any) -> None:
        if self.state is not None and self._goal is not None:
            self._show(attrs.evolve(self.state, remaining_m=_remaining(values)))

    async def _wait(self, handle: Any) -> None:
        from rcon_core.bridge.errors import ConnectionLostError

        try:
            result = await handle.result()
        except ConnectionLostError:
            self._end(handle, GoalPhase.UNKNOWN, "link lost while navigating: the goal's fate is unknown")
            return
        except Exception as exc:
            self._end(handle, GoalPhase.FAILED, str(exc) or type(exc).__name__)
            return
        phase = STATUS_PHASE.get(handle.status, GoalPhase.UNKNOWN)
        message = result.get("message") if isinstance(result, dict) else None
        self._end(handle, phase, message if isinstance(message, str) else "")

    def _end(self, handle: Any, phase: GoalPhase, text: str) -> None:
        if handle is self._goal and self.state is not None:
            self._show(attrs.evolve(self.state, phase=phase, text=text))

    def stop(self) -> None:
        """The map stops: a goal still running is cancelled (said so), tasks end."""
        if self._goal is not None and not self._goal.done:
            self._goal.cancel()
            if self.state is not None:
                self.state = attrs.evolve(self.state, phase=GoalPhase.CANCELED, text="cancelled: the map stopped")
        self._goal = None
        for task in list(self._tasks):
            task.cancel()
