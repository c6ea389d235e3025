"""The vessel model: a small twin-hull surface vessel (Kingfisher-like), pure Python, no I/O.

Planar motion in a local ENU frame (x east, y north, yaw counter-clockwise from east, REP 103). Surge
speed and yaw rate follow the command with first-order lags plus quadratic drag; a watchdog zeroes the
command when no command arrived for ``watchdog_s``. The battery drains with a hotel load plus the power
the thrusters draw, and charges while docked.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

EARTH_RADIUS_M = 6_378_137.0


@dataclass
class VesselParams:
    max_surge: float = 2.0  # m/s, the hull's top speed
    max_reverse: float = 0.8  # m/s
    max_yaw_rate: float = 1.2  # rad/s
    tau_surge: float = 1.6  # s, first-order surge response
    tau_yaw: float = 0.5  # s, first-order yaw response
    drag: float = 0.08  # 1/m, quadratic drag coefficient
    watchdog_s: float = 0.5
    capacity_ah: float = 20.0
    hotel_a: float = 1.2  # electronics
    thrust_a_per_ms: float = 9.0  # extra current per m/s of speed
    charge_a: float = 8.0
    cells: int = 6


@dataclass
class Vessel:
    """Pose, velocity, battery and equipment state of the simulated vessel."""

    params: VesselParams = field(default_factory=VesselParams)
    #: local ENU origin on the water (Toronto Inner Harbour)
    origin_lat: float = 43.6385
    origin_lon: float = -79.3790
    x: float = 0.0
    y: float = 0.0
    yaw: float = math.radians(30.0)
    surge: float = 0.0  # m/s
    yaw_rate: float = 0.0  # rad/s
    surge_accel: float = 0.0  # m/s^2, from the last step
    cmd_surge: float = 0.0
    cmd_yaw_rate: float = 0.0
    last_cmd_time: float = float("-inf")
    speed_limit: float | None = None
    lights: bool = False
    battery_charge: float = 17.0  # Ah
    current: float = 0.0  # A, negative while discharging (BatteryState convention)
    docked: bool = False
    docking: bool = False
    dock_x: float = 0.0
    dock_y: float = 0.0
    watchdog_tripped: bool = True
    distance_m: float = 0.0
    time_s: float = 0.0
    _roll: float = 0.0
    _pitch: float = 0.0

    # -- commands -----------------------------------------------------------------------------------

    def command(self, surge: float, yaw_rate: float, now: float) -> None:
        """A velocity command (from /cmd_vel): clamped to the hull's limits and the speed limit."""
        if not (math.isfinite(surge) and math.isfinite(yaw_rate)):
            return
        top = self.params.max_surge if self.speed_limit is None else min(self.params.max_surge, self.speed_limit)
        self.cmd_surge = max(-min(self.params.max_reverse, top), min(top, surge))
        self.cmd_yaw_rate = max(-self.params.max_yaw_rate, min(self.params.max_yaw_rate, yaw_rate))
        self.last_cmd_time = now
        self.watchdog_tripped = False
        if self.docked and (abs(surge) > 0.01 or abs(yaw_rate) > 0.01):
            self.docked = False
        self.docking = False

    def reset_pose(self) -> None:
        self.x = self.y = 0.0
        self.yaw = math.radians(30.0)
        self.surge = self.yaw_rate = self.surge_accel = 0.0
        self.cmd_surge = self.cmd_yaw_rate = 0.0
        self.distance_m = 0.0

    @property
    def battery_fraction(self) -> float:
        return max(0.0, min(1.0, self.battery_charge / self.params.capacity_ah))

    @property
    def voltage(self) -> float:
        # a LiPo pack's open-circuit curve, roughly: 3.3 V/cell empty, 4.2 V/cell full, minus IR drop
        frac = self.battery_fraction
        per_cell = 3.3 + 0.9 * frac - 0.25 * (1 - frac) ** 3
        return self.params.cells * per_cell + 0.01 * self.current

    @property
    def dock_distance(self) -> float:
        return math.hypot(self.x - self.dock_x, self.y - self.dock_y)

    # -- integration --------------------------------------------------------------------------------

    def step(self, dt: float, now: float) -> list[str]:
        """Advance by ``dt`` seconds; returns events (``watchdog``, ``docked``, ``battery_low``...)."""
        events: list[str] = []
        if dt <= 0:
            return events
        p = self.params
        self.time_s += dt
        if self.docking:
            self._dock_guidance()
        elif not self.watchdog_tripped and now - self.last_cmd_time > p.watchdog_s:
            self.watchdog_tripped = True
            self.cmd_surge = self.cmd_yaw_rate = 0.0
            events.append("watchdog")
        if self.docked or self.battery_charge <= 0.0:
            target_u, target_r = 0.0, 0.0
        else:
            target_u, target_r = self.cmd_surge, self.cmd_yaw_rate
        du = (target_u - self.surge) / p.tau_surge - p.drag * self.surge * abs(self.surge)
        self.surge_accel = du
        self.surge += du * dt
        self.yaw_rate += (target_r - self.yaw_rate) / p.tau_yaw * dt
        if abs(self.surge) < 1e-4 and target_u == 0.0:
            self.surge = 0.0
        if abs(self.yaw_rate) < 1e-4 and target_r == 0.0:
            self.yaw_rate = 0.0
        self.yaw = (self.yaw + self.yaw_rate * dt + math.pi) % (2 * math.pi) - math.pi
        self.x += self.surge * math.cos(self.yaw) * dt
        self.y += self.surge * math.sin(self.yaw) * dt
        self.distance_m += abs(self.surge) * dt
        # small wave motion for the IMU and the cameras' horizon
        self._roll = 0.03 * math.sin(1.3 * self.time_s) + 0.02 * self.yaw_rate * self.surge
        self._pitch = 0.02 * math.sin(0.9 * self.time_s + 0.5) - 0.01 * self.surge_accel
        was_low = self.battery_fraction < 0.2
        if self.docked:
            self.current = p.charge_a * (1.0 - self.battery_fraction) + 0.5
        else:
            self.current = -(p.hotel_a + p.thrust_a_per_ms * abs(self.surge) + 2.0 * abs(self.yaw_rate)
                             + (0.4 if self.lights else 0.0))
        self.battery_charge = max(0.0, min(p.capacity_ah, self.battery_charge + self.current * dt / 3600.0))
        if not was_low and self.battery_fraction < 0.2:
            events.append("battery_low")
        if self.docking and self.dock_distance < 1.5:
            self.docking = False
            self.docked = True
            self.cmd_surge = self.cmd_yaw_rate = 0.0
            events.append("docked")
        return events

    def _dock_guidance(self) -> None:
        bearing = math.atan2(self.dock_y - self.y, self.dock_x - self.x)
        error = (bearing - self.yaw + math.pi) % (2 * math.pi) - math.pi
        self.cmd_yaw_rate = max(-self.params.max_yaw_rate, min(self.params.max_yaw_rate, 1.5 * error))
        speed = min(1.0, 0.3 * self.dock_distance) if abs(error) < 0.6 else 0.2
        self.cmd_surge = speed

    # -- derived quantities -------------------------------------------------------------------------

    @property
    def roll(self) -> float:
        return self._roll

    @property
    def pitch(self) -> float:
        return self._pitch

    def quaternion(self) -> tuple[float, float, float, float]:
        """(x, y, z, w) from roll, pitch, yaw."""
        cr, sr = math.cos(self._roll / 2), math.sin(self._roll / 2)
        cp, sp = math.cos(self._pitch / 2), math.sin(self._pitch / 2)
        cy, sy = math.cos(self.yaw / 2), math.sin(self.yaw / 2)
        return (sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy,
                cr * cp * sy - sr * sp * cy, cr * cp * cy + sr * sp * sy)

    def lat_lon(self) -> tuple[float, float]:
        lat = self.origin_lat + math.degrees(self.y / EARTH_RADIUS_M)
        lon = self.origin_lon + math.degrees(self.x / (EARTH_RADIUS_M * math.cos(math.radians(self.origin_lat))))
        return lat, lon

    def local_from_lat_lon(self, lat: float, lon: float) -> tuple[float, float]:
        y = math.radians(lat - self.origin_lat) * EARTH_RADIUS_M
        x = math.radians(lon - self.origin_lon) * EARTH_RADIUS_M * math.cos(math.radians(self.origin_lat))
        return x, y
