"""Text View: a scrollable history of ``std_msgs/String`` and log messages (``rosgraph_msgs/Log`` on
ROS 1, ``rcl_interfaces/msg/Log`` on ROS 2), coloured by level, filtered by level and text, in bounded
memory (a deque of ``max_lines``). Bound with role PUBLISH it is also an input line: what the operator
types is published on the topic, and the history shows the topic, i.e. a chat room.

Decision: the cost of one message is bounded, whatever its size and however many arrive
    A single 5 MB String froze the window for minutes (Qt lays out a line that long) and 10,000 messages a
    second copied the whole history once per message. So, on the bridge thread, each line keeps a
    *display text* of at most ``DISPLAY_CHARS`` characters and ``DISPLAY_ROWS`` rows (``Line.length``
    says how long the whole text was); the whole texts of the newest shortened lines are kept, up to
    ``FULL_TEXT_BUDGET`` characters in all, for :meth:`TextViewModel.full_text` (the view shows or copies
    one on demand). The filter looks at the display text. A snapshot (:class:`History`) is a window onto
    an append-only ring of the visible lines, made in constant time per message (no copy of the
    history); ``History.lines`` reads the window, ``History.since(k)`` only the lines after the ones a
    view has painted. A line that falls off the end of the history while a view still reads an older
    snapshot is skipped, as it would have scrolled away.
"""

from __future__ import annotations

import collections
import threading
import time
from typing import Any

import attrs

from rcon_core.bridge.safety import bounded_repr
from rcon_core.msgs import time as rtime
from rcon_core.plugins import Role

from .base import StdModel
from .common import shorten_text

__all__ = ["TextViewSettings", "TextViewModel", "Line", "History", "Ring", "LEVELS", "level_name", "display_text"]

LEVELS = ("debug", "info", "warn", "error", "fatal")
_ROS1 = {1: "debug", 2: "info", 4: "warn", 8: "error", 16: "fatal"}
_ROS2 = {10: "debug", 20: "info", 30: "warn", 40: "error", 50: "fatal"}
MAX_LINES_LIMIT = 50_000
#: a line is shown shortened to this many characters (and ``DISPLAY_ROWS`` rows); the whole text on demand
DISPLAY_CHARS = 1000
DISPLAY_ROWS = 12
#: characters of whole texts kept for the shortened lines (the newest first; the newest is always kept)
FULL_TEXT_BUDGET = 16_000_000
#: a subscription's latched replay is put in stamp order for at most this many lines (then appended)
REPLAY_MAX = 256
#: a log line arriving this soon (s) after subscribing, stamped before the subscription, is a latched
#: replay (rosbridge sends each node's latched last line first, in no time order)
REPLAY_WINDOW_S = 1.5
#: how much older (s) than the subscription a line's stamp must be to count as replayed (clock slack)
REPLAY_SLACK_S = 1.0


def _text(value: Any) -> str:
    """A message's text: a string as it is; anything else in a bounded form (never ``str()`` of a value
    that may be nested 1000 deep or a million items long)."""
    if isinstance(value, str):
        return value
    return bounded_repr(value, limit=DISPLAY_CHARS * 4, depth=8)


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
    #: the whole text's length in characters when ``text`` is shortened for display, else None
    length: int | None = None

    @property
    def shortened(self) -> bool:
        return self.length is not None

    def matches(self, min_level: str, text: str) -> bool:
        if LEVELS.index(self.level) < LEVELS.index(min_level):
            return False
        return not text or text.lower() in self.text.lower() or text.lower() in self.node.lower()


def display_text(text: str) -> tuple[str, int | None]:
    """``text`` as a line shows it: at most ``DISPLAY_CHARS`` characters and ``DISPLAY_ROWS`` rows; and
    the whole length when it was shortened (else None). Costs at most ``DISPLAY_CHARS``, whatever the
    length of ``text``."""
    return shorten_text(text, DISPLAY_CHARS, DISPLAY_ROWS)


