"""The GPS map model: tracks of fixes from one or more topics, a heading, and goals to publish. No Qt.

The bound topic (role SUBSCRIBE) is the main track; ``extra_topics`` add more tracks, each subscribed
through the same port and ended in :meth:`MapModel.stop`. ``heading_topic`` optionally gives the main
track's heading; otherwise it is the course between fixes. A goal tapped on the map is published as a
``sensor_msgs/NavSatFix`` on ``goal_topic`` (role SUBSCRIBE) or on the bound topic (role PUBLISH). A long
press proposes "Navigate here": a goal to the ROS 2 action ``navigate_action`` (:mod:`.navigate`).

With ``every_robot`` (several robots in one workspace) the map shows the bound topic's fix of every
robot: the canvas runtime calls :meth:`MapModel.on_fleet` before ``start`` with a port per robot; the own
robot's fix stays the main track (named and coloured as its robot), each other robot gets a track keyed
``@<robot id>`` with its name and colour, subscribed through that robot's port.

``state.value`` is a :class:`MapValue` (immutable), rebuilt on the bridge thread at each fix.
"""

from __future__ import annotations

import collections
import functools
import math
import threading
from typing import Any

import attrs

from rcon_core.msgs import names
from rcon_core.msgs import time as rcon_time
from rcon_core.plugins import Role, WidgetModel
from rcon_core.plugins.paths import PathError, get_path, set_path

from . import mercator
from .geo import Fix, GeoError, fix_from_message, heading_from_message
from .navigate import Navigation, Navigator
from .settings import MapSettings, parse_extra_topics

NAVSATFIX = "sensor_msgs/NavSatFix"
#: marker colours: the main track first, then one per extra topic
PALETTE = ("#0050d0", "#d05a00", "#008a2e", "#c0007a", "#6a2fd0", "#8a6d00", "#007a8a", "#b00020")
#: a course heading needs the robot to have moved this far over the last COURSE_WINDOW points
COURSE_MIN_M = 2.0
COURSE_WINDOW = 60
#: a fix this far from the one before, faster than JUMP_SPEED_MS, is a jump (a robot restarted at its
#: start, a GPS re-acquired elsewhere): the trail breaks there instead of drawing a line across
JUMP_MIN_M = 50.0
JUMP_SPEED_MS = 60.0
#: no fix for this long (when the widget has no stale_after of its own) breaks the trail too
TRAIL_GAP_S = 10.0


@attrs.frozen
class Track:
    """One position source as the view paints it. ``stamp`` is on the model's clock (see ``MapModel.age``)."""

    key: str
    label: str
    colour: str
    points: tuple[tuple[float, float], ...] = ()
    #: indices into ``points`` where the trail starts again (after a jump, a gap, a lost link): the trail
    #: is drawn as :meth:`segments`, never as one line through these breaks
    breaks: tuple[int, ...] = ()
    lat: float | None = None
    lon: float | None = None
    status: int | None = None
    no_fix: bool = False
    accuracy_m: float | None = None
    heading_deg: float | None = None
    heading_source: str = ""  # "course" | "sensor" | ""
    stamp: float | None = None
    count: int = 0

    @property
    def has_position(self) -> bool:
        return self.lat is not None and self.lon is not None

    def segments(self) -> list[tuple[tuple[float, float], ...]]:
        """The trail's unbroken pieces, oldest first."""
        cuts = [0, *self.breaks, len(self.points)]
        return [self.points[a:b] for a, b in zip(cuts, cuts[1:], strict=False) if b > a]


@attrs.frozen
class Goal:
    lat: float
    lon: float
    topic: str
    stamp: float


@attrs.frozen
class MapValue:
    """Everything the map paints, at one instant."""

    tracks: tuple[Track, ...] = ()
    goal: Goal | None = None
    goals_sent: int = 0
    nav: Navigation | None = None  #: the "Navigate here" goal, while it runs and how it ended

    def track(self, key: str) -> Track | None:
        return next((t for t in self.tracks if t.key == key), None)

    @property
    def main(self) -> Track | None:
        return self.track("")


class _TrackState:
    """Mutable per-topic history (bridge thread only)."""

    def __init__(self, key: str, label: str, colour: str, trail_length: int) -> None:
        self.key, self.label, self.colour = key, label, colour
        self.points: collections.deque[tuple[float, float]] = collections.deque(maxlen=max(1, trail_length))
        #: beside each point: whether the trail starts again there
        self.starts: collections.deque[bool] = collections.deque(maxlen=max(1, trail_length))
        self.break_next = False  #: the next point starts a new piece (the link was lost)
        self.good_stamp: float | None = None  #: when ``last_good`` came
        self.keep_trail = trail_length > 0
        self.fix: Fix | None = None
        self.last_good: tuple[float, float] | None = None
        self.stamp: float | None = None
        self.count = 0
        self.sensor_heading: float | None = None
        self.sensor_stamp: float | None = None


