"""The Multi-Touch teleop pad's settings and model (no Qt).

The view reports where the finger is on the pad as ``set_axes(x, y)`` (each -1..1, y up) and
``release()`` when it lifts. While a finger is down the model publishes the command at a steady rate from
a timer on the bridge loop; when it lifts it publishes one zero command at once and then nothing at all
(an idle pad never floods zeros that would fight another controller).

Safety: the zero is also sent, immediately, when the model is stopped (the canvas is left), when the link
goes down (sent again once it is back, then silence), when the robot's bridge holds the link's commands
behind an unanswered service call (``on_commands_held``: then nothing at all until it answers), and by the
view on touch cancel and focus loss.
After a forced stop the pad ignores the finger until it is lifted and put down again.
A stalled link (the client's DEGRADED state) counts as down. Every command has a freshness limit of
``COMMAND_MAX_AGE`` (the publisher's ``max_age``): the bridge drops a command it could not write within it,
so a stall never delivers a burst of old commands (see ``rcon_core/bridge/freshness.py``).

Several pads bound to the same topic on the same connection (two thumbs: linear on one, angular on the
other) form a group: their axes are merged into one message, published by one of them at its rate, so
they never fight; each pad's release zeroes only its own axes. The group is an object the model's
``WidgetContext`` shares per robot link (``context.shared``), so pads of two robots never merge.

What the pad shows is what is sent. The command at the pad's edge is the least of its own maximum
(``max_linear`` / ``max_angular``), the robot's safety envelope (the port's ``envelope``: the bridge holds
every command to it anyway, see ``rcon_core/bridge/envelope.py``) and, for forward speed, the robot's
speed limit when ``speed_limit_topic`` names where it is published (``/speed_limit``: the demo's Speed
limit slider); :meth:`TeleopModel.limits` says which holds. A pad whose topic nobody subscribes to says so
(asked of ``/rosapi/subscribers`` when it starts, when its link comes back and when a finger goes down), so
a pad bound to a topic the robot does not have never animates as if it drove.
"""

from __future__ import annotations

import asyncio
import itertools
import math
import re
import time
from typing import Any

import attrs

from rcon_core.plugins import WidgetModel
from rcon_core.plugins.paths import PathError, get_path, set_path

from .slots import LoopTicker

__all__ = ["TeleopSettings", "TeleopModel", "TeleopValue", "TELEOP_TYPES", "shape_axes", "axis_words"]

#: canonical type -> path of the part the axes are relative to
TELEOP_TYPES: dict[str, str] = {
    "geometry_msgs/msg/Twist": "",
    "geometry_msgs/msg/TwistStamped": "twist",
    "geometry_msgs/msg/Accel": "",
    "geometry_msgs/msg/AccelStamped": "accel",
    "geometry_msgs/msg/Vector3": "",
    "geometry_msgs/msg/Vector3Stamped": "vector",
    "geometry_msgs/msg/Point": "",
    "geometry_msgs/msg/PointStamped": "point",
    "geometry_msgs/msg/Point32": "",
    "geometry_msgs/msg/Pose2D": "",
}
_XYZ = {"x": 0.0, "y": 0.0, "z": 0.0}
_STAMP_HEADER = {"seq": 0, "stamp": {"secs": 0, "nsecs": 0}, "frame_id": ""}
_FALLBACK: dict[str, dict[str, Any]] = {
    "geometry_msgs/msg/Twist": {"linear": dict(_XYZ), "angular": dict(_XYZ)},
    "geometry_msgs/msg/Accel": {"linear": dict(_XYZ), "angular": dict(_XYZ)},
    "geometry_msgs/msg/Vector3": dict(_XYZ),
    "geometry_msgs/msg/Point": dict(_XYZ),
    "geometry_msgs/msg/Point32": dict(_XYZ),
    "geometry_msgs/msg/Pose2D": {"x": 0.0, "y": 0.0, "theta": 0.0},
}
for _stamped, _inner, _key in (("TwistStamped", "Twist", "twist"), ("AccelStamped", "Accel", "accel"),
                               ("Vector3Stamped", "Vector3", "vector"), ("PointStamped", "Point", "point")):
    _FALLBACK[f"geometry_msgs/msg/{_stamped}"] = {"header": _STAMP_HEADER,
                                                  _key: _FALLBACK[f"geometry_msgs/msg/{_inner}"]}

