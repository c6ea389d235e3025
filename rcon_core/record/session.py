"""``AppRecording``: the app's Record control, without Qt -- every robot of the workspace into its own file.

What is recorded, per robot: the topics the canvases' widgets show (``topics_of``: every canvas, not only
the one on screen, so switching canvases never leaves a hole), every other topic the app subscribes to on
that robot (what widgets read beside their binding, such as a button's state topic: ``follow_session``)
and everything the operator sent to it
through any widget or panel (the client's operator tap, ``bridge/tap.py``). One MCAP file per robot,
``<dir>/rcon-<time>-<robot>.mcap``, so each opens on its own in Foxglove, Lichtblick or ``rcon sim --play``.
A robot on the Foxglove protocol is recorded by ``foxglove_source.py`` (its channels as advertised, the
file's profile from every channel it advertises), each rosbridge robot as ``ingest.py`` says.

Threading: ``start``/``stop``/``swap_client`` are called from the GUI thread and run their work on the
bridge thread (``BridgeThread.run``); ``status()`` may be read from any thread (counters only).

A robot whose link drops keeps its recorder: the client reconnects and restores the subscriptions, the
gap shows in the file (``/rcon/link`` says when). A robot given a new client (the operator connected it
again) gets a new recorder on the same file (``swap_client``).
"""

from __future__ import annotations

import logging
import re
import time
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .foxglove_source import is_foxglove, recorder_for, wait_profile
from .ingest import RobotRecorder
from .writer import McapSink

log = logging.getLogger(__name__)

__all__ = ["AppRecording", "RecordingStatus", "topics_of", "DEFAULT_BUDGET"]

DEFAULT_BUDGET = 4_000_000_000  #: bytes for all the files of one recording (4 GB)


def topics_of(workspace: Any, robot_id: str, first_id: str) -> dict[str, str]:
    """``{topic: type}`` the widgets bound to ``robot_id`` subscribe to, on every canvas."""
    out: dict[str, str] = {}
    for canvas in workspace.canvases:
        for inst in canvas.widgets:
            b = inst.binding
            rid = b.robot or first_id
            if rid != robot_id or not b.name or str(getattr(b.role, "value", b.role)) != "subscribe":
                continue
            out.setdefault(b.name, b.type or "")
    return out


@dataclass(frozen=True)
class RecordingStatus:
    """What the indicator shows."""

    recording: bool
    seconds: float
    size: int  #: bytes on disk, every file
    messages: int
    events: int  #: operator events
    dropped: int
    warning: str | None  #: the disk budget is nearly used
    problem: str | None  #: what stopped or hurt the recording, in words
    files: tuple[str, ...]


def _slug(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "-", text).strip("-") or "robot"


