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

:class:`RobotRecordings` is given the robots' links, the notice bar and the recordings folder; the window
places the bars (``bar_shown``/``bar_gone``: under the connection bar, on the frame clock), connects the
first robot (``connect_first``), restarts widgets on a seek (``seeked``) and on new view-only marks
(``marks_changed``). It also plays a recording as the first robot (:meth:`RobotRecordings.play_first`:
``rcon --play FILE``, *Canvas ▾ → Replay a recording…*), whose bar is :attr:`RobotRecordings.replay`.
"""

from __future__ import annotations

import contextlib
import logging
from pathlib import Path
from typing import Any

from qtpy import QtCore, QtWidgets

from rcon_core.app.fleet_links import FleetLinks
from rcon_core.app.notice_bar import NoticeBar
from rcon_core.app.replay_bar import ReplayBar
from rcon_core.canvas.robots import Robot

log = logging.getLogger(__name__)

__all__ = ["RobotRecordings", "recording_reason"]


def recording_reason(robot: Robot) -> str | None:
    """Why a recording's robot may not be commanded (None for a live robot)."""
    if not robot.recording:
        return None
    return f"robot “{robot.label}” is a recording ({Path(robot.recording).name}): commands go nowhere"


class RobotRecordings(QtCore.QObject):
    """The players of the workspace's recording robots, by robot id (see the module docstring)."""

    #: a timeline (a ReplayBar) to put under the connection bar and on the frame clock
    bar_shown = QtCore.Signal(object)
    #: a timeline going away: off the frame clock
    bar_gone = QtCore.Signal(object)
    #: the first robot connects to this URL (a player's; never kept in the URL history)
    connect_first = QtCore.Signal(str)
    #: a robot's link now goes to a recording: the widgets restart on ports that refuse to send
    marks_changed = QtCore.Signal()
    #: a timeline was moved: the widgets start again on the state there
    seeked = QtCore.Signal()

    def __init__(self, links: FleetLinks, notice: NoticeBar, why: dict[str, str], directory: Path,
                 parent: QtCore.QObject | None = None) -> None:
        super().__init__(parent)
        self.links, self.notice, self.why, self.directory = links, notice, why, directory
        self._stacks: dict[str, contextlib.ExitStack] = {}
        self._files: dict[str, str] = {}
        self.players: dict[str, Any] = {}
        self.servers: dict[str, Any] = {}
        self.bars: dict[str, ReplayBar] = {}
        #: the timeline of a recording played as the first robot, or None
        self.replay: ReplayBar | None = None
        #: what plays a recording opened from the menu (closed at shutdown)
        self.replay_stack: contextlib.ExitStack | None = None

    def sync(self, robots: list[Robot]) -> None:
        """Stop the players of robots that are gone or play another file now."""
        wanted = {r.id: r.recording for r in robots if r.recording}
        for rid in list(self._stacks):
            if wanted.get(rid) != self._files.get(rid):
                self.stop(rid)

    def play(self, robot: Robot, first: bool) -> bool:
        """Play ``robot``'s recording and connect its link to it; False (said) when it cannot be played."""
        from rcon_core.record.files import RecordingError
        from rcon_core.sim.playback import played_in_thread

        if robot.id in self._stacks and self._files.get(robot.id) == robot.recording:
            return True
        self.stop(robot.id)
        stack = contextlib.ExitStack()
        try:
            server, player = stack.enter_context(played_in_thread(robot.recording))
        except (RecordingError, OSError, ValueError) as exc:
            stack.close()
            text = f"cannot replay {exc}"
            self.why[robot.id] = text
            self.notice.show_notice(f"⚠ {robot.label}: {text}")
            log.warning("robot %s: %s", robot.label, text)
            return False
        self._stacks[robot.id] = stack
        self._files[robot.id] = robot.recording
        self.players[robot.id], self.servers[robot.id] = player, server
        if first:
            bar = self.play_first(server, player)  # the connection bar connects to it
        else:
            bar = self._bar(server, player)
            bar.words.setText(f"REPLAY · {robot.label} · {Path(robot.recording).name} · commands go nowhere")
            self.links.connect_robot(robot.id, server.url)
            self.marks_changed.emit()
        self.bars[robot.id] = bar
        return True

    def _bar(self, server: Any, player: Any) -> ReplayBar:
        bar = ReplayBar(server, player)
        bar.seeked.connect(self.seeked)
        self.bar_shown.emit(bar)
        return bar

    def play_first(self, server: Any, player: Any) -> ReplayBar:
        """Put the timeline under the connection bar, mark the recording's robot view-only, and connect the
        first robot to it (never kept in the URL history)."""
        if self.replay is not None:
            self.replay.hide()
        bar = self.replay = self._bar(server, player)
        self.connect_first.emit(server.url)
        # the link refuses to send (bridge/guard.py), and widgets already running are rebuilt on ports that say so
        self.marks_changed.emit()
        return bar

    def open_dialog(self, parent: QtWidgets.QWidget | None = None) -> None:
        """Canvas ▾ → Replay a recording…: pick an .mcap, a .bag or a rosbag2 folder's file and play it."""
        from rcon_core.record.files import RecordingError
        from rcon_core.sim.playback import played_in_thread

        path, _filter = QtWidgets.QFileDialog.getOpenFileName(
            parent, "Replay a recording", str(self.directory),
            "Recordings (*.mcap *.bag *.db3 metadata.yaml);;All files (*)")
        if not path:
            return
        if path.endswith(("metadata.yaml", ".db3")):
            path = str(Path(path).parent)
        stack = self.replay_stack
        if stack is None:
            stack = self.replay_stack = contextlib.ExitStack()
        try:
            server, player = stack.enter_context(played_in_thread(path))
        except (RecordingError, OSError) as exc:
            self.notice.show_notice(f"Cannot replay {exc}")
            return
        self.play_first(server, player)

    def stop(self, robot_id: str) -> None:
        bar = self.bars.pop(robot_id, None)
        if bar is not None:
            self.bar_gone.emit(bar)
            if self.replay is bar:
                self.replay = None
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

    def close_menu_replay(self) -> None:
        """A recording opened from the menu stops playing (the window is closing)."""
        if self.replay_stack is not None:
            self.replay_stack.close()

    def shutdown(self) -> None:
        for rid in list(self._stacks):
            self.stop(rid)