#: freshness limit of a motion command (s): older ones are dropped by the bridge, never sent late
COMMAND_MAX_AGE = 0.25

_TOPIC_RE = re.compile(r"^/?[A-Za-z_~][A-Za-z0-9_/~]*$")
_AXIS_RE = re.compile(r"^(auto|-?[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)*)?$")


@attrs.define
class TeleopSettings:
    """``horizontal``/``vertical``: the field (relative to the motion part of the message) a finger
    moving right/up drives; a leading ``-`` inverts it, ``""`` leaves the axis unused, ``"auto"``: for
    Twist/Accel up = ``linear.x`` and right = ``-angular.z`` (turn right); for points and vectors up = ``x``,
    right = ``-y``. ``max_linear`` (m/s) and ``max_angular`` (rad/s) are the commands at the pad's edge
    (``angular.*`` and ``theta`` use ``max_angular``). ``dead_zone``: fraction of the pad radius around the
    centre that means zero. ``rate_hz``: publish rate while a finger is down. ``frame_id``: for stamped
    types. ``speed_limit_topic``: a ``std_msgs/Float64`` topic holding the robot's speed limit (m/s); the
    pad's linear command never exceeds its last value (``""``: none)."""

    horizontal: str = "auto"
    vertical: str = "auto"
    max_linear: float = 1.0
    max_angular: float = 1.0
    dead_zone: float = 0.1
    rate_hz: float = 10.0
    frame_id: str = ""
    speed_limit_topic: str = ""

    def problems(self) -> list[str]:
        out = []
        for name in ("horizontal", "vertical"):
            value = getattr(self, name)
            if not _AXIS_RE.match(value or ""):
                out.append(f"the {name} axis {value!r} is not a field path such as 'linear.x' or '-angular.z'")
        if not self.horizontal and not self.vertical:
            out.append("both axes are unused: set the horizontal or the vertical axis")
        if not 0 < self.max_linear <= 100:
            out.append(f"the maximum linear speed must be more than 0 and at most 100, not {self.max_linear:g}")
        if not 0 < self.max_angular <= 50:
            out.append(f"the maximum angular speed must be more than 0 and at most 50, not {self.max_angular:g}")
        if not 0 <= self.dead_zone < 0.9:
            out.append(f"the dead zone must be between 0 and 0.9 of the pad, not {self.dead_zone:g}")
        if not 1 <= self.rate_hz <= 50:
            out.append(f"the publish rate must be between 1 and 50 Hz, not {self.rate_hz:g}")
        if self.speed_limit_topic and not _TOPIC_RE.match(self.speed_limit_topic):
            out.append(f"the speed limit topic {self.speed_limit_topic!r} is not a topic name such as /speed_limit")
        return out

    def commands(self, binding: Any) -> list[tuple[str, float]]:
        """(field path, the largest value this pad may send there) for each axis it drives: what the app
        compares with the robot's safety envelope before saving these settings."""
        base = binding.field_path or TELEOP_TYPES.get(binding.canonical_type, "")
        out = []
        for axis, auto in ((self.horizontal, "-angular.z"), (self.vertical, "linear.x")):
            rel = (auto if axis == "auto" else axis).lstrip("-")
            if not rel:
                continue
            leaf = rel.rsplit(".", 1)[-1]
            limit = self.max_angular if rel.startswith("angular") or leaf == "theta" else self.max_linear
            out.append((f"{base}.{rel}" if base else rel, float(limit)))
        return out


