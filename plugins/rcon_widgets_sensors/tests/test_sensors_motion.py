"""Accelerometer, gyroscope and magnetometer: sources (device/test signal/manual), publishing at a set rate
on the sim, subscribing to the robot's IMU, "no sensor" state, and two children of the std Compound
composing one full Imu."""

import math
import time

import pytest
from rcon_widgets_sensors import plugin as sensors_plugin
from rcon_widgets_sensors.motion_sensors import (
    AccelerometerModel,
    GyroscopeModel,
    MagnetometerModel,
    MotionSettings,
    SensorValue,
    synthetic_reading,
)

from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import Binding, WidgetContext
from rcon_core.testing import ManualClock, RecordingPort, flushed, until, widget_catalog


def make(cls, client, topic, type_name, role="publish", path=(), types=True, ticker_clock=None, **settings):
    return cls(MotionSettings(**settings), Binding(topic, type_name, role, path),
               client.node(f"{cls.__name__}-{topic}") if client else None,
               types=TypeRegistry.standard() if types else None, ticker_clock=ticker_clock)


def test_test_signal_publishes_at_the_set_rate_on_its_clock():
    clock, port = ManualClock(), RecordingPort()
    m = AccelerometerModel(MotionSettings(source="test signal", rate_hz=20), Binding("/imu", "sensor_msgs/Imu",
                           "publish"), port, types=TypeRegistry.standard(), clock=clock, ticker_clock=clock)
    m.start()
    try:
        clock.advance(1.025)
        assert len(port.published) == 21  # at once, then every 50 ms: 0.00 .. 1.00 s
        assert m.state.value.sent == 21
        z = [msg["linear_acceleration"]["z"] for _topic, msg in port.published]
        assert len(set(z)) > 1  # the signal follows the clock: a sway, not one value repeated
    finally:
        m.stop()
    clock.advance(1.0)
    assert len(port.published) == 21 and clock.pending == 0  # stopped: silent, no timer left


async def test_test_signal_publishes_imu_on_the_sim(sim, client):
    got, clock = [], ManualClock()  # the publish timer runs on the test's clock: each poll moves it one period
    sim.subscribe_internal("/phone/imu", "sensor_msgs/Imu", "/rcon_test_rx", lambda m: got.append(time.monotonic()))
    m = make(AccelerometerModel, client, "/phone/imu", "sensor_msgs/Imu", source="test signal", rate_hz=20,
             frame_id="phone", ticker_clock=clock)
    assert m.problems() == []
    m.start()
    try:
        await until(lambda: clock.advance(0.05) or len(got) >= 5, 5.0, "a stream of messages")
        n = len(got)
        msg = sim.published("/phone/imu")[-1]
        acc = msg["linear_acceleration"]
        assert 9.0 < acc["z"] < 10.5 and abs(acc["x"]) <= 0.6  # gravity plus a gentle sway
        assert msg["header"]["frame_id"] == "phone" and msg["header"]["stamp"]["secs"] > 0
        # REP 145: what an accelerometer does not measure is marked -1
        assert msg["orientation_covariance"][0] == -1 and msg["angular_velocity_covariance"][0] == -1
        assert msg["linear_acceleration_covariance"][0] == 0
        v = m.state.value
        assert isinstance(v, SensorValue) and v.available and v.sent >= n and "test signal" in v.status
    finally:
        m.stop()
    await flushed(client, sim)  # what was sent before the stop has arrived
    count = len(sim.published("/phone/imu"))
    clock.advance(1.0)  # twenty periods: a timer left running would send now
    await flushed(client, sim)
    assert len(sim.published("/phone/imu")) == count  # stopped: silent


async def test_manual_and_fed_values_magnetometer(sim, client):
    m = make(MagnetometerModel, client, "/phone/mag", "sensor_msgs/MagneticField", source="manual",
             manual_x=2e-5, manual_y=0.0, manual_z=-4e-5, rate_hz=10)
    m.start()
    try:
        got = await sim.wait_for_published("/phone/mag", timeout=5)
        assert got["magnetic_field"] == {"x": 2e-5, "y": 0.0, "z": -4e-5}
        m.feed(1e-5, 1e-5, 1e-5)  # from another thread, as the device backend does
        await sim.wait_for_published("/phone/mag", lambda msg: msg["magnetic_field"]["y"] == 1e-5, timeout=5)
    finally:
        m.stop()


