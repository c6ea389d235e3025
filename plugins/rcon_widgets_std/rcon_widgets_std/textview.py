"""Text View: a scrollable history of ``std_msgs/String`` and log messages (``rosgraph_msgs/Log`` on
ROS 1, ``rcl_interfaces/msg/Log`` on ROS 2), coloured by level, filtered by level and text, in bounded
memory (a deque of ``max_lines``). Bound with role PUBLISH it is also an input line: what the operator
types is published on the topic, and the history shows the topic, i.e. a chat room."""

from __future__ import annotations

import collections
import threading
import time
from typing import Any

import attrs

from rcon_core.msgs import time as rtime
from rcon_core.plugins import Role

from .base import StdModel

__all__ = ["TextViewSettings", "TextViewModel", "Line", "History", "LEVELS", "level_name"]

LEVELS = ("debug", "info", "warn", "error", "fatal")
_ROS1 = {1: "debug", 2: "info", 4: "warn", 8: "error", 16: "fatal"}
_ROS2 = {10: "debug", 20: "info", 30: "warn", 40: "error", 50: "fatal"}
MAX_LINES_LIMIT = 50_000
#: a log line arriving this soon (s) after subscribing, stamped before the subscription, is a latched
#: replay (rosbridge sends each node's latched last line first, in no time order)
REPLAY_WINDOW_S = 1.5
#: how much older (s) than the subscription a line's stamp must be to count as replayed (clock slack)
REPLAY_SLACK_S = 1.0


def level_name(level: Any) -> str:
    """ROS 1 (1, 2, 4, 8, 16) and ROS 2 (10 .. 50) log levels -> ``"debug"`` .. ``"fatal"``."""
    if isinstance(level, int) and not isinstance(level, bool):
        if level in _ROS1:
            return _ROS1[level]
        if level in _ROS2:
            return _ROS2[level]
        if level > 50:
            return "fatal"
    return "info"


@attrs.define
class TextViewSettings:
    max_lines: int = attrs.field(default=1000, metadata={"label": "Lines kept", "min": 10, "max": MAX_LINES_LIMIT})
    min_level: str = attrs.field(default="debug", metadata={
        "label": "Log: lowest level", "choices": list(LEVELS),
        "help": "log topics (rosgraph_msgs/Log, rcl_interfaces/Log) only; text topics have no levels"})
    filter_text: str = attrs.field(default="", metadata={"label": "Only lines containing"})
    show_node: bool = attrs.field(default=True, metadata={"label": "Show the node name"})
    show_time: bool = attrs.field(default=True, metadata={"label": "Show the time"})

    def problems(self) -> list[str]:
        out = []
        if not 10 <= self.max_lines <= MAX_LINES_LIMIT:
            out.append(f"lines kept must be between 10 and {MAX_LINES_LIMIT}, not {self.max_lines}")
        if self.min_level not in LEVELS:
            out.append(f"lowest level must be one of {', '.join(LEVELS)}, not {self.min_level!r}")
        return out


@attrs.frozen
class Line:
    n: int  #: running number: a view appends the lines it has not painted yet
    text: str
    level: str = "info"
    node: str = ""
    stamp: float | None = None  #: seconds (the message's own stamp), when it has one
    #: logged before we subscribed and delivered as a latched replay: shown first, in stamp order, marked
    replayed: bool = False

    def matches(self, min_level: str, text: str) -> bool:
        if LEVELS.index(self.level) < LEVELS.index(min_level):
            return False
        return not text or text.lower() in self.text.lower() or text.lower() in self.node.lower()


@attrs.frozen
class History:
    """What the view paints: the visible (filtered) lines, oldest first. ``filter_version`` changes when
    the filter does (repaint everything); otherwise lines only get appended (and old ones drop off)."""

    lines: tuple[Line, ...]
    filter_version: int
    min_level: str
    filter_text: str
    total: int  #: lines received since start