@attrs.frozen
class TeleopValue:
    """What the pad shows: the finger (x, y after the dead zone, -1..1), the command by field path,
    ``active`` (a finger is down and commands go out), ``locked`` (stopped by safety until the finger
    lifts), ``sent`` (messages published so far)."""

    active: bool = False
    x: float = 0.0
    y: float = 0.0
    command: tuple[tuple[str, float], ...] = ()
    locked: bool = False
    sent: int = 0
    reason: str = ""
    #: what holds the command at the pad's edge below the pad's own maximum ("" when nothing does):
    #: "≤ 1 m/s, 0.5 rad/s (safety envelope)", "≤ 0.5 m/s (speed limit)"
    held: str = ""
    #: nobody subscribes to the pad's topic: what the pad says instead of pretending to drive ("" otherwise)
    unheard: str = ""
    #: the robot's bridge holds this link's commands behind an unanswered call: why the pad sends nothing
    commands_held: str = ""


#: what moving the finger along an axis does, by the field it drives (the leaf, or part.leaf)
_WORDS = {"linear.x": ("forward", "back"), "linear.y": ("left", "right"), "linear.z": ("up", "down"),
          "angular.z": ("turn left", "turn right"), "angular.x": ("roll", "roll back"),
          "angular.y": ("pitch", "pitch back"), "x": ("forward", "back"), "y": ("left", "right"),
          "z": ("up", "down"), "theta": ("turn left", "turn right")}


def axis_words(axis: str) -> str:
    """What a finger moving up (vertical axis) or right (horizontal) does, in words: ``linear.x`` ->
    "forward", ``-angular.z`` -> "turn right"; "" for a field without words (the field is shown then)."""
    rel = axis.lstrip("-")
    words = _WORDS.get(rel) or _WORDS.get(".".join(rel.split(".")[-2:])) or _WORDS.get(rel.rsplit(".", 1)[-1])
    if words is None or not rel:
        return ""
    return words[1] if axis.startswith("-") else words[0]


def shape_axes(x: float, y: float, dead_zone: float) -> tuple[float, float]:
    """Clamp (x, y) to the unit disc and apply a radial dead zone (rescaled so the edge stays 1)."""
    r = math.hypot(x, y)
    if r > 1:
        x, y, r = x / r, y / r, 1.0
    if r <= dead_zone or r == 0:
        return 0.0, 0.0
    k = (r - dead_zone) / (1 - dead_zone) / r
    return x * k, y * k


class _Group:
    """Pads publishing to one topic on one connection: merged contributions, one publisher at a time."""

    def __init__(self) -> None:
        self.members: list[TeleopModel] = []  # active ones, in activation order; the first publishes
        self.contrib: dict[int, dict[str, float]] = {}


#: the pads' groups are shared per robot link under this key and the topic name (``WidgetContext.shared``)
GROUP_KEY = "rcon_widgets_sensors.teleop.group"
_ids = itertools.count(1)