class Ring:
    """The visible lines, append-only: slot ``k % capacity`` holds the k-th line. A snapshot is
    ``(ring, start, end)``; reading it copies nothing until asked, and a line overwritten since (it fell
    off the history) reads as None. One writer (the bridge thread), any readers."""

    __slots__ = ("capacity", "slots", "end")

    def __init__(self, capacity: int) -> None:
        self.capacity = capacity
        self.slots: list[tuple[int, Line] | None] = [None] * capacity
        self.end = 0

    def append(self, line: Line) -> None:
        self.slots[self.end % self.capacity] = (self.end, line)
        self.end += 1

    def get(self, k: int) -> Line | None:
        slot = self.slots[k % self.capacity]
        return slot[1] if slot is not None and slot[0] == k else None


@attrs.frozen
class History:
    """What the view paints: the visible (filtered) lines ``start .. end - 1`` of ``ring``, oldest first.
    ``filter_version`` (and the ring) changes when the filter does (repaint everything); otherwise lines
    only get appended (and old ones drop off)."""

    ring: Ring = attrs.field(eq=False, repr=False)
    start: int
    end: int
    filter_version: int
    min_level: str
    filter_text: str
    total: int  #: lines received since start

    @property
    def lines(self) -> tuple[Line, ...]:
        """The visible lines of this snapshot (a copy: for tests and tools, not per message)."""
        return tuple(self.since(self.start))

    def __len__(self) -> int:
        return self.end - max(self.start, self.end - self.ring.capacity)

    def since(self, k: int, limit: int | None = None) -> list[Line]:
        """The lines from the k-th visible one on (at most ``limit``, the newest), skipping those gone."""
        first = max(k, self.start, self.end - self.ring.capacity)
        if limit is not None:
            first = max(first, self.end - limit)
        get = self.ring.get
        return [x for x in map(get, range(first, self.end)) if x is not None]


