"""Motion sensor views offscreen: the real Qt Sensors backend on a machine without sensors says so;
values drawn from the test signal. (The README's pictures: docs/make_screenshots.py.)"""

import sys

from rcon_widgets_sensors.motion_sensors import (
    AccelerometerModel,
    GyroscopeModel,
    MotionSettings,
)
from rcon_widgets_sensors.motion_view import MotionSensorView

from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import Binding


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


def test_qt_sensors_missing_is_reported(qtbot, monkeypatch):
    import qtpy

    monkeypatch.delattr(qtpy, "QtSensors", raising=False)
    monkeypatch.setitem(sys.modules, "qtpy.QtSensors", None)  # import fails as if PySide6-Addons were absent
    model, _view = view_for(qtbot, GyroscopeModel, "device")
    assert "Qt Sensors is not installed" in model.state.value.status


def test_values_drawn(qtbot):
    model, view = view_for(qtbot, AccelerometerModel, "manual", manual_x=3.2, manual_y=-1.1, manual_z=9.81)
    assert model.state.value.vector == (3.2, -1.1, 9.81)
    img = view.grab().toImage()
    # the x bar (red) extends right of the middle, the y bar (green) left
    w = view.width()
    row_y = [int(28 + i * ((150 - 52) / 3) + 10) for i in range(3)]
    reds = [x for x in range(w) if img.pixelColor(x, row_y[0]).red() > 200 and img.pixelColor(x, row_y[0]).green() < 120]
    greens = [x for x in range(w) if img.pixelColor(x, row_y[1]).green() > 150 and img.pixelColor(x, row_y[1]).red() < 120]
    assert reds and greens and min(reds) >= max(greens) - 2