async def test_no_device_sensor_is_a_clear_state_and_publishes_nothing(sim, client):
    clock = ManualClock()
    m = make(GyroscopeModel, client, "/phone/gyro", "sensor_msgs/Imu", source="device", ticker_clock=clock)
    m.start()
    try:
        m.set_unavailable("no gyroscope on this device; choose the 'test signal' or 'manual' source")
        clock.advance(1.0)  # a timer sending anyway would send now
        await flushed(client, sim)
        assert sim.published("/phone/gyro") == []
        v = m.state.value
        assert not v.available and v.vector is None and v.status.startswith("no gyroscope on this device")
        m.feed(0.0, 0.0, 0.5)  # a sensor appears (a backend starts feeding): publishing starts
        await until(lambda: clock.advance(0.1) or sim.published("/phone/gyro"), 5.0, "the gyroscope publishing")
        got = sim.published("/phone/gyro")[0]
        assert got["angular_velocity"]["z"] == 0.5 and got["linear_acceleration_covariance"][0] == -1
    finally:
        m.stop()


async def test_subscribe_shows_the_robots_imu_and_mag(sim, client):
    acc = make(AccelerometerModel, client, "/imu/data", "sensor_msgs/Imu", role="subscribe")
    gyro = make(GyroscopeModel, client, "/imu/data", "sensor_msgs/Imu", role="subscribe")
    mag = make(MagnetometerModel, client, "/imu/mag", "sensor_msgs/MagneticField", role="subscribe")
    for m in (acc, gyro, mag):
        m.start()
    try:
        await until(lambda: all(m.state.value.vector for m in (acc, gyro, mag)), 10.0, "readings")
        assert 9 < acc.state.value.vector[2] < 10.6  # the vessel floats: gravity on z
        assert acc.state.value.source == "topic" and acc.state.value.status == "from /imu/data"
        assert all(abs(c) < 1e-3 for c in mag.state.value.vector)  # tens of microtesla
        assert abs(gyro.state.value.vector[2]) < 2.0
    finally:
        for m in (acc, gyro, mag):
            m.stop()


async def test_vector3_stamped_and_plain_vector3(sim, client):
    stamped = make(GyroscopeModel, client, "/phone/rate", "geometry_msgs/Vector3Stamped", source="manual",
                   manual_z=0.25)
    plain = make(AccelerometerModel, client, "/phone/acc", "geometry_msgs/Vector3", source="manual", manual_x=1.5,
                 types=False)
    assert stamped.vector_path == "vector" and plain.vector_path == ""
    stamped.start()
    plain.start()
    try:
        a = await sim.wait_for_published("/phone/rate", timeout=5)
        b = await sim.wait_for_published("/phone/acc", timeout=5)
        assert a["vector"]["z"] == 0.25 and a["header"]["frame_id"] == "imu_link"
        assert b == {"x": 1.5, "y": 0.0, "z": 0.0}
    finally:
        stamped.stop()
        plain.stop()


async def test_children_of_the_std_compound_compose_one_imu(sim, client):
    compound = pytest.importorskip("rcon_widgets_std.compound")
    settings = compound.CompoundSettings(auto_send=True, rate_hz=10, children=[
        compound.ChildSpec("sensors.accelerometer", "linear_acceleration",
                           {"source": "manual", "manual_z": 9.81, "rate_hz": 10}),
        compound.ChildSpec("sensors.gyroscope", "angular_velocity", {"source": "manual", "manual_z": -0.3}),
    ])
    m = compound.CompoundModel(settings, Binding("/phone/imu_full", "sensor_msgs/Imu", "publish"),
                               client.node("compound"), types=TypeRegistry.standard(),
                               context=WidgetContext(widget_catalog(sensors_plugin)))  # only this package's kinds
    m.start()
    try:
        await until(lambda: m.children, 5.0, "children built")
        assert m.problems() == []
        got = await sim.wait_for_published(
            "/phone/imu_full", lambda msg: msg["linear_acceleration"]["z"] == 9.81
            and msg["angular_velocity"]["z"] == -0.3, timeout=10)
        assert got["linear_acceleration"] == {"x": 0.0, "y": 0.0, "z": 9.81}
        assert got["angular_velocity"] == {"x": 0.0, "y": 0.0, "z": -0.3}
    finally:
        m.stop()
    assert not any(c.model.running for c in m.children)


def test_settings_problems_and_signal():
    assert MotionSettings().problems() == []
    text = " | ".join(MotionSettings(source="gps", rate_hz=0, manual_x=math.inf).problems())
    assert "source must be one of device, test signal, manual" in text and "between 0.5 and 100 Hz" in text
    assert "manual_x must be a finite number" in text
    bad = AccelerometerModel(None, Binding("/x", "sensor_msgs/Imu", "publish", "header"), None,
                             types=TypeRegistry.standard())
    assert bad.problems() == ["header of sensor_msgs/Imu is not an x/y/z vector"]
    gx, gy, gz = synthetic_reading("accelerometer", 0.0)
    assert gz == pytest.approx(9.80665) and synthetic_reading("magnetometer", 0.0)[2] < 0
