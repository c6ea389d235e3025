"""Camera widget: the synthetic source published as JPEG on the sim and read back by another client (valid
JPEGs), rgb8 raw, no camera -> a clear error, capture off the GUI thread, settings; the preview."""

import asyncio
import threading
import time

import cv2
import numpy as np
import pytest
from rcon_widgets_sensors.camera import CameraModel, CameraSettings, TestPattern, pace
from rcon_widgets_sensors.image import Frame

from rcon_core.bridge import BridgeClient
from rcon_core.msgs import TypeRegistry
from rcon_core.msgs.values import as_bytes
from rcon_core.plugins import Binding
from rcon_core.testing import flushed, until


def loop_dispatch():
    loop = asyncio.get_running_loop()
    return lambda fn: loop.call_soon_threadsafe(fn)


@pytest.fixture
async def clients(sim):
    a = BridgeClient(sim.url, reconnect=False)
    b = BridgeClient(sim.url, reconnect=False)
    await a.connect()
    await b.connect()
    yield a, b
    await a.close()
    await b.close()


async def test_test_pattern_jpegs_reach_another_client(sim, clients):
    pub_client, viewer = clients
    model = CameraModel(CameraSettings(source="test pattern", fps=10, quality=70, width=320, height=240),
                        Binding("/phone/camera/compressed", "sensor_msgs/CompressedImage", "publish"),
                        pub_client.node("cam"), types=TypeRegistry.standard(), dispatch=loop_dispatch())
    received = []
    viewer.node("viewer").subscribe("/phone/camera/compressed", lambda m: received.append((time.monotonic(), m)),
                                    type="sensor_msgs/CompressedImage")
    capture_threads = []
    real_encode = model.encode

    def spy(rgb, stamp):
        capture_threads.append(threading.current_thread().name)
        return real_encode(rgb, stamp)

    model.encode = spy
    model.start()
    try:
        await until(lambda: len(received) >= 3, 10.0, "three frames at the other client")  # the pace: below
        assert model.capturing
        _t, msg = received[-1]
        assert msg["format"] == "jpeg" and msg["header"]["frame_id"] == "camera"
        img = cv2.imdecode(np.frombuffer(as_bytes(msg["data"]), np.uint8), cv2.IMREAD_COLOR)
        assert img is not None and img.shape == (240, 320, 3)
        stamps = [m["header"]["stamp"]["secs"] + m["header"]["stamp"]["nsecs"] / 1e9 for _t, m in received]
        assert stamps == sorted(stamps) and abs(stamps[-1] - time.time()) < 5
        preview = model.state.value
        assert isinstance(preview, Frame) and preview.rgb.shape == (240, 320, 3) and "jpeg q70" in preview.info
        assert set(capture_threads) == {"rcon-camera"}  # capture and encoding on the capture thread
    finally:
        model.stop()
    assert not model.capturing
    await flushed(pub_client, sim)  # what the capture thread sent before the stop has arrived
    n = len(sim.published("/phone/camera/compressed"))
    await flushed(pub_client, sim)  # and a marker after it: nothing more in between
    assert len(sim.published("/phone/camera/compressed")) == n  # stopped: nothing more


async def test_raw_rgb8(sim, clients):
    pub_client, _viewer = clients
    model = CameraModel(CameraSettings(source="test pattern", fps=5, width=64, height=48),
                        Binding("/phone/camera/raw", "sensor_msgs/Image", "publish"), pub_client.node("raw"),
                        dispatch=loop_dispatch())
    model.start()
    try:
        got = await sim.wait_for_published("/phone/camera/raw", timeout=5)
        assert (got["width"], got["height"], got["encoding"], got["step"]) == (64, 48, "rgb8", 192)
        pix = np.frombuffer(as_bytes(got["data"]), np.uint8).reshape(48, 64, 3)
        assert pix[5, 2].tolist() == [235, 235, 235]  # the first colour bar
    finally:
        model.stop()


async def test_no_camera_is_a_clear_error(sim, clients):
    pub_client, _viewer = clients
    model = CameraModel(CameraSettings(source="device", device_index=63),
                        Binding("/phone/camera/compressed", "sensor_msgs/CompressedImage", "publish"),
                        pub_client.node("nocam"), dispatch=loop_dispatch())
    model.start()
    try:
        await until(lambda: model.state.error, 10.0, "the error")
        assert model.state.error.startswith("no camera at index 63 on this device")
        await flushed(pub_client, sim)
        assert sim.published("/phone/camera/compressed") == []
    finally:
        model.stop()


def test_settings_problems():
    assert CameraSettings().problems() == []
    text = " | ".join(CameraSettings(source="webcam", device_index=99, fps=100, quality=0, width=8).problems())
    for part in ("source must be one of device, test pattern", "between 0 and 63", "between 0.2 and 60 fps",
                 "JPEG quality", "16 and 4096"):
        assert part in text


def test_capture_pace_is_steady_and_skips_rather_than_bursts():
    period, now, due, times = 0.1, 100.0, 100.0, []
    for cost in [0.01] * 10 + [0.35] + [0.01] * 5:  # each frame's capture and encoding time; one slow one
        times.append(now)
        now += cost
        due, wait = pace(due, period, now)
        now += wait
    gaps = [round(b - a, 6) for a, b in zip(times, times[1:], strict=False)]
    assert gaps[:10] == [0.1] * 10  # 10 fps while the capture keeps up
    assert gaps[10] == 0.35  # the slow frame: the next one at once ...
    assert gaps[11:] == [0.1] * 4  # ... then steady again from there: no catch-up burst of the 2.5 missed


def test_pattern_moves():
    p = TestPattern(160, 120)
    a, b = p.read(), p.read()
    assert a.shape == (120, 160, 3) and not np.array_equal(a, b)
