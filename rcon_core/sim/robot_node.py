"""The robot's ROS node inside the sim: its topics, services and /rosout lines, on a schedule.

Sensor messages are built only while someone subscribes (the cameras especially), and a sensor nobody
subscribes to does not even wake the loop, so an idle sim costs almost nothing. All publish rates are
multiplied by the server's ``rate_scale``.

Camera frames are drawn (and JPEG-encoded, and given their base64 text when a JSON subscriber is there) in a
worker thread from a copy of the vessel's pose, then published from the loop: the loop never waits on a
picture, so commands (``cmd_vel``) are taken as they arrive, as on a real robot whose camera drivers are not
its rosbridge. A camera whose previous frame is still being drawn skips its turn (frames are dropped, never
queued).
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import contextlib
import copy
import logging
import math
import random
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from rcon_core.priority import lower_this_thread

from . import world
from .camera import CameraRenderer
from .commands import StampedCommands
from .encoding import Base64Bytes
from .identity import Identity
from .rosapi import add_logger_services
from .vessel import Vessel
from .video import FrontVideo

if TYPE_CHECKING:
    from .server import SimServer

log = logging.getLogger(__name__)

NODE = "/kingfisher"  # the unnamed sim's node; a named one is /NAME/kingfisher (identity.py)
PHYSICS_HZ = 50.0

#: topic (before the namespace) -> base rate in Hz (scaled by rate_scale)
RATES: dict[str, float] = {
    "/odom": 20.0,
    "/gps/fix": 5.0,
    "/imu/data": 100.0,
    "/imu/mag": 25.0,
    "/camera/front/image_raw": 10.0,
    "/camera/rear/image_raw/compressed": 12.0,
    "/scan": 10.0,
    "/battery": 1.0,
    "/depth": 5.0,
}

# the Earth's field in Toronto, Tesla, ENU (declination about -10.5 deg, inclination about 71 deg)
_MAG_E, _MAG_N, _MAG_U = -3.17e-6, 17.1e-6, -51.4e-6


def f32(value: float) -> float:
    """A float32 value widened to double, as rosbridge sends float32 fields."""
    return float(np.float32(value))


def _diag(values: list[float], n: int) -> list[float]:
    out = [0.0] * (n * n)
    for i, v in enumerate(values):
        out[i * n + i] = v
    return out


@dataclass
class _Periodic:
    topic: str
    period: float
    fn: Callable[[float], None]
    next_due: float = 0.0


class RobotNode:
    """Publishes the vessel's sensors and takes its commands.

    Topic names in this class are written without the namespace (``/cmd_vel``); ``self.ns`` maps them to
    the graph's names (``/boat2/cmd_vel`` for a named vessel, see identity.py).
    """

    def __init__(self, server: SimServer, vessel: Vessel | None = None, identity: Identity | None = None) -> None:
        self.server = server
        self.identity = identity = identity or Identity()
        if vessel is None:
            lat, lon = identity.origin
            vessel = Vessel(origin_lat=lat, origin_lon=lon)
        self.vessel = vessel
        self.node = identity.node
        self.ns = identity.topic
        self.fl = server.flavour
        self.rng = random.Random(7 + identity.index)
        self.lidar = world.Lidar()
        bow = (identity.hull, identity.label) if identity.hull is not None else None
        self.front = CameraRenderer("front", sky=identity.sky, bow=bow, vessel_name=identity.name)
        self.rear = CameraRenderer("rear", yaw_offset=math.pi, sky=identity.sky, vessel_name=identity.name)
        self.published_counts: dict[str, int] = {}
        self._task: asyncio.Task[None] | None = None
        self._render_pool: concurrent.futures.ThreadPoolExecutor | None = None
        self._rendering: set[str] = set()  # cameras with a frame being drawn
        self._last_physics = time.monotonic()
        self._cmd_logged_at = float("-inf")
        self._idle = True
        m, s = self.fl.msg, self.fl.srv
        self.types = {
            "/odom": m("nav_msgs", "Odometry"),
            "/gps/fix": m("sensor_msgs", "NavSatFix"),
            "/imu/data": m("sensor_msgs", "Imu"),
            "/imu/mag": m("sensor_msgs", "MagneticField"),
            "/camera/front/image_raw": m("sensor_msgs", "Image"),
            "/camera/rear/image_raw/compressed": m("sensor_msgs", "CompressedImage"),
            "/scan": m("sensor_msgs", "LaserScan"),
            "/battery": m("sensor_msgs", "BatteryState"),
            "/depth": m("sensor_msgs", "Range"),
            "/map": m("nav_msgs", "OccupancyGrid"),
            "/lights/state": m("std_msgs", "Bool"),
        }
        for topic, type_name in self.types.items():
            server.advertise_internal(self.ns(topic) if topic != "/map" else topic, type_name, self.node,
                                      latched=topic in ("/map", "/lights/state"))
        ns, node = self.ns, self.node
        server.subscribe_internal(ns("/cmd_vel"), m("geometry_msgs", "Twist"), node, self._on_cmd_vel)
        #: TwistStamped commands older than cmd_max_age are dropped, the watchdog runs from the stamp
        self.stamped = StampedCommands(self.vessel.params.watchdog_s, lambda text: server.log(
            self.node, "warn", text, function="cmd_vel_stamped"))
        server.subscribe_internal(ns("/cmd_vel_stamped"), m("geometry_msgs", "TwistStamped"), node,
                                  self._on_cmd_vel_stamped)
        server.subscribe_internal(ns("/speed_limit"), m("std_msgs", "Float64"), node, self._on_speed_limit)
        # and holds the limit it took, latched (ROS 1 latched, ROS 2 transient local): a pad started later
        # hears it at once, as the last value rosbridge keeps for a new subscriber
        server.advertise_internal(ns("/speed_limit"), m("std_msgs", "Float64"), node, latched=True)
        self._echo = False
        server.add_service(ns("/reset_pose"), s("std_srvs", "Empty"), node, self._srv_reset_pose)
        server.add_service(ns("/lights/set"), s("std_srvs", "SetBool"), node, self._srv_lights)
        server.add_service(ns("/dock"), s("std_srvs", "Trigger"), node, self._srv_dock)
        if server.rosapi is not None:
            add_logger_services(server, server.rosapi, node)
        p = self.vessel.params
        server.params_tree.set(node, {
            "max_speed": p.max_surge, "max_yaw_rate": p.max_yaw_rate, "watchdog_timeout": p.watchdog_s,
            "cmd_max_age": self.stamped.max_age,
            "battery_capacity_ah": p.capacity_ah, "frame_id": "base_link",
            "gps": {"origin_lat": self.vessel.origin_lat, "origin_lon": self.vessel.origin_lon},
        })
        scale = server.rate_scale
        self._periodic = [_Periodic(t, 1.0 / (hz * scale), getattr(self, "_pub_" + t.strip("/").replace("/", "_")))
                          for t, hz in RATES.items()]
        #: the front camera as H.264 video (video.py; no topics without PyAV)
        self.video = FrontVideo(self)
        self._periodic += [_Periodic(t, 1.0 / (hz * scale), fn) for t, hz, fn in self.video.periodic()]

    # -- lifecycle ----------------------------------------------------------------------------------

    def start(self) -> None:
        self._publish_map()
        self._publish_lights()
        self.server.log(self.node, "info",
                        f"Kingfisher simulator up: thrusters armed, waiting for {self.ns('/cmd_vel')}",
                        function="start")
        self._task = asyncio.get_running_loop().create_task(self._run(), name="sim-robot")

    async def stop(self) -> None:
        if self._task is not None:
            self._task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._task
            self._task = None
        if self._render_pool is not None:
            self._render_pool.shutdown(wait=False, cancel_futures=True)
            self._render_pool = None

    async def _run(self) -> None:
        now = time.monotonic()
        physics = _Periodic("", 1.0 / PHYSICS_HZ, self._physics, now)
        for i, e in enumerate(self._periodic):
            e.next_due = now + (i * 0.0037) % e.period  # spread the first publications
        graph = {e.topic: self.graph_name(e.topic) for e in self._periodic}
        has_subscribers = self.server.has_subscribers
        while True:
            # a sensor nobody subscribes to does not wake the loop: the physics tick (every 20 ms) looks
            # again, and a sensor wanted after a pause publishes at once, then at its rate
            active = [physics, *(e for e in self._periodic if has_subscribers(graph[e.topic]))]
            due = min(e.next_due for e in active)
            delay = due - time.monotonic()
            if delay > 0:
                await asyncio.sleep(delay)
            now = time.monotonic()
            for e in active:
                if e.next_due <= now:
                    e.next_due += e.period
                    if e.next_due < now:  # fell behind: skip, never burst
                        e.next_due = now + e.period
                    try:
                        e.fn(now)
                    except Exception:  # noqa: BLE001 - a sensor bug must not stop the robot
                        log.exception("publishing %s failed", e.topic or "physics")

    def graph_name(self, topic: str) -> str:
        """The graph's name of one of the robot's topics (``/map`` is shared, never namespaced)."""
        return topic if topic == "/map" else self.ns(topic)

    def _publish(self, topic: str, msg: dict[str, Any]) -> None:
        self.published_counts[topic] = self.published_counts.get(topic, 0) + 1
        self.server.publish(self.graph_name(topic), msg, self.node)

    # -- physics and events -------------------------------------------------------------------------

    def _physics(self, now: float) -> None:
        dt = min(0.2, now - self._last_physics)
        self._last_physics = now
        v = self.vessel
        for event in v.step(dt, now):
            if event == "watchdog":
                self.server.log(self.node, "warn", f"No /cmd_vel for {v.params.watchdog_s:.1f} s: watchdog stopped "
                                "the thrusters", function="watchdog")
                self._idle = True
            elif event == "battery_low":
                self.server.log(self.node, "warn", f"Battery low: {v.battery_fraction * 100:.0f}% "
                                f"({v.voltage:.1f} V); return to dock", function="battery")
            elif event == "docked":
                self.server.log(self.node, "info", f"Docked; charging at {v.current:.1f} A", function="dock")

    def _on_cmd_vel_stamped(self, msg: dict[str, Any]) -> None:
        limit = self.server.params_tree.get(f"{self.node}/cmd_max_age")  # a client may set it (rosapi)
        if isinstance(limit, int | float) and not isinstance(limit, bool) and limit > 0:
            self.stamped.max_age = float(limit)
        made = self.stamped.judge(msg, self.ns("/cmd_vel_stamped"))
        if made is not None:
            self._on_cmd_vel(msg.get("twist") or {}, made)

    def _on_cmd_vel(self, msg: dict[str, Any], made: float | None = None) -> None:
        """A velocity command; ``made``: when (monotonic) a stamped one was made, the watchdog's start."""
        linear = msg.get("linear") or {}
        angular = msg.get("angular") or {}
        surge = float(linear.get("x", 0.0) or 0.0)
        yaw_rate = float(angular.get("z", 0.0) or 0.0)
        now = time.monotonic()
        was_docking = self.vessel.docking
        self.vessel.command(surge, yaw_rate, now if made is None else made)
        if was_docking:
            self.server.log(self.node, "warn", "Docking cancelled by a /cmd_vel command", function="cmd_vel")
        if self._idle or now - self._cmd_logged_at > 10.0:
            self._idle = False
            self._cmd_logged_at = now
            self.server.log(self.node, "info", f"cmd_vel received: surge {self.vessel.cmd_surge:.2f} m/s, yaw rate "
                            f"{self.vessel.cmd_yaw_rate:.2f} rad/s", function="cmd_vel")

    def _on_speed_limit(self, msg: dict[str, Any]) -> None:
        if self._echo:  # our own latched copy of the limit, coming back through our subscription
            return
        value = msg.get("data")
        if not isinstance(value, int | float) or not math.isfinite(value) or value < 0:
            self.server.log(self.node, "error", f"Ignoring invalid speed limit {value!r}", function="speed_limit")
            return
        self.vessel.speed_limit = float(value)
        self.server.log(self.node, "info", f"Speed limit set to {value:.2f} m/s", function="speed_limit")
        self._echo = True
        try:
            self._publish("/speed_limit", {"data": float(value)})
        finally:
            self._echo = False

    # -- services -----------------------------------------------------------------------------------

    def _srv_reset_pose(self, req: dict[str, Any]) -> dict[str, Any]:
        self.vessel.reset_pose()
        self.server.log(self.node, "info", "Pose reset to the origin", function="reset_pose")
        return {}

    def _srv_lights(self, req: dict[str, Any]) -> dict[str, Any]:
        on = bool(req.get("data", False))
        changed = on != self.vessel.lights
        self.vessel.lights = on
        if changed:
            self._publish_lights()
            self.server.log(self.node, "info", f"Lights {'on' if on else 'off'}", function="lights")
        return {"success": True, "message": f"lights {'on' if on else 'off'}"}

    def _srv_dock(self, req: dict[str, Any]) -> dict[str, Any]:
        v = self.vessel
        if v.docked:
            return {"success": False, "message": "already docked"}
        if v.dock_distance < 1.5:
            v.docked = True
            v.docking = False
            self.server.log(self.node, "info", "Docked; charging", function="dock")
            return {"success": True, "message": "docked"}
        v.docking = True
        v.watchdog_tripped = False
        self.server.log(self.node, "info", f"Docking started: {v.dock_distance:.1f} m to the dock", function="dock")
        return {"success": True, "message": f"docking started, {v.dock_distance:.1f} m to go"}

    # -- latched topics -----------------------------------------------------------------------------

    def _publish_lights(self) -> None:
        self._publish("/lights/state", {"data": self.vessel.lights})

    def _publish_map(self) -> None:
        resolution = 0.5
        data, width, height = world.occupancy_grid(resolution=resolution)
        stamp = time.time()
        info = {
            "map_load_time": self.fl.time(stamp),
            "resolution": f32(resolution),
            "width": width,
            "height": height,
            "origin": {"position": {"x": -40.0, "y": -50.0, "z": 0.0},
                       "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}},
        }
        self._publish("/map", {"header": self.fl.header("map", stamp), "info": info, "data": data})

    # -- periodic publishers ------------------------------------------------------------------------

    def _wanted(self, topic: str) -> bool:
        return self.server.has_subscribers(self.graph_name(topic))

    def _pub_odom(self, now: float) -> None:
        if not self._wanted("/odom"):
            return
        v = self.vessel
        qx, qy, qz, qw = v.quaternion()
        pose_cov = _diag([0.05, 0.05, 1e3, 1e3, 1e3, 0.02], 6)
        twist_cov = _diag([0.01, 0.01, 1e3, 1e3, 1e3, 0.01], 6)
        self._publish("/odom", {
            "header": self.fl.header("odom"),
            "child_frame_id": "base_link",
            "pose": {"pose": {"position": {"x": v.x, "y": v.y, "z": 0.0},
                              "orientation": {"x": qx, "y": qy, "z": qz, "w": qw}},
                     "covariance": np.array(pose_cov)},
            "twist": {"twist": {"linear": {"x": v.surge, "y": 0.0, "z": 0.0},
                                "angular": {"x": 0.0, "y": 0.0, "z": v.yaw_rate}},
                      "covariance": np.array(twist_cov)},
        })

    def _pub_gps_fix(self, now: float) -> None:
        if self._wanted("/gps/fix"):
            self._publish("/gps/fix", self.fix_message())

    def fix_message(self) -> dict[str, Any]:
        """A sensor_msgs/NavSatFix of the vessel's position now, with GPS noise."""
        v = self.vessel
        sigma = 0.6
        lat, lon = v.lat_lon()
        lat += math.degrees(self.rng.gauss(0, sigma) / 6_378_137.0)
        lon += math.degrees(self.rng.gauss(0, sigma) / (6_378_137.0 * math.cos(math.radians(v.origin_lat))))
        return {
            "header": self.fl.header("gps"),
            "status": {"status": 0, "service": 1},
            "latitude": lat,
            "longitude": lon,
            "altitude": 74.6 + self.rng.gauss(0, 0.8),
            "position_covariance": np.array(_diag([sigma**2, sigma**2, 1.5**2], 3)),
            "position_covariance_type": 2,
        }

    def _pub_imu_data(self, now: float) -> None:
        if not self._wanted("/imu/data"):
            return
        v = self.vessel
        g = self.rng.gauss
        qx, qy, qz, qw = v.quaternion()
        self._publish("/imu/data", {
            "header": self.fl.header("imu_link"),
            "orientation": {"x": qx, "y": qy, "z": qz, "w": qw},
            "orientation_covariance": np.array(_diag([0.0004, 0.0004, 0.0025], 3)),
            "angular_velocity": {"x": g(0, 0.002) + 0.04 * math.cos(1.3 * v.time_s),
                                 "y": g(0, 0.002) + 0.018 * math.cos(0.9 * v.time_s + 0.5),
                                 "z": v.yaw_rate + g(0, 0.002)},
            "angular_velocity_covariance": np.array(_diag([4e-6, 4e-6, 4e-6], 3)),
            "linear_acceleration": {"x": v.surge_accel + g(0, 0.02), "y": v.surge * v.yaw_rate + g(0, 0.02),
                                    "z": 9.80665 + 0.15 * math.sin(1.7 * v.time_s) + g(0, 0.02)},
            "linear_acceleration_covariance": np.array(_diag([4e-4, 4e-4, 4e-4], 3)),
        })

    def _pub_imu_mag(self, now: float) -> None:
        if not self._wanted("/imu/mag"):
            return
        yaw = self.vessel.yaw
        g = self.rng.gauss
        bx = math.cos(yaw) * _MAG_E + math.sin(yaw) * _MAG_N
        by = -math.sin(yaw) * _MAG_E + math.cos(yaw) * _MAG_N
        self._publish("/imu/mag", {
            "header": self.fl.header("imu_link"),
            "magnetic_field": {"x": bx + g(0, 2e-7), "y": by + g(0, 2e-7), "z": _MAG_U + g(0, 2e-7)},
            "magnetic_field_covariance": np.array(_diag([4e-14, 4e-14, 4e-14], 3)),
        })

    def _pub_camera_front_image_raw(self, now: float) -> None:
        if self._wanted("/camera/front/image_raw"):
            self._render("/camera/front/image_raw", self.front, self._raw_image)

    def _pub_camera_rear_image_raw_compressed(self, now: float) -> None:
        if self._wanted("/camera/rear/image_raw/compressed"):
            self._render("/camera/rear/image_raw/compressed", self.rear, self._jpeg_image)

    def _raw_image(self, img: np.ndarray, stamp: float, text: bool) -> dict[str, Any]:
        h, w = img.shape[:2]
        return {"header": self.fl.header("camera_front_optical", stamp),
                "height": h, "width": w, "encoding": "rgb8", "is_bigendian": 0, "step": w * 3,
                "data": Base64Bytes.of(img) if text else img.tobytes()}

    def _jpeg_image(self, img: np.ndarray, stamp: float, text: bool) -> dict[str, Any]:
        data = self.rear.jpeg(img)
        return {"header": self.fl.header("camera_rear_optical", stamp), "format": "jpeg",
                "data": Base64Bytes.of(data) if text else data}

    def _render(self, topic: str, camera: CameraRenderer,
                build: Callable[[np.ndarray, float, bool], dict[str, Any] | None]) -> None:
        """Draw one frame of ``camera`` in the worker thread, then publish it on ``topic`` from the loop.

        The worker also makes the pixels' base64 text when a JSON subscriber is there now (``text``); the
        loop then only encodes the rest of the message, for every compression (encoding.py)."""
        if topic in self._rendering:
            return  # the previous frame is still being drawn: skip this one, never queue
        if self._render_pool is None:
            # below the loop that receives commands (rcon_core/priority.py)
            self._render_pool = concurrent.futures.ThreadPoolExecutor(2, thread_name_prefix="sim-camera",
                                                                      initializer=lower_this_thread)
        stamp = time.time()
        pose = copy.copy(self.vessel)  # the loop goes on moving the vessel while the frame is drawn
        loop = asyncio.get_running_loop()
        self._rendering.add(topic)
        text = self.server.wants_text(self.graph_name(topic))
        future = self._render_pool.submit(lambda: camera.render(pose, stamp, lambda img: build(img, stamp, text)))

        def done(fut: concurrent.futures.Future[dict[str, Any] | None]) -> None:
            with contextlib.suppress(RuntimeError):  # the loop is closed: the sim has stopped
                loop.call_soon_threadsafe(self._rendered, topic, fut)

        future.add_done_callback(done)

    def _rendered(self, topic: str, future: concurrent.futures.Future[dict[str, Any] | None]) -> None:
        self._rendering.discard(topic)
        if self._task is None or future.cancelled():
            return  # stopped meanwhile
        exc = future.exception()
        if exc is not None:
            log.error("drawing %s failed: %s", topic, exc)
            return
        msg = future.result()
        if msg is not None:  # None: nothing to send this turn (a video encoder held the frame back)
            self._publish(topic, msg)

    def _pub_scan(self, now: float) -> None:
        if not self._wanted("/scan"):
            return
        v = self.vessel
        ranges = self.lidar.scan(v.x, v.y, v.yaw)
        noise = np.asarray([self.rng.gauss(0, 0.01) for _ in range(8)], dtype=np.float32)
        ranges = ranges + np.resize(noise, ranges.shape)
        lid = self.lidar
        self._publish("/scan", {
            "header": self.fl.header("laser"),
            "angle_min": f32(lid.angle_min),
            "angle_max": f32(lid.angle_max),
            "angle_increment": f32(lid.angle_increment),
            "time_increment": f32(0.1 / lid.rays),
            "scan_time": f32(0.1),
            "range_min": f32(lid.range_min),
            "range_max": f32(lid.range_max),
            "ranges": ranges.astype(np.float32),
            "intensities": np.where(np.isfinite(ranges), 100.0, 0.0).astype(np.float32),
        })

    def _pub_battery(self, now: float) -> None:
        if not self._wanted("/battery"):
            return
        v = self.vessel
        cells = v.params.cells
        cell = v.voltage / cells
        status = 1 if v.docked and v.battery_fraction < 0.999 else (4 if v.docked else 2)
        self._publish("/battery", {
            "header": self.fl.header("battery"),
            "voltage": f32(v.voltage),
            "temperature": f32(24.5 + 0.3 * abs(v.current) / 10),
            "current": f32(v.current),
            "charge": f32(v.battery_charge),
            "capacity": f32(v.params.capacity_ah),
            "design_capacity": f32(v.params.capacity_ah),
            "percentage": f32(v.battery_fraction),
            "power_supply_status": status,
            "power_supply_health": 1,
            "power_supply_technology": 3,
            "present": True,
            "cell_voltage": np.array([cell + 0.005 * ((i * 7) % 3 - 1) for i in range(cells)], dtype=np.float32),
            "cell_temperature": np.full(cells, 24.5, dtype=np.float32),
            "location": "hull",
            "serial_number": "KF-BAT-0142",
        })

    def _pub_depth(self, now: float) -> None:
        if not self._wanted("/depth"):
            return
        v = self.vessel
        depth = world.depth_at(v.x, v.y) + self.rng.gauss(0, 0.03)
        self._publish("/depth", {
            "header": self.fl.header("sonar"),
            "radiation_type": 0,  # ULTRASOUND
            "field_of_view": f32(0.26),
            "min_range": f32(0.3),
            "max_range": f32(50.0),
            "range": f32(depth),
        })