class TeleopModel(WidgetModel):
    """Turns pad positions into motion commands at a steady rate; zero on every kind of letting go."""

    stale_after = None

    def __init__(self, settings: Any, binding: Any, port: Any, *, ticker_clock: Any = None,
                 **kwargs: Any) -> None:
        """``ticker_clock``: what the publish rate is timed on instead of the bridge loop (see
        :class:`~rcon_widgets_sensors.slots.LoopTicker`); tests pass ``rcon_core.testing.ManualClock``, as
        ``clock`` too, so ``send_times`` follow it."""
        super().__init__(settings if settings is not None else TeleopSettings(), binding, port, **kwargs)
        self.pad_id = next(_ids)  # tells the pads of one group apart
        self._ticker_clock = ticker_clock
        self._ticker: LoopTicker | None = None
        self._active = False
        self._locked = False
        self._zero_pending = False
        self._x = self._y = 0.0
        self._sent = 0
        self._reason = ""
        self._speed_limit: float | None = None  #: the last value heard on ``speed_limit_topic``
        self._limit_sub: Any = None
        self._unheard = ""
        self._commands_held = ""  #: why the robot's bridge holds commands now ("" when it does not)
        self._listeners_asked = -math.inf  #: the model's clock when /rosapi/subscribers was last asked
        self.send_times: list[float] = []  # the model's clock at each publish (tests, diagnostics)
        self._show_value()

    # -- what the message looks like --------------------------------------------------------------------
    @property
    def canonical_type(self) -> str:
        return self.binding.canonical_type

    @property
    def body_path(self) -> str:
        """Where the motion part sits in the message (the bound field, else by type)."""
        return self.binding.field_path or TELEOP_TYPES.get(self.canonical_type, "")

    def template(self) -> dict[str, Any]:
        """An all-zero message of the bound type."""
        if self.types is not None:
            try:
                return self.types.default(self.binding.type)
            except Exception:  # noqa: BLE001 - unknown to the registry: the table below may know it
                pass
        base = _FALLBACK.get(self.canonical_type)
        if base is None:
            raise ValueError(f"cannot build a {self.binding.type} message (unknown type)")
        return _deep_copy(base)

    def axes(self) -> tuple[str, str]:
        """(horizontal, vertical) field paths relative to :attr:`body_path`, ``-`` prefix = inverted."""
        s = self.settings
        body = self._body_fields()
        if "linear" in body or "angular" in body:
            auto = ("-angular.z", "linear.x")
        else:
            auto = ("-y", "x")
        h = auto[0] if s.horizontal == "auto" else s.horizontal
        v = auto[1] if s.vertical == "auto" else s.vertical
        return h, v

    def _body_fields(self) -> dict[str, Any]:
        try:
            body = self.template()
            if self.body_path:
                body = get_path(body, self.body_path)
        except (ValueError, PathError):
            return {}
        return body if isinstance(body, dict) else {}

    def problems(self) -> list[str]:
        out = super().problems()
        if out or not self.binding.type:
            return out
        try:
            msg = self.template()
        except ValueError as exc:
            return [str(exc)]
        for axis in self.axes():
            if not axis:
                continue
            path = self._abs(axis.lstrip("-"))
            try:
                value = get_path(msg, path)
            except PathError:
                out.append(f"{self.binding.type} has no field {path!r} for the pad's axis")
                continue
            if not isinstance(value, int | float) or isinstance(value, bool):
                out.append(f"{path!r} in {self.binding.type} is not a number")
        return out

    def _abs(self, rel: str) -> str:
        return f"{self.body_path}.{rel}" if self.body_path else rel

    def limits(self) -> tuple[float, float, str]:
        """(linear, angular, what holds them) at the pad's edge: the pad's own maximum, lowered to the
        robot's safety envelope and, for linear, to the robot's speed limit. The words say what holds,
        compactly ("≤ 1 m/s, 0.5 rad/s (safety envelope)"; "" when the pad's own maximum does)."""
        s = self.settings
        linear, angular = float(s.max_linear), float(s.max_angular)
        lin_by = ang_by = ""
        env = self.port.envelope
        if env is not None:
            lin_env = getattr(env, "max_linear", None)
            ang_env = getattr(env, "max_angular", None)
            if lin_env is not None and lin_env < linear:
                linear, lin_by = float(lin_env), "safety envelope"
            if ang_env is not None and ang_env < angular:
                angular, ang_by = float(ang_env), "safety envelope"
        limit = self._speed_limit
        if limit is not None and limit < linear:
            linear, lin_by = limit, "speed limit"
        groups: dict[str, list[str]] = {}
        if lin_by:
            groups.setdefault(lin_by, []).append(f"{linear:g} m/s")
        if ang_by:
            groups.setdefault(ang_by, []).append(f"{angular:g} rad/s")
        held = ", ".join(f"{', '.join(parts)} ({by})" for by, parts in groups.items())
        return linear, angular, f"≤ {held}" if held else ""

    def command_for(self, x: float, y: float) -> dict[str, float]:
        """Field path -> value for a finger at (x, y) (raw pad coordinates, -1..1, y up): what is sent."""
        s = self.settings
        sx, sy = shape_axes(x, y, s.dead_zone)
        max_linear, max_angular, _held = self.limits()
        out: dict[str, float] = {}
        for axis, v in zip(self.axes(), (sx, sy), strict=True):
            if not axis:
                continue
            sign = -1.0 if axis.startswith("-") else 1.0
            rel = axis.lstrip("-")
            leaf = rel.rsplit(".", 1)[-1]
            limit = max_angular if rel.startswith("angular") or leaf == "theta" else max_linear
            out[self._abs(rel)] = out.get(self._abs(rel), 0.0) + sign * v * limit + 0.0
        return out

    def advertise_options(self) -> dict[str, Any]:
        return {"max_age": COMMAND_MAX_AGE}

    # -- view -> model (any thread) ---------------------------------------------------------------------
    def set_axes(self, x: float, y: float) -> None:
        """The finger is at (x, y) on the pad (each -1..1, y up)."""
        self._dispatch(lambda: self._on_axes(float(x), float(y)))

    def release(self, reason: str = "released") -> None:
        """The finger lifted (or the touch was cancelled, or focus was lost): zero now, then silence."""
        self._dispatch(lambda: self._on_release(reason, unlock=True))

    def on_focus_lost(self) -> None:
        """The app says the operator's attention left (window inactive, the canvas put in Edit mode): stop
        now, and a finger still on the pad drives nothing more until it lifts (its touch keeps reaching the
        pad: its next move drove again).

        Called by the canvas runtime even when no view of this pad had keyboard focus.
        """
        self._dispatch(lambda: self._force_release("focus lost"))

    # -- loop thread ----------------------------------------------------------------------------------
    def _group(self) -> _Group:
        """The group of the pads on this robot link and topic (made by the first of them)."""
        group: _Group = self.context.shared((GROUP_KEY, self.binding.name), _Group)
        return group

    def _merged(self) -> dict[str, Any]:
        msg = self.template()
        g = self._group()
        for contrib in [g.contrib.get(m.pad_id, {}) for m in g.members]:
            for path, value in contrib.items():
                msg = set_path(msg, path, value)
        header = msg.get("header")
        if isinstance(header, dict) and isinstance(header.get("stamp"), dict):
            stamp = header["stamp"]
            ns = time.time_ns()
            a, b = ("sec", "nanosec") if "sec" in stamp else ("secs", "nsecs")
            header["stamp"] = {a: ns // 1_000_000_000, b: ns % 1_000_000_000}
            header["frame_id"] = self.settings.frame_id
        return msg

    def _send(self) -> None:
        pub = self._pub
        if pub is None:
            return
        try:
            pub.publish(self._merged())
        except Exception as exc:  # noqa: BLE001 - report on the widget, never raise into the loop
            self.set_error(f"publishing failed: {exc}")
            return
        self._sent += 1
        self.send_times.append(self._clock())
        del self.send_times[:-2000]

    def _on_axes(self, x: float, y: float) -> None:
        if not self.running or self._pub is None or self._locked or self.state.link_down or self._commands_held:
            self._x, self._y = x, y
            self._show_value()
            return
        self._x, self._y = x, y
        g = self._group()
        g.contrib[self.pad_id] = self.command_for(x, y)
        if not self._active:
            self._active = True
            self._reason = ""
            self._ask_listeners(fresh=2.0)  # does anyone listen? said on the pad, never a silent drive
            g.members.append(self)
            self._ticker = LoopTicker(1.0 / self.settings.rate_hz, self._tick, clock=self._ticker_clock)
            self._send()  # the first command goes out at once
            self._ticker.start()
        self._show_value()

    def _tick(self) -> None:
        g = self._group()
        if self._active and g.members and g.members[0] is self:
            self._send()
            self._show_value()

    def _on_release(self, reason: str, unlock: bool) -> bool:
        """End this pad's command: drop its axes, send the (merged) zero once. True if it was active."""
        was = self._active
        if unlock:
            self._locked = False
        self._x = self._y = 0.0
        if self._ticker is not None:
            self._ticker.stop()
            self._ticker = None
        if was:
            self._active = False
            self._reason = reason
            g = self._group()
            g.contrib.pop(self.pad_id, None)
            self._send()  # own axes now zero (others' still held if any)
            if self in g.members:
                g.members.remove(self)
        self._show_value()
        return was

    def _force_release(self, reason: str) -> bool:
        was = self._on_release(reason, unlock=False)
        if was:
            self._locked = True  # until the finger lifts
            self._show_value()
        return was

    # -- the robot's speed limit, and who listens (loop thread) ---------------------------------------------
    def _on_speed_limit(self, msg: dict[str, Any]) -> None:
        value = msg.get("data") if isinstance(msg, dict) else None
        if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value) or value < 0:
            return  # the robot ignores an invalid limit too
        self._speed_limit = float(value)
        self._show_value()

    def _ask_listeners(self, fresh: float = 0.0) -> None:
        """Ask the robot (``/rosapi/subscribers``) whether anyone subscribes to the pad's topic, unless it
        was asked less than ``fresh`` s ago. Loop thread; the answer arrives later."""
        now = self._clock()
        if now - self._listeners_asked < fresh or not self.binding.name:
            return
        self._listeners_asked = now
        try:
            loop = asyncio.get_running_loop()
        except RuntimeError:
            return  # no loop (plain tests): nothing to ask with
        task = loop.create_task(self._listeners())
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)

    async def _listeners(self) -> None:
        try:
            answer = await self.port.call_service("/rosapi/subscribers", {"topic": self.binding.name},
                                                  timeout=3.0)
        except Exception:  # an old rosapi, a link drop: nothing known, nothing said
            return
        subs = answer.get("subscribers") if isinstance(answer, dict) else None
        if not isinstance(subs, list):
            return
        unheard = "" if subs else f"nobody subscribes to {self.binding.name}: nothing moves"
        if unheard != self._unheard:
            self._unheard = unheard
            self._show_value()

    # -- lifecycle ------------------------------------------------------------------------------------
    def on_start(self) -> None:
        topic = self.settings.speed_limit_topic
        if topic:
            self._limit_sub = self.port.subscribe(topic, self._on_speed_limit, type="std_msgs/Float64")
        self._ask_listeners()

    def on_stop(self) -> None:
        self._force_release("stopped")
        self._zero_pending = False  # the group stays with the link (one small object per topic)
        if self._limit_sub is not None:
            try:
                self._limit_sub.unsubscribe()
            except Exception as exc:  # the link may be down: the server drops it with the socket
                self.set_error(f"while stopping: {exc}")
            self._limit_sub = None

    def set_link(self, up: bool) -> None:
        was_down = self.state.link_down
        super().set_link(up)
        if not up and not was_down:
            self._dispatch(self._link_lost)
        elif up and was_down:
            self._dispatch(self._link_back)

    def on_commands_held(self, reason: str | None) -> None:
        """The robot's bridge holds this link's commands behind an unanswered service call (the runtime
        says so, ``rcon_core/bridge/held.py``): the pad stops at once -- one zero, which waits behind the
        call with whatever was sent since it, so the robot ends stopped when they are let through -- and
        sends nothing more until the call is answered and the finger is lifted and put down again."""
        self._dispatch(lambda: self._held_changed(reason or ""))

    def _held_changed(self, reason: str) -> None:
        self._commands_held = reason
        if reason:
            self._force_release(reason)
        self._show_value()

    def _link_lost(self) -> None:
        if self._force_release("link down"):
            self._zero_pending = True  # the zero may not have gone out: send it again once back

    def _link_back(self) -> None:
        self._ask_listeners()
        if self._zero_pending and self.running:
            self._zero_pending = False
            g = self._group()
            if not g.members:
                self._send()

    def _show_value(self) -> None:
        """Set the value the pad's view shows (finger, command, lock); sends nothing (:meth:`_send` does)."""
        active = self._active
        cmd = self.command_for(self._x, self._y) if active else {}
        sx, sy = shape_axes(self._x, self._y, self.settings.dead_zone) if active else (0.0, 0.0)
        self.set_value(TeleopValue(active=active, x=sx, y=sy, command=tuple(sorted(cmd.items())),
                                   locked=self._locked, sent=self._sent, reason=self._reason,
                                   held=self.limits()[2], unheard=self._unheard,
                                   commands_held=self._commands_held))

    @property
    def active(self) -> bool:
        return self._active


def _deep_copy(v: Any) -> Any:
    if isinstance(v, dict):
        return {k: _deep_copy(x) for k, x in v.items()}
    if isinstance(v, list):
        return [_deep_copy(x) for x in v]
    return v