class AppRecording:
    """One press of Record: a file per robot (see the module docstring)."""

    def __init__(self, thread: Any, directory: str | Path, *, budget: int | None = DEFAULT_BUDGET,
                 compression: str = "zstd") -> None:
        self.thread = thread
        self.directory = Path(directory)
        self.budget = budget
        self.compression = compression
        self.started = 0.0
        self.active = False
        self.robots: dict[str, tuple[Any, RobotRecorder | None, McapSink]] = {}  # id -> (client, recorder, sink)
        self.problems: list[str] = []
        self._topics: dict[str, tuple[str, dict[str, str]]] = {}  # id -> (name, topics)

    def start(self, robots: Iterable[tuple[str, str, Any, dict[str, str]]], timeout: float = 15.0) -> None:
        """``robots``: ``(robot_id, name, client or None, {topic: type})``; a robot without a client gets its
        file when it has one (``swap_client``). Raises OSError when the folder or a file cannot be made."""
        self.directory.mkdir(parents=True, exist_ok=True)
        stamp = time.strftime("%Y%m%d-%H%M%S")
        items = list(robots)
        per_file = self.budget // max(1, len(items)) if self.budget else None
        self.started = time.monotonic()
        self.active = True
        for robot_id, name, client, topics in items:
            path = self.directory / f"rcon-{stamp}-{_slug(name)}.mcap"
            self.thread.run(self._start_robot(robot_id, name, client, topics, path, per_file)).result(timeout)

    async def _start_robot(self, robot_id: str, name: str, client: Any, topics: dict[str, str], path: Path,
                           budget: int | None) -> None:
        ros2 = False
        if is_foxglove(client):  # the channels' own encodings say (foxglove_source.py)
            profile = await wait_profile(client)
        else:
            if client is not None:
                try:
                    ros2 = client.ros_version == 2 or (client.ros_version is None and
                                                       (await client.detect_ros()).version == 2)
                except Exception:  # noqa: BLE001 - not connected yet: ROS 1 unless the robot says otherwise
                    ros2 = False
            profile = "ros2" if ros2 else "ros1"
        sink = McapSink(str(path), profile, compression=self.compression, budget=budget,
                        metadata={"robot": name, "recorder": "rcon app",
                                  "started": time.strftime("%Y-%m-%dT%H:%M:%S%z")},
                        on_problem=self.problems.append)
        rec = None
        if client is not None and hasattr(client, "session"):
            rec = recorder_for(client, sink, ros2=ros2, robot=name, topics=list(topics), types=topics,
                               follow_session=True)
            await rec.start()
        self.robots[robot_id] = (client, rec, sink)
        self._topics[robot_id] = (name, dict(topics))

    def swap_client(self, robot_id: str, client: Any, timeout: float = 10.0) -> None:
        """The robot has a new client (or none): record from it into the same file."""
        entry = self.robots.get(robot_id)
        if not self.active or entry is None or entry[0] is client:
            return
        self.thread.run(self._swap(robot_id, client)).result(timeout)

    async def _swap(self, robot_id: str, client: Any) -> None:
        old_client, rec, sink = self.robots[robot_id]
        if rec is not None:
            rec.stop()
        name, topics = self._topics[robot_id]
        new = None
        if client is not None and hasattr(client, "session") and not sink.stopped:
            new = recorder_for(client, sink, ros2=sink.profile == "ros2", robot=name, topics=list(topics),
                               types=topics, follow_session=True)
            await new.start()
        self.robots[robot_id] = (client, new, sink)

    def add_topics(self, robot_id: str, topics: dict[str, str]) -> None:
        """Widgets were added while recording: their topics are recorded from now on."""
        entry = self.robots.get(robot_id)
        if entry is None or entry[1] is None:
            return
        rec = entry[1]
        new = {t: ty for t, ty in topics.items() if t not in rec.topics and t not in rec.wanted}
        if new:
            self._topics[robot_id][1].update(new)
            self.thread.call(rec.add_topics, new)

    def stop(self, timeout: float = 30.0) -> None:
        """Stop every recorder and close every file properly (summary and index)."""
        if not self.active:
            return
        self.active = False

        async def stop_all() -> None:
            for _client, rec, _sink in self.robots.values():
                if rec is not None:
                    rec.stop()

        try:
            self.thread.run(stop_all()).result(timeout)
        except Exception as exc:  # noqa: BLE001 - the files are closed all the same
            log.warning("stopping the recorders: %s", exc)
        for _client, _rec, sink in self.robots.values():
            sink.close(timeout)

    def status(self) -> RecordingStatus:
        sinks = [s for _c, _r, s in self.robots.values()]
        recs = [r for _c, r, _s in self.robots.values() if r is not None]
        problems = [s.problem for s in sinks if s.problem] + [p for r in recs for p in r.problems]
        warnings = [s.warning for s in sinks if s.warning]
        return RecordingStatus(
            recording=self.active and not all(s.stopped for s in sinks),
            seconds=time.monotonic() - self.started if self.started else 0.0,
            size=sum(s.size for s in sinks), messages=sum(s.stats.messages for s in sinks),
            events=sum(r.events for r in recs), dropped=sum(s.stats.dropped for s in sinks),
            warning=warnings[0] if warnings else None, problem=problems[0] if problems else None,
            files=tuple(f for s in sinks for f in s.stats.files))
