"""Accelerometer, gyroscope and magnetometer widgets: settings, sensor sources and models (no Qt).

A model shows a 3-axis reading and, with role PUBLISH, publishes it at a steady rate (a timer on the bridge
loop) as ``sensor_msgs/Imu`` (accelerometer: ``linear_acceleration``; gyroscope: ``angular_velocity``),
``sensor_msgs/MagneticField`` (magnetometer) or a plain ``geometry_msgs/Vector3[Stamped]``. With role
SUBSCRIBE it shows the robot's vector instead.

Where readings come from (``settings.source``):

* ``"device"``: this device's sensor. The model has no Qt; the view attaches the Qt Sensors backend
  (:mod:`.qt_sensors`, imported lazily) which calls :meth:`MotionSensorModel.feed`. Without a backend,
  or on a device without that sensor, the state says so clearly ("no accelerometer on this device") and
  nothing is published.
* ``"test signal"``: a smooth synthetic signal, generated on the publish timer (for demos and CI).
* ``"manual"``: the fixed ``manual_x/y/z`` values; tests and other code may also call ``feed(x, y, z)``.

Children of the std package's Compound: bound to ``sensor_msgs/Imu`` with field path
``linear_acceleration`` / ``angular_velocity`` (role PUBLISH), each publishes a whole Imu through the
compound's child port and the compound takes the value at that path, so an accelerometer and a gyroscope
compose one full Imu message.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from typing import Any, Protocol

import attrs

from rcon_core.plugins import Role, WidgetModel
from rcon_core.plugins.paths import PathError, get_path, set_path

from .slots import LoopTicker

__all__ = ["MotionSettings", "SensorValue", "SensorBackend", "MotionSensorModel", "AccelerometerModel",
           "GyroscopeModel", "MagnetometerModel", "SOURCES", "synthetic_reading"]

SOURCES = ("device", "test signal", "manual")


@attrs.define
class MotionSettings:
    """``source``: device, test signal or manual. ``rate_hz``: publish rate. ``frame_id``: the header's
    frame. ``manual_x/y/z``: the values of the manual source (SI units: m/s², rad/s, tesla)."""

    source: str = "device"
    rate_hz: float = 10.0
    frame_id: str = "imu_link"
    manual_x: float = 0.0
    manual_y: float = 0.0
    manual_z: float = 0.0

    def problems(self) -> list[str]:
        out = []
        if self.source not in SOURCES:
            out.append(f"source must be one of {', '.join(SOURCES)}, not {self.source!r}")
        if not 0.5 <= self.rate_hz <= 100:
            out.append(f"the publish rate must be between 0.5 and 100 Hz, not {self.rate_hz:g}")
        for name in ("manual_x", "manual_y", "manual_z"):
            if not math.isfinite(getattr(self, name)):
                out.append(f"{name} must be a finite number")
        return out


@attrs.frozen
class SensorValue:
    """What the view shows. ``available``: a reading source works; ``status``: a sentence for people
    (e.g. "no gyroscope on this device"); ``vector``: (x, y, z) in SI units or None; ``sent``: messages
    published; ``source``: device / test signal / manual / topic."""

    sensor: str
    unit: str
    source: str
    available: bool
    status: str = ""
    vector: tuple[float, float, float] | None = None
    sent: int = 0

    @property
    def magnitude(self) -> float | None:
        return None if self.vector is None else math.sqrt(sum(v * v for v in self.vector))


class SensorBackend(Protocol):
    """A source of device readings (the Qt one lives in :mod:`.qt_sensors`); it calls ``model.feed``."""

    def stop(self) -> None: ...


def synthetic_reading(sensor: str, t: float) -> tuple[float, float, float]:
    """A smooth, plausible synthetic reading at time ``t`` (seconds)."""
    if sensor == "accelerometer":  # gravity, plus a gentle sway
        return (0.6 * math.sin(0.9 * t), 0.4 * math.sin(1.3 * t + 1.0), 9.80665 + 0.1 * math.sin(2.1 * t))
    if sensor == "gyroscope":  # slowly turning and rocking
        return (0.05 * math.sin(1.1 * t), 0.04 * math.cos(0.7 * t), 0.35 * math.sin(0.4 * t))
    heading = 0.3 * t  # magnetometer: the horizontal field turns with the heading (Toronto: ~18 µT N, -50 µT up)
    return (18e-6 * math.cos(heading), -18e-6 * math.sin(heading), -50e-6)


# field the vector goes to, by canonical type
_DEFAULT_PATHS: dict[str, dict[str, str]] = {
    "accelerometer": {"sensor_msgs/msg/Imu": "linear_acceleration"},
    "gyroscope": {"sensor_msgs/msg/Imu": "angular_velocity"},
    "magnetometer": {"sensor_msgs/msg/MagneticField": "magnetic_field"},
}
_COMMON_PATHS = {"geometry_msgs/msg/Vector3Stamped": "vector", "geometry_msgs/msg/Vector3": ""}
_XYZ = {"x": 0.0, "y": 0.0, "z": 0.0}
_STAMP: dict[str, Any] = {"secs": 0, "nsecs": 0}
_HEADER: dict[str, Any] = {"seq": 0, "stamp": _STAMP, "frame_id": ""}
_FALLBACK: dict[str, Callable[[], dict[str, Any]]] = {
    "sensor_msgs/msg/Imu": lambda: {"header": dict(_HEADER, stamp=dict(_STAMP)),
                                    "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 0.0},
                                    "orientation_covariance": [0.0] * 9, "angular_velocity": dict(_XYZ),
                                    "angular_velocity_covariance": [0.0] * 9, "linear_acceleration": dict(_XYZ),
                                    "linear_acceleration_covariance": [0.0] * 9},
    "sensor_msgs/msg/MagneticField": lambda: {"header": dict(_HEADER, stamp=dict(_STAMP)),
                                              "magnetic_field": dict(_XYZ), "magnetic_field_covariance": [0.0] * 9},
    "geometry_msgs/msg/Vector3Stamped": lambda: {"header": dict(_HEADER, stamp=dict(_STAMP)),
                                                 "vector": dict(_XYZ)},
    "geometry_msgs/msg/Vector3": lambda: dict(_XYZ),
}


class MotionSensorModel(WidgetModel):
    """Base of the three: subclasses set ``sensor`` and ``unit``."""

    sensor = "sensor"
    unit = ""
    stale_after = 5.0

    def __init__(self, settings: Any, binding: Any, port: Any, *, ticker_clock: Any = None,
                 **kwargs: Any) -> None:
        """``ticker_clock``: what the publish rate is timed on instead of the bridge loop (see
        :class:`~rcon_widgets_sensors.slots.LoopTicker`); tests pass ``rcon_core.testing.ManualClock``, as
        ``clock`` too, so the test signal follows it."""
        super().__init__(settings if settings is not None else MotionSettings(), binding, port, **kwargs)
        self._ticker_clock = ticker_clock
        self._feed_lock = threading.Lock()
        self._reading: tuple[float, float, float] | None = None
        self._reading_at: float | None = None
        self._unavailable: str | None = None
        self._backend: SensorBackend | None = None
        self._ticker: LoopTicker | None = None
        self._sent = 0
        self._t0 = self._clock()
        self.sent_messages: list[dict[str, Any]] = []  # the last few (tests, diagnostics)
        if self.settings.source == "manual":
            s = self.settings
            self._reading = (float(s.manual_x), float(s.manual_y), float(s.manual_z))
        self._show()

    # -- the message -------------------------------------------------------------------------------------
    @property
    def canonical_type(self) -> str:
        return self.binding.canonical_type

    @property
    def vector_path(self) -> str:
        """Where the vector goes (the bound field, else the type's usual field)."""
        if self.binding.field_path:
            return self.binding.field_path
        t = self.canonical_type
        return _DEFAULT_PATHS.get(self.sensor, {}).get(t, _COMMON_PATHS.get(t, ""))

    def template(self) -> dict[str, Any]:
        if self.types is not None:
            try:
                return self.types.default(self.binding.type)
            except Exception:  # noqa: BLE001 - unknown to the registry; the table may know it
                pass
        make = _FALLBACK.get(self.canonical_type)
        if make is None:
            raise ValueError(f"cannot build a {self.binding.type} message (unknown type)")
        return make()

    def build_message(self, value: Any, path: str | None = None) -> dict[str, Any]:
        """A whole message carrying ``value`` (x, y, z) at :attr:`vector_path`, stamped now."""
        x, y, z = value
        msg = self.template()
        vec = {"x": float(x), "y": float(y), "z": float(z)}
        p = self.vector_path if path is None else path
        msg = set_path(msg, p, vec) if p else {**msg, **vec}
        if self.canonical_type == "sensor_msgs/msg/Imu":
            # REP 145: element 0 of a covariance = -1 means "not measured"
            for part, cov in (("orientation", "orientation_covariance"),
                              ("angular_velocity", "angular_velocity_covariance"),
                              ("linear_acceleration", "linear_acceleration_covariance")):
                if part != p and isinstance(msg.get(cov), list) and msg[cov]:
                    msg[cov][0] = -1.0
        header = msg.get("header")
        if isinstance(header, dict) and isinstance(header.get("stamp"), dict):
            ns = time.time_ns()
            a, b = ("sec", "nanosec") if "sec" in header["stamp"] else ("secs", "nsecs")
            header["stamp"] = {a: ns // 1_000_000_000, b: ns % 1_000_000_000}
            header["frame_id"] = self.settings.frame_id
        return msg

    def problems(self) -> list[str]:
        out = super().problems()
        if out or not self.binding.type or self.binding.role is not Role.PUBLISH:
            return out
        try:
            msg = self.template()
            target = get_path(msg, self.vector_path) if self.vector_path else msg
        except (ValueError, PathError) as exc:
            return [str(exc)]
        if not (isinstance(target, dict) and {"x", "y", "z"} <= set(target)):
            out.append(f"{self.vector_path or 'the message'} of {self.binding.type} is not an x/y/z vector")
        return out

    # -- readings (any thread) ------------------------------------------------------------------------
    def feed(self, x: float, y: float, z: float) -> None:
        """A new reading from a source (the device backend, a test...). Thread-safe."""
        with self._feed_lock:
            self._reading = (float(x), float(y), float(z))
            self._reading_at = time.monotonic()
            self._unavailable = None
        self._show()

    def set_unavailable(self, status: str) -> None:
        """The source cannot give readings (e.g. "no gyroscope on this device"); shown, nothing published."""
        with self._feed_lock:
            self._unavailable = status
            if self.settings.source == "device":
                self._reading = None
        self._show()

    def attach_backend(self, backend: SensorBackend | None) -> None:
        """The view hands over the device backend it made (so stop() can end it)."""
        self._backend = backend

    def reading(self) -> tuple[float, float, float] | None:
        with self._feed_lock:
            return self._reading

    @property
    def available(self) -> bool:
        if self.binding.role is Role.SUBSCRIBE:
            return True
        src = self.settings.source
        return src in ("test signal", "manual") or (self._unavailable is None and self._reading is not None)

    def _status(self) -> str:
        s = self.settings
        if self.binding.role is Role.SUBSCRIBE:
            return f"from {self.binding.name}" if self.binding.name else ""
        if self._unavailable:
            return self._unavailable
        if s.source == "device" and self._reading is None:
            return f"waiting for the {self.sensor}…"
        where = self.binding.name or "(no topic)"
        return f"{s.source} → {where} at {s.rate_hz:g} Hz" if self.running else f"{s.source} (not publishing)"

    def _show(self) -> None:
        src = "topic" if self.binding.role is Role.SUBSCRIBE else self.settings.source
        self.set_value(SensorValue(self.sensor, self.unit, src, self.available, self._status(), self.reading(),
                                   self._sent))

    # -- publishing (bridge loop) ---------------------------------------------------------------------
    def on_start(self) -> None:
        if self.binding.role is Role.PUBLISH and self._pub is not None:
            self._t0 = self._clock()
            self._ticker = LoopTicker(1.0 / self.settings.rate_hz, self._tick, clock=self._ticker_clock)
            self._ticker.start(first_delay=0.0)
        self._show()

    def on_stop(self) -> None:
        if self._ticker is not None:
            self._ticker.stop()
            self._ticker = None
        backend, self._backend = self._backend, None
        if backend is not None:
            try:
                backend.stop()
            except Exception:  # noqa: BLE001 - the device may be gone already
                pass

    def _tick(self) -> None:
        if self.settings.source == "test signal":
            with self._feed_lock:
                self._reading = synthetic_reading(self.sensor, self._clock() - self._t0)
        vec = self.reading()
        if vec is None or self._unavailable or self._pub is None:
            self._show()
            return
        msg = self.build_message(vec)
        try:
            self._pub.publish(msg)
        except Exception as exc:  # noqa: BLE001 - shown on the widget
            self.set_error(f"publishing failed: {exc}")
            return
        self._sent += 1
        self.sent_messages.append(msg)
        del self.sent_messages[:-20]
        self._show()

    # -- subscribing (bridge loop) ----------------------------------------------------------------------
    def on_message(self, msg: dict[str, Any]) -> None:
        path = self.vector_path
        vec = get_path(msg, path) if path else msg
        if not isinstance(vec, dict):
            raise PathError(f"{path or 'the message'} is not an x/y/z vector")
        with self._feed_lock:
            x, y, z = (vec.get(k) for k in ("x", "y", "z"))
            self._reading = tuple(float(v) if v is not None else math.nan for v in (x, y, z))  # type: ignore[assignment]
        self._show()


class AccelerometerModel(MotionSensorModel):
    sensor = "accelerometer"
    unit = "m/s²"


class GyroscopeModel(MotionSensorModel):
    sensor = "gyroscope"
    unit = "rad/s"


class MagnetometerModel(MotionSensorModel):
    sensor = "magnetometer"
    unit = "T"


#: for the Qt backend and tests: the model class per sensor
MODELS: dict[str, Callable[..., MotionSensorModel]] = {
    "accelerometer": AccelerometerModel, "gyroscope": GyroscopeModel, "magnetometer": MagnetometerModel}