class TextViewModel(StdModel):
    stale_after = None
    needs_types = False

    def __init__(self, settings: TextViewSettings | None, *args: Any, **kwargs: Any) -> None:
        super().__init__(settings if settings is not None else TextViewSettings(), *args, **kwargs)
        s = self.settings
        self.limit = limit = max(10, min(MAX_LINES_LIMIT, int(s.max_lines)))
        self._all: collections.deque[Line] = collections.deque(maxlen=limit)
        self._visible = Ring(limit)
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
        self._replays = 0
        #: (node, stamp, display text, length) of the stamped lines kept: a latched line sent again (a
        #: re-subscription after a reconnect) is not shown twice
        self._seen: collections.OrderedDict[tuple[str, float, str, int | None], None] = collections.OrderedDict()
        #: line number -> the whole text of a shortened line, newest last, ``FULL_TEXT_BUDGET`` in all
        self._full: collections.OrderedDict[int, str] = collections.OrderedDict()
        self._full_chars = 0

    @property
    def is_log(self) -> bool:
        return self.binding.type.replace("/msg/", "/") in ("rosgraph_msgs/Log", "rcl_interfaces/Log")

    # -- history -------------------------------------------------------------------------------------
    def to_line(self, msg: dict[str, Any], n: int) -> tuple[Line, str]:
        """The line for ``msg`` and its whole text (the line's ``text`` is the shortened display text)."""
        if "msg" in msg and "level" in msg:  # a log message, either flavour
            stamp_v = msg.get("stamp") or (msg.get("header") or {}).get("stamp")
            stamp = rtime.to_float(stamp_v) if rtime.is_time(stamp_v) else None
            whole = _text(msg.get("msg", ""))
            shown, length = display_text(whole)
            node, _ = display_text(_text(msg.get("name", "")))
            return Line(n, shown, level_name(msg.get("level")), node.replace("\n", " "), stamp,
                        length=length), whole
        whole = _text(msg.get("data", msg) if isinstance(msg, dict) else msg)
        shown, length = display_text(whole)
        return Line(n, shown, length=length), whole

    def on_message(self, msg: dict[str, Any]) -> None:
        """Lines are shown in the order received, except the latched replay a subscription starts with:
        those lines (each node's last line from before we subscribed) come first, in stamp order, marked
        as replayed, so the history reads in time order from the top. A stamped line already kept (sent
        again by a re-subscription) is dropped. Costs the same for a 5 MB line as for a short one (see
        the module's docstring)."""
        with self._hist_lock:
            self._n += 1
            line, whole = self.to_line(msg, self._n)
            if line.stamp is not None:
                key = (line.node, line.stamp, line.text, line.length)
                if key in self._seen:
                    self._n -= 1
                    return
                self._seen[key] = None
                while len(self._seen) > self.limit:
                    self._seen.popitem(last=False)
                if self._is_replay(line):
                    line = attrs.evolve(line, replayed=True)
            if line.shortened:
                self._keep_whole(line.n, whole)
            if line.replayed and self._insert_replayed(line):
                pass  # placed among the earlier replayed lines: the view repaints everything
            else:
                self._all.append(line)
                if line.matches(self._min_level, self._filter_text):
                    self._visible.append(line)
            history = self._snapshot()
        self.set_value(history, message=msg)

    def _keep_whole(self, n: int, whole: str) -> None:
        self._full[n] = whole
        self._full_chars += len(whole)
        while self._full_chars > FULL_TEXT_BUDGET and len(self._full) > 1:
            _, old = self._full.popitem(last=False)
            self._full_chars -= len(old)

    def full_text(self, line: Line | int) -> str | None:
        """The whole text of ``line`` (a Line or its number ``n``): its display text when it was not
        shortened, None when the whole text is no longer kept (``FULL_TEXT_BUDGET``). Any thread."""
        n = line if isinstance(line, int) else line.n
        with self._hist_lock:
            whole = self._full.get(n)
            if whole is not None:
                return whole
            if isinstance(line, Line):
                return None if line.shortened else line.text
            found = next((x for x in reversed(self._all) if x.n == n), None)
        if found is None or found.shortened:
            return None
        return found.text

    def _is_replay(self, line: Line) -> bool:
        if self._subscribed_wall is None or self._subscribed_mono is None or line.stamp is None:
            return False
        soon = self._clock() - self._subscribed_mono < REPLAY_WINDOW_S
        return soon and line.stamp < self._subscribed_wall - REPLAY_SLACK_S

    def _insert_replayed(self, line: Line) -> bool:
        """Put a replayed line in stamp order within the leading replayed block. Returns False when its
        place is the end (an ordinary append), True when it was inserted before other lines. Only the
        first ``REPLAY_MAX`` replayed lines are placed (a flood of old stamps is appended)."""
        self._replays += 1
        if self._replays > REPLAY_MAX:
            return False
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
        self._refilter()  # lines moved: the view paints the history again
        return True

    def _refilter(self) -> None:
        """A new ring of the visible lines (under the lock); the view repaints everything."""
        self._visible = Ring(self.limit)
        for x in self._all:
            if x.matches(self._min_level, self._filter_text):
                self._visible.append(x)
        self._filter_version += 1

    def _snapshot(self) -> History:
        ring = self._visible
        return History(ring, max(0, ring.end - ring.capacity), ring.end, self._filter_version, self._min_level,
                       self._filter_text, self._n)

    def set_filter(self, min_level: str | None = None, text: str | None = None) -> None:
        """Change what is shown (any thread); the kept history is filtered again."""
        with self._hist_lock:
            if min_level is not None:
                if min_level not in LEVELS:
                    raise ValueError(f"level must be one of {', '.join(LEVELS)}, not {min_level!r}")
                self._min_level = min_level
            if text is not None:
                self._filter_text = text
            self._refilter()
            history = self._snapshot()
        self.replace_value(history)

    def clear(self) -> None:
        with self._hist_lock:
            self._seen.clear()
            self._all.clear()
            self._full.clear()
            self._full_chars = 0
            self._refilter()
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
