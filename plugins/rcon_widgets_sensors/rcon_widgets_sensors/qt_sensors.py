"""The device-sensor backend through Qt Sensors (PySide6-Addons), loaded lazily by the views.

``attach(model, parent)`` connects the model's sensor (accelerometer, gyroscope, magnetometer) and feeds
its readings to ``model.feed`` in SI units (Qt gives the gyroscope in degrees per second). When Qt Sensors
is not installed or the device has no such sensor, the model is told so with a clear sentence.
"""

from __future__ import annotations

import math
from typing import Any

from qtpy import QtCore

HINT = "choose the 'test signal' or 'manual' source to try the widget"


class QtSensorBackend(QtCore.QObject):
    """Owns one QSensor and forwards its readings."""

    def __init__(self, model: Any, sensor: Any, scale: float, parent: QtCore.QObject | None = None) -> None:
        super().__init__(parent)
        self.model = model
        self.sensor = sensor
        self.scale = scale
        sensor.readingChanged.connect(self._reading)

    def _reading(self) -> None:
        r = self.sensor.reading()
        if r is not None:
            k = self.scale
            self.model.feed(r.x() * k, r.y() * k, r.z() * k)

    def stop(self) -> None:
        try:
            self.sensor.stop()
        except RuntimeError:  # already deleted with its parent
            pass


def attach(model: Any, parent: QtCore.QObject | None = None) -> QtSensorBackend | None:
    """Start the device sensor for ``model`` (``model.sensor`` names it); None when there is none."""
    name = model.sensor
    try:
        from qtpy import QtSensors
    except Exception:  # noqa: BLE001 - ImportError, or qtpy's PythonQtError for a missing module
        model.set_unavailable(f"no {name} on this device (Qt Sensors is not installed); {HINT}")
        return None
    classes = {"accelerometer": (QtSensors.QAccelerometer, 1.0),
               "gyroscope": (QtSensors.QGyroscope, math.pi / 180.0),  # Qt: degrees per second
               "magnetometer": (QtSensors.QMagnetometer, 1.0)}
    cls, scale = classes[name]
    sensor = cls(parent)
    if name == "magnetometer":
        sensor.setReturnGeoValues(False)
    if not sensor.connectToBackend():
        model.set_unavailable(f"no {name} on this device; {HINT}")
        sensor.deleteLater()
        return None
    backend = QtSensorBackend(model, sensor, scale, parent)
    rate = int(max(1.0, float(getattr(model.settings, "rate_hz", 10.0))))
    sensor.setDataRate(rate)
    if not sensor.start():
        model.set_unavailable(f"the {name} could not be started; {HINT}")
        return None
    model.attach_backend(backend)
    return backend