class TextViewModel(StdModel):
    stale_after = None
    needs_types = False

    def __init__(self, settings: TextViewSettings | None, *args: Any, **kwargs: Any) -> None:
        super().__init__(settings if settings is not None else TextViewSettings(), *args, **kwargs)
        s = self.settings
        limit = max(10, min(MAX_LINES_LIMIT, int(s.max_lines)))
        self._all: collections.deque[Line] = collections.deque(maxlen=limit)
        self._visible: collections.deque[Line] = collections.deque(maxlen=limit)
        self._hist_lock = threading.Lock()
        self._n = 0
        self._min_level = s.min_level if s.min_level in LEVELS else "debug"
        self._filter_text = s.filter_text
        self._filter_version = 0
        self._echo_sub: Any = None
        #: wall clock (log stamps are wall time); tests may replace it
        self.wall: Any = time.time
        self._subscribed_wall: float | None = None
        self._subscribed_mono: float | None = None
        #: (node, stamp, text) of the stamped lines kept: a latched line sent again (a re-subscription
        #: after a reconnect) is not shown twice
        self._seen: collections.OrderedDict[tuple[str, float, str], None] = collections.OrderedDict()

    @property
    def is_log(self) -> bool:
        return self.binding.type.replace("/msg/", "/") in ("rosgraph_msgs/Log", "rcl_interfaces/Log")

    # -- history -------------------------------------------------------------------------------------
    def to_line(self, msg: dict[str, Any], n: int) -> Line:
        if "msg" in msg and "level" in msg:  # a log message, either flavour
            stamp_v = msg.get("stamp") or (msg.get("header") or {}).get("stamp")
            stamp = rtime.to_float(stamp_v) if rtime.is_time(stamp_v) else None
            return Line(n, str(msg.get("msg", "")), level_name(msg.get("level")), str(msg.get("name", "")), stamp)
        text = msg.get("data", msg) if isinstance(msg, dict) else msg
        return Line(n, str(text))

    def on_message(self, msg: dict[str, Any]) -> None:
        """Lines are shown in the order received, except the latched replay a subscription starts with:
        those lines (each node's last line from before we subscribed) come first, in stamp order, marked
        as replayed, so the history reads in time order from the top. A stamped line already kept (sent
        again by a re-subscription) is dropped."""
        with self._hist_lock:
            self._n += 1
            line = self.to_line(msg, self._n)
            if line.stamp is not None:
                key = (line.node, line.stamp, line.text)
                if key in self._seen:
                    self._n -= 1
                    return
                self._seen[key] = None
                while len(self._seen) > (self._all.maxlen or 0):
                    self._seen.popitem(last=False)
                if self._is_replay(line):
                    line = attrs.evolve(line, replayed=True)
            if line.replayed and self._insert_replayed(line):
                pass  # placed among the earlier replayed lines: the view repaints everything
            else:
                self._all.append(line)
                if line.matches(self._min_level, self._filter_text):
                    self._visible.append(line)
            history = self._snapshot()
        self.set_value(history, message=msg)

    def _is_replay(self, line: Line) -> bool:
        if self._subscribed_wall is None or self._subscribed_mono is None or line.stamp is None:
            return False
        soon = self._clock() - self._subscribed_mono < REPLAY_WINDOW_S
        return soon and line.stamp < self._subscribed_wall - REPLAY_SLACK_S

    def _insert_replayed(self, line: Line) -> bool:
        """Put a replayed line in stamp order within the leading replayed block. Returns False when its
        place is the end (an ordinary append), True when it was inserted before other lines."""
        at = 0
        for x in self._all:
            if not x.replayed or (x.stamp or 0.0) > (line.stamp or 0.0):
                break
            at += 1
        if at == len(self._all):
            return False
        if len(self._all) == self._all.maxlen:
            self._all.popleft()
            at = max(0, at - 1)
        self._all.insert(at, line)
        self._visible.clear()
        self._visible.extend(x for x in self._all if x.matches(self._min_level, self._filter_text))
        self._filter_version += 1  # lines moved: the view paints the history again
        return True

    def _snapshot(self) -> History:
        return History(tuple(self._visible), self._filter_version, self._min_level, self._filter_text, self._n)

    def set_filter(self, min_level: str | None = None, text: str | None = None) -> None:
        """Change what is shown (any thread); the kept history is filtered again."""
        with self._hist_lock:
            if min_level is not None:
                if min_level not in LEVELS:
                    raise ValueError(f"level must be one of {', '.join(LEVELS)}, not {min_level!r}")
                self._min_level = min_level
            if text is not None:
                self._filter_text = text
            self._filter_version += 1
            self._visible.clear()
            self._visible.extend(x for x in self._all if x.matches(self._min_level, self._filter_text))
            history = self._snapshot()
        self.replace_value(history)

    def clear(self) -> None:
        with self._hist_lock:
            self._seen.clear()
            self._all.clear()
            self._visible.clear()
            self._filter_version += 1
            history = self._snapshot()
        self.replace_value(history)

    # -- chat: publish role --------------------------------------------------------------------------
    def on_start(self) -> None:
        self._subscribed_wall, self._subscribed_mono = self.wall(), self._clock()
        super().on_start()
        b = self.binding
        if b.role is Role.PUBLISH and not b.problems():
            self._echo_sub = self.port.subscribe(b.name, self._receive, type=b.type)

    def on_stop(self) -> None:
        if self._echo_sub is not None:
            try:
                self._echo_sub.unsubscribe()
            except Exception as exc:
                self.set_error(f"while stopping: {exc}")
            self._echo_sub = None

    def message_for(self, text: str) -> dict[str, Any]:
        """A ``std_msgs/String``, or an info-level log line from the operator on a log topic."""
        if not self.is_log:
            return {"data": text}
        ros2 = "rcl_interfaces" in self.binding.type
        msg: dict[str, Any] = {"level": 20 if ros2 else 2, "name": "rcon_operator", "msg": text,
                               "file": "", "function": "", "line": 0}
        if ros2:
            msg["stamp"] = rtime.now(ros2=True)
        else:
            msg["header"] = {"seq": 0, "stamp": rtime.now(), "frame_id": ""}
            msg["topics"] = []
        return msg

    def send(self, text: str) -> bool:
        """Publish a line typed by the operator (any thread). Empty lines are not sent."""
        if not text.strip():
            return False
        return self.publish(self.message_for(text))