class MapModel(WidgetModel):
    """Tracks + goals. ``state.value`` is a :class:`MapValue` (or None before anything arrived)."""

    def __init__(self, settings: MapSettings | None, binding: Any, port: Any, **kw: Any) -> None:
        settings = settings if settings is not None else MapSettings()
        super().__init__(settings, binding, port, **kw)
        self._build_lock = threading.Lock()
        self._tracks: dict[str, _TrackState] = {}
        self._extra_subs: list[Any] = []
        self._goal_pub: Any = None
        self._robot_ports: list[tuple[str, Any]] = []  # (track key, port) of the other robots
        self._own_robot: str | None = None  # the robot id of this widget's own port (on_fleet)
        self._goal: Goal | None = None
        self._goals_sent = 0
        self.navigator = Navigator(settings, port, self.types, self._dispatch, self._replace_value, self.set_error)
        if binding.role is Role.SUBSCRIBE:
            self._tracks[""] = _TrackState("", binding.name or "robot", PALETTE[0], settings.trail_length)
        try:
            extras = parse_extra_topics(settings.extra_topics)
        except ValueError:
            extras = []  # shown by problems(); the main track still works
        for i, (label, topic) in enumerate(extras, start=1):
            self._tracks[topic] = _TrackState(topic, label, PALETTE[i % len(PALETTE)], settings.trail_length)

    # -- lifecycle (bridge thread) -------------------------------------------------------------------
    def on_fleet(self, robots: list[Any]) -> None:
        """The workspace's robots (``RobotPort``: id, name, colour, port), before ``start``. With
        ``every_robot`` each other robot's fix becomes a track of its own, in its colour."""
        self._robot_ports = []
        self.shows_every_robot = False
        for key in [k for k in self._tracks if k.startswith("@")]:
            del self._tracks[key]
        if not self.settings.every_robot or self.binding.role is not Role.SUBSCRIBE:
            return
        self.shows_every_robot = True  # the frame on a mixed canvas names no single robot
        trail = self.settings.trail_length
        for robot in robots:
            if robot.port is self.port:
                self._own_robot = robot.id
                main = self._tracks.get("")
                if main is not None:
                    main.label, main.colour = robot.name, robot.colour
                continue
            key = f"@{robot.id}"
            self._tracks[key] = _TrackState(key, robot.name, robot.colour, trail)
            self._robot_ports.append((key, robot.port))

    def on_start(self) -> None:
        s = self.settings
        try:
            for key, port in self._robot_ports:
                self._extra_subs.append(port.subscribe(
                    self.binding.name, functools.partial(self._guard, self._on_robot, key), type=self.binding.type))
            for key in self._tracks:
                if key and not key.startswith("@"):
                    self._extra_subs.append(
                        self.port.subscribe(key, functools.partial(self._guard, self._on_extra, key), type=NAVSATFIX)
                    )
            if s.heading_topic.strip():
                self._extra_subs.append(
                    self.port.subscribe(s.heading_topic.strip(), functools.partial(self._guard, self._on_heading),
                                        type=s.heading_type)
                )
            if self.binding.role is Role.SUBSCRIBE and s.goal_topic.strip():
                self._goal_pub = self.port.advertise(s.goal_topic.strip(), NAVSATFIX)
        except Exception as exc:  # the link may be down: the main track still shows what it can
            self.set_error(f"map: {exc}")

    def on_stop(self) -> None:
        self.navigator.stop()
        handles = [(sub, "unsubscribe") for sub in self._extra_subs]
        if self._goal_pub is not None:
            handles.append((self._goal_pub, "unadvertise"))
        for handle, method in handles:
            try:
                getattr(handle, method)()
            except Exception as exc:
                self.set_error(f"while stopping: {exc}")
        self._extra_subs = []
        self._goal_pub = None

    def _guard(self, fn: Any, *args: Any) -> None:
        try:
            fn(*args)
        except Exception as exc:  # a bad message must not break the bridge's callback loop
            self.set_error(f"{type(exc).__name__}: {exc}")

    # -- incoming (bridge thread) --------------------------------------------------------------------
    def on_message(self, msg: dict[str, Any]) -> None:
        path = self.binding.field_path
        try:
            geo = get_path(msg, path) if path else msg
            fix = fix_from_message(geo)
        except (PathError, GeoError) as exc:
            self.set_error(str(exc))
            return
        self._record("", fix)
        self.set_value(self._snapshot(), message=msg)

    def _on_extra(self, key: str, msg: dict[str, Any]) -> None:
        try:
            fix = fix_from_message(msg)
        except GeoError as exc:
            self.set_error(f"{key}: {exc}")
            return
        self._record(key, fix)
        self._replace_value()

    def _on_robot(self, key: str, msg: dict[str, Any]) -> None:
        """Another robot's fix on the bound topic (``every_robot``)."""
        path = self.binding.field_path
        try:
            fix = fix_from_message(get_path(msg, path) if path else msg)
        except (PathError, GeoError) as exc:
            self.set_error(f"{self._tracks[key].label}: {exc}")
            return
        self._record(key, fix)
        self._replace_value()

    def _on_heading(self, msg: dict[str, Any]) -> None:
        heading = heading_from_message(msg, self.settings.heading_type)
        main = self._tracks.get("")
        if heading is None or main is None:
            return
        with self._build_lock:
            main.sensor_heading, main.sensor_stamp = heading, self._clock()
        self._replace_value()

    def _record(self, key: str, fix: Fix) -> None:
        with self._build_lock:
            self._record_locked(self._tracks[key], fix)

    def _record_locked(self, t: _TrackState, fix: Fix) -> None:
        now = self._clock()
        t.fix, t.stamp = fix, now
        t.count += 1
        if fix.has_fix:
            assert fix.lat is not None and fix.lon is not None
            broken = t.break_next or self._jumped(t, fix.lat, fix.lon, now)
            t.last_good, t.good_stamp = (fix.lat, fix.lon), now
            if t.keep_trail:
                spacing = self.settings.trail_spacing_m
                last = t.points[-1] if t.points else None
                if broken or last is None or mercator.haversine_m(last[0], last[1], fix.lat, fix.lon) >= spacing:
                    t.points.append((fix.lat, fix.lon))
                    t.starts.append(broken)
                    t.break_next = False

    def _jumped(self, t: _TrackState, lat: float, lon: float, now: float) -> bool:
        """Whether a fix at ``lat``/``lon`` cannot follow the last one by moving: too far too fast (a robot
        restarted at its start), or after too long a silence."""
        if t.last_good is None or t.good_stamp is None:
            return False
        dt = max(0.0, now - t.good_stamp)
        gap = self.stale_after_s if math.isfinite(self.stale_after_s) else TRAIL_GAP_S
        if dt > gap:
            return True
        metres = mercator.haversine_m(t.last_good[0], t.last_good[1], lat, lon)
        return metres > JUMP_MIN_M and metres > JUMP_SPEED_MS * dt

    # -- link state (bridge thread) ------------------------------------------------------------------
    def set_link(self, up: bool) -> None:
        """The own robot's link: lost, its trails (the bound topic's, the extra topics') break there."""
        if not up:
            self._break_trails(lambda key: not key.startswith("@"))
        super().set_link(up)

    def on_robot_link(self, robot_id: str, up: bool) -> None:
        """Another robot's link (``every_robot``): lost, its trail breaks there."""
        if not up and robot_id != self._own_robot:
            self._break_trails(lambda key: key == f"@{robot_id}")

    def _break_trails(self, which: Any) -> None:
        with self._build_lock:
            for key, t in self._tracks.items():
                if which(key) and t.points:
                    t.break_next = True

    def _replace_value(self) -> None:
        """A new snapshot without counting it as a value of the bound topic (its age stays the main one's)."""
        self.replace_value(self._snapshot())

    # -- snapshots -----------------------------------------------------------------------------------
    def _course(self, t: _TrackState) -> float | None:
        if not t.points or t.last_good is None:
            return None
        lat, lon = t.last_good
        starts = list(t.starts)
        for i, (plat, plon) in enumerate(reversed(t.points)):
            if i >= COURSE_WINDOW or (i > 0 and starts[-i]):  # never across a break
                break
            if mercator.haversine_m(plat, plon, lat, lon) >= COURSE_MIN_M:
                return mercator.bearing_deg(plat, plon, lat, lon)
        return None

    def _snapshot(self) -> MapValue:
        now = self._clock()
        with self._build_lock:
            tracks = []
            for t in self._tracks.values():
                heading, source = None, ""
                fresh = t.sensor_stamp is not None and now - t.sensor_stamp <= self.stale_after_s
                if t.sensor_heading is not None and fresh:
                    heading, source = t.sensor_heading, "sensor"
                else:
                    heading = self._course(t)
                    source = "course" if heading is not None else ""
                fix = t.fix
                tracks.append(Track(
                    key=t.key, label=t.label, colour=t.colour, points=tuple(t.points),
                    breaks=tuple(i for i, start in enumerate(t.starts) if start and i > 0),
                    lat=t.last_good[0] if t.last_good else None, lon=t.last_good[1] if t.last_good else None,
                    status=fix.status if fix else None, no_fix=bool(fix and not fix.has_fix),
                    accuracy_m=fix.accuracy_m if fix and fix.has_fix else None,
                    heading_deg=heading, heading_source=source, stamp=t.stamp, count=t.count,
                ))
            return MapValue(tracks=tuple(tracks), goal=self._goal, goals_sent=self._goals_sent,
                            nav=self.navigator.state)

    @property
    def stale_after_s(self) -> float:
        return float(self.stale_after) if self.stale_after is not None else math.inf

    def now(self) -> float:
        """The model's clock (what ``Track.stamp`` is measured on)."""
        return self._clock()

    def age(self, track: Track, now: float | None = None) -> float | None:
        """Seconds since the track's last message (fix or no-fix), None if none came."""
        if track.stamp is None:
            return None
        return max(0.0, (self._clock() if now is None else now) - track.stamp)

    def is_stale(self, track: Track, now: float | None = None) -> bool:
        age = self.age(track, now)
        return age is None or age > self.stale_after_s

    # -- goals (any thread) ---------------------------------------------------------------------------
    @property
    def goal_topic(self) -> str:
        """Where goals go: the bound topic when publishing, else ``settings.goal_topic`` ('' = none)."""
        if self.binding.role is Role.PUBLISH:
            return self.binding.name
        return self.settings.goal_topic.strip()

    def goal_message(self, lat: float, lon: float) -> dict[str, Any]:
        """The message published for a goal at ``lat``/``lon``: a NavSatFix stamped now (frame ``map``,
        status FIX, covariance unknown), or, on a bound non-NavSatFix type, its default with the geo field set."""
        if not (-90.0 <= lat <= 90.0 and -180.0 <= lon <= 180.0):
            raise ValueError(f"goal ({lat}, {lon}) is not a valid latitude/longitude")
        publishing = self.binding.role is Role.PUBLISH
        type_name = self.binding.type if publishing else NAVSATFIX
        path = self.binding.field_path if publishing else ""
        base: dict[str, Any] = self.types.default(type_name)
        ros2 = self.types.ros2
        geo = get_path(base, path) if path else base
        geo = dict(geo) if isinstance(geo, dict) else {}
        geo.update(latitude=float(lat), longitude=float(lon))
        if names.normalize(type_name) == names.normalize(NAVSATFIX):
            header: dict[str, Any] = {"stamp": rcon_time.now(ros2), "frame_id": "map"}
            if not ros2:
                header = {"seq": 0, **header}
            geo.update(
                header=header,
                status={"status": 0, "service": 1},  # STATUS_FIX, SERVICE_GPS
                altitude=0.0,
                position_covariance=[0.0] * 9,
                position_covariance_type=0,  # COVARIANCE_TYPE_UNKNOWN
            )
        return set_path(base, path, geo) if path else geo

    def send_goal(self, lat: float, lon: float) -> bool:
        """Publish a goal at ``lat``/``lon`` (after the operator confirmed it). False + error if impossible."""
        topic = self.goal_topic
        if not topic:
            self.set_error("no goal topic set: choose one in the map's settings")
            return False
        try:
            msg = self.goal_message(lat, lon)
        except (ValueError, PathError) as exc:
            self.set_error(str(exc))
            return False
        if self.binding.role is Role.PUBLISH:
            if not self.publish(msg):
                return False
        else:
            pub = self._goal_pub
            if pub is None:
                self.set_error("not publishing goals: the map is not running")
                return False
            self._dispatch(lambda: pub.publish(msg))
        with self._build_lock:
            self._goal = Goal(float(lat), float(lon), topic, self._clock())
            self._goals_sent += 1
        self._replace_value()
        return True

    def navigate(self, lat: float, lon: float) -> bool:
        """Send a goal to ``settings.navigate_action`` to go to ``lat``/``lon`` (after the operator confirmed)."""
        return self.navigator.start(lat, lon)

    def cancel_navigation(self) -> None:
        self.navigator.cancel()

    def clear_trails(self) -> None:
        """Forget the trails (keeps the last positions)."""
        def go() -> None:
            with self._build_lock:
                for t in self._tracks.values():
                    t.points.clear()
                    t.starts.clear()
            self._replace_value()
        self._dispatch(go)
