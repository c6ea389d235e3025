"""Motion sensor views offscreen: the real Qt Sensors backend on a machine without sensors says so;
values drawn from the test signal; screenshots."""

import os
import sys
import tempfile
from pathlib import Path

from rcon_widgets_sensors.motion_sensors import (
    AccelerometerModel,
    GyroscopeModel,
    MagnetometerModel,
    MotionSettings,
)
from rcon_widgets_sensors.motion_view import MotionSensorView

from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import Binding

#: set RCON_SCREENSHOTS=1 to refresh the PNGs in docs/screenshots/sensors (otherwise they go to a temp dir)
SHOTS = (Path(__file__).resolve().parents[3] / "docs" / "screenshots" / "sensors" if os.environ.get("RCON_SCREENSHOTS")
         else Path(tempfile.mkdtemp(prefix="rcon-shots-")))


def view_for(qtbot, cls, source, type_name="sensor_msgs/Imu", **kw):
    model = cls(MotionSettings(source=source, **kw), Binding("/phone/imu", type_name, "publish"), None,
                types=TypeRegistry.standard())
    view = MotionSensorView(model)
    qtbot.addWidget(view)
    view.resize(280, 150)
    view.show()
    view.refresh(model.state)
    return model, view


def test_device_without_sensor_says_so(qtbot):
    model, view = view_for(qtbot, AccelerometerModel, "device")
    value = model.state.value
    # this machine has no accelerometer: either Qt Sensors finds no backend or it is not installed
    assert not value.available and value.vector is None
    assert value.status.startswith("no accelerometer on this device")
    assert "test signal" in value.status
    view.refresh(model.state)
    view.grab().save(str(SHOTS / "accelerometer-no-sensor.png"))


def test_qt_sensors_missing_is_reported(qtbot, monkeypatch):
    import qtpy

    monkeypatch.delattr(qtpy, "QtSensors", raising=False)
    monkeypatch.setitem(sys.modules, "qtpy.QtSensors", None)  # import fails as if PySide6-Addons were absent
    model, _view = view_for(qtbot, GyroscopeModel, "device")
    assert "Qt Sensors is not installed" in model.state.value.status


def test_values_drawn_screenshots(qtbot):
    SHOTS.mkdir(parents=True, exist_ok=True)
    model, view = view_for(qtbot, AccelerometerModel, "manual", manual_x=3.2, manual_y=-1.1, manual_z=9.81)
    assert model.state.value.vector == (3.2, -1.1, 9.81)
    img = view.grab().toImage()
    # the x bar (red) extends right of the middle, the y bar (green) left
    w = view.width()
    row_y = [int(28 + i * ((150 - 52) / 3) + 10) for i in range(3)]
    reds = [x for x in range(w) if img.pixelColor(x, row_y[0]).red() > 200 and img.pixelColor(x, row_y[0]).green() < 120]
    greens = [x for x in range(w) if img.pixelColor(x, row_y[1]).green() > 150 and img.pixelColor(x, row_y[1]).red() < 120]
    assert reds and greens and min(reds) >= max(greens) - 2
    view.grab().save(str(SHOTS / "accelerometer.png"))
    mag, mview = view_for(qtbot, MagnetometerModel, "manual", type_name="sensor_msgs/MagneticField",
                          manual_x=1.8e-5, manual_y=-0.4e-5, manual_z=-5e-5)
    mview.grab().save(str(SHOTS / "magnetometer.png"))
