"""Robots whose source is a recording file (``Robot.recording``, added with Robots… → Recording file…).

Each such robot gets a player of its own (``sim/playback.py``'s ``played_in_thread``: a bare sim serving
the file, on its own thread), and its link connects to that player's URL for this run only (the URL is
never saved: the port changes at every start; the file's path is what the workspace keeps). Its timeline
(:class:`~rcon_core.app.replay_bar.ReplayBar`, naming the robot) goes under the connection bar. The robot is
view-only: ``view_only.reason`` names the recording, so its link refuses every command
(``bridge/guard.py``) and its control widgets say why; the player absorbs whatever reaches it anyway.

A first robot that is a recording (only a hand-edited file makes one: the dialog adds recordings after the
first) is played as *Canvas ▾ → Replay a recording…* plays one: through the connection bar.

A file that cannot be played (gone, not a recording) is said on the notice bar and on the robot's chip;
the other robots go on. A robot removed, or given another file, stops its player and its bar.
"""

from __future__ import annotations

import contextlib
import logging
from pathlib import Path
from typing import Any

from rcon_core.canvas.robots import Robot

log = logging.getLogger(__name__)

__all__ = ["RobotRecordings", "recording_reason"]


def recording_reason(robot: Robot) -> str | None:
    """Why a recording's robot may not be commanded (None for a live robot)."""
    if not robot.recording:
        return None
    return f"robot “{robot.label}” is a recording ({Path(robot.recording).name}): commands go nowhere"


class RobotRecordings:
    """The players of the workspace's recording robots, by robot id (see the module docstring)."""

    def __init__(self, window: Any) -> None:
        self.window = window
        self._stacks: dict[str, contextlib.ExitStack] = {}
        self._files: dict[str, str] = {}
        self.players: dict[str, Any] = {}
        self.servers: dict[str, Any] = {}
        self.bars: dict[str, Any] = {}

    def sync(self, robots: list[Robot]) -> None:
        """Stop the players of robots that are gone or play another file now."""
        wanted = {r.id: r.recording for r in robots if r.recording}
        for rid in list(self._stacks):
            if wanted.get(rid) != self._files.get(rid):
                self.stop(rid)

    def play(self, robot: Robot, first: bool) -> bool:
        """Play ``robot``'s recording and connect its link to it; False (said) when it cannot be played."""
        from rcon_core.app.replay_bar import ReplayBar, install_replay_bar
        from rcon_core.record.files import RecordingError
        from rcon_core.sim.playback import played_in_thread

        if robot.id in self._stacks and self._files.get(robot.id) == robot.recording:
            return True
        self.stop(robot.id)
        window = self.window
        stack = contextlib.ExitStack()
        try:
            server, player = stack.enter_context(played_in_thread(robot.recording))
        except (RecordingError, OSError, ValueError) as exc:
            stack.close()
            text = f"cannot replay {exc}"
            window.fleet_ui.why[robot.id] = text
            window.notice.show_notice(f"⚠ {robot.label}: {text}")
            log.warning("robot %s: %s", robot.label, text)
            return False
        self._stacks[robot.id] = stack
        self._files[robot.id] = robot.recording
        self.players[robot.id], self.servers[robot.id] = player, server
        if first:
            bar = install_replay_bar(window, server, player)  # the connection bar connects to it
        else:
            bar = ReplayBar(window, server, player)
            bar.words.setText(f"REPLAY · {robot.label} · {Path(robot.recording).name} · commands go nowhere")
            root = window.centralWidget().layout()
            root.insertWidget(root.indexOf(window.connection) + 1, bar)
            window.clock.add(bar.poll)
            window.fleet_ui.links.connect_robot(robot.id, server.url)
            window.apply_view_only()
        self.bars[robot.id] = bar
        return True

    def stop(self, robot_id: str) -> None:
        bar = self.bars.pop(robot_id, None)
        if bar is not None:
            self.window.clock.remove(bar.poll)
            if getattr(self.window, "replay", None) is bar:
                self.window.replay = None
            bar.hide()
            bar.deleteLater()
        stack = self._stacks.pop(robot_id, None)
        self._files.pop(robot_id, None)
        self.players.pop(robot_id, None)
        self.servers.pop(robot_id, None)
        if stack is not None:
            try:
                stack.close()
            except Exception:  # noqa: BLE001 - a player that fails to stop never keeps the window open
                log.exception("stopping the recording of robot %s failed", robot_id)

    def shutdown(self) -> None:
        for rid in list(self._stacks):
            self.stop(rid)
