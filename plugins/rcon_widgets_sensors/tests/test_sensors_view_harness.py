"""The accelerometer view built and rendered through RCON's view test harness (rcon_core.testing)."""

from rcon_widgets_sensors.motion_sensors import AccelerometerModel, MotionSettings
from rcon_widgets_sensors.motion_view import MotionSensorView

from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import Binding
from rcon_core.testing import RecordingPort, grab_view


def model(**settings):
    return AccelerometerModel(MotionSettings(**settings), Binding("/phone/imu", "sensor_msgs/Imu", "publish"),
                              RecordingPort(), types=TypeRegistry.standard())


def test_accelerometer_view_through_the_harness(qapp, tmp_path):
    manual = model(source="manual", manual_x=3.2, manual_y=-1.1, manual_z=9.81)
    assert manual.state.value.vector == (3.2, -1.1, 9.81)
    drawn = grab_view(MotionSensorView, manual, size=(280, 150), path=tmp_path / "accelerometer.png")
    assert (tmp_path / "accelerometer.png").stat().st_size > 0
    no_sensor = model(source="device")  # this machine has no accelerometer: the view says so instead
    assert no_sensor.state.value.vector is None
    said = grab_view(MotionSensorView, no_sensor, size=(280, 150))
    assert drawn.size() == said.size() == drawn.size().__class__(280, 150)
    assert drawn != said  # the vector is drawn
