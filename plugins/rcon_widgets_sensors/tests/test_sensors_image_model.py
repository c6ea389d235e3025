"""Image model against the embedded sim: raw and compressed cameras, scan, map; server-side options;
decoding off the bridge loop with latest-wins dropping."""

import asyncio
import threading
import time

import numpy as np
from rcon_widgets_sensors.image import Frame, ImageModel, ImageSettings
from sensors_helpers import in_thread

from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import Binding, PluginManager
from rcon_core.testing import until, until_sync


def sim_options(sim, topic):
    subs = [conn.subscriptions[topic] for conn in sim.connections if topic in conn.subscriptions]
    assert subs, f"nobody subscribed to {topic}"
    return list(subs[0].ids.values())[0]


async def test_raw_camera_frames_arrive_decoded_with_stamp(sim, client):
    model = ImageModel(ImageSettings(max_fps=20), Binding("/camera/front/image_raw", "sensor_msgs/Image",
                                                          "subscribe"), client.node("img"))
    model.start()
    try:
        frame = await in_thread(model.wait_frame, 0, 10.0)
        assert isinstance(frame, Frame) and frame.kind == "image"
        assert frame.rgb.shape == (480, 640, 3) and frame.rgb.dtype == np.uint8
        assert frame.info == "640×480 rgb8"
        assert frame.stamp is not None and abs(frame.stamp - time.time()) < 10
        assert frame.received >= frame.stamp - 1 and frame.decoded >= frame.received
        # the sky is at the top of the sim's camera, water at the bottom: blue-ish both, sky brighter
        assert frame.rgb[5].mean() > frame.rgb[-60].mean()
        opts = sim_options(sim, "/camera/front/image_raw")
        assert (opts.throttle_rate, opts.queue_length, opts.compression) == (45, 1, "cbor")
        st = model.state
        assert st.error is None and "data" not in st.message and st.message["encoding"] == "rgb8"
        second = await in_thread(model.wait_frame, frame.index, 10.0)
        assert second.index > frame.index
    finally:
        model.stop()
    await until(lambda: sim.topic_subscriber_count("/camera/front/image_raw") == 0, what="unsubscribe")


async def test_compressed_camera_json_and_cbor(sim, client):
    for compression in ("none", "cbor"):
        model = ImageModel(ImageSettings(compression=compression, max_fps=0),
                           Binding("/camera/rear/image_raw/compressed", "sensor_msgs/CompressedImage", "subscribe"),
                           client.node(f"rear-{compression}"))
        model.start()
        try:
            frame = await in_thread(model.wait_frame, 0, 10.0)
            assert frame.kind == "compressed" and frame.rgb.shape == (480, 640, 3)
            assert sim_options(sim, "/camera/rear/image_raw/compressed").throttle_rate == 0
        finally:
            model.stop()
        await until(lambda: sim.topic_subscriber_count("/camera/rear/image_raw/compressed") == 0)


async def test_scan_and_latched_map(sim, client):
    scan = ImageModel(None, Binding("/scan", "sensor_msgs/LaserScan", "subscribe"), client.node("scan"))
    grid = ImageModel(None, Binding("/map", "nav_msgs/OccupancyGrid", "subscribe"), client.node("map"))
    scan.start()
    grid.start()
    try:
        f = await in_thread(scan.wait_frame, 0, 10.0)
        assert f.kind == "scan" and f.counts is not None and f.counts.valid > 0
        g = await in_thread(grid.wait_frame, 0, 10.0)
        assert g.kind == "grid" and not g.smooth
        # the sim's map has free water, the shore (occupied) and unknown cells
        colours = {tuple(c) for c in g.rgb.reshape(-1, 3)[::7]}
        assert (255, 255, 255) in colours and (0, 0, 0) in colours
    finally:
        scan.stop()
        grid.stop()


async def test_bound_sub_image_and_bad_data_report_errors(sim, client):
    # a model bound to a field path: the DisparityImage-style "image" sub-message
    model = ImageModel(None, Binding("/x", "stereo_msgs/DisparityImage", "subscribe", "image"), None)
    pix = np.full((4, 6, 3), 200, np.uint8)
    model.on_message({"image": {"height": 4, "width": 6, "encoding": "rgb8", "step": 18, "data": pix.tobytes()}})
    f = await in_thread(model.wait_frame, 0, 5.0)
    assert f.rgb.shape == (4, 6, 3) and f.stamp is None
    model.on_message({"image": {"height": 4, "width": 6, "encoding": "weird", "step": 18, "data": b""}})
    await until(lambda: model.state.error and "'weird' is not supported" in model.state.error)
    assert model.state.value is f  # the last good frame stays on screen
    model.on_message({"nothing": 1})
    await until(lambda: "'image'" in (model.state.error or ""))
    model.stop()
    model.on_stop()


def test_decoding_never_blocks_the_caller_and_latest_wins():
    """on_message returns at once even while a slow decode runs; frames queued meanwhile collapse to the newest."""
    model = ImageModel(None, Binding("/x", "sensor_msgs/Image", "subscribe"), None)
    gate = threading.Event()
    real = model.decode

    def slow(msg, received=None):
        gate.wait(5)
        return real(msg, received)

    model.decode = slow
    pix = np.zeros((2, 2, 3), np.uint8)

    def msg(i):
        return {"header": {"stamp": {"secs": i, "nsecs": 0}}, "height": 2, "width": 2, "encoding": "rgb8",
                "step": 6, "data": pix.tobytes()}

    caller = threading.Thread(target=lambda: [model.on_message(msg(i)) for i in range(1, 51)])
    caller.start()
    caller.join(5)  # a deadline for a hang, not a speed measure: the decode stays held at the gate meanwhile
    assert not caller.is_alive(), "on_message waited for a decode"
    gate.set()
    until_sync(lambda: isinstance(model.state.value, Frame) and model.state.value.stamp == 50,
               what="the newest frame")
    assert model.state.count < 50 and model.dropped >= 40
    model.on_stop()


def test_settings_validation_and_options():
    assert ImageSettings().problems() == []
    bad = ImageSettings(max_fps=500, compression="zip", depth_min=5, depth_max=1, scan_range=-1, stale_after=-1)
    text = " | ".join(bad.problems())
    for part in ("between 0 (no limit) and 120", "compression must be one of", "min < max", "cannot be negative",
                 "'stale after'"):
        assert part in text
    m = ImageModel(ImageSettings(max_fps=0, compression="png"), Binding("/a", "sensor_msgs/Image"), None)
    assert m.subscribe_options() == {"queue_length": 1, "compression": "png"}
    pm = PluginManager(environ={})
    pm.load_entry_points()
    spec = pm.widget("sensors.image")
    assert spec.settings_problems({"max_fps": "fast"})  # wrong type -> a sentence, not a crash
    assert spec.settings_problems({"max_fps": 10}) == []
    assert TypeRegistry.standard().has("sensor_msgs/Image")


async def test_stop_ends_the_worker_thread(sim, client):
    model = ImageModel(None, Binding("/camera/front/image_raw", "sensor_msgs/Image", "subscribe"),
                       client.node("w"))
    model.start()
    await in_thread(model.wait_frame, 0, 10.0)
    worker = model.worker
    model.stop()
    await asyncio.sleep(0)
    assert worker is not None and not worker.alive
