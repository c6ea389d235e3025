"""The Image widget's "best transport the robot offers": the pure choice, and the model moving its subscription
to the sim's H.264 stream of the camera it was bound to (and saying so)."""

from __future__ import annotations

from rcon_widgets_sensors.image import ImageModel, ImageSettings
from rcon_widgets_sensors.transport import camera_base, pick
from sensors_helpers import in_thread

from rcon_core.plugins import Binding
from rcon_core.testing import until

CAM = "/cam/image_raw"
LISTED = {CAM: "sensor_msgs/Image", CAM + "/compressed": "sensor_msgs/CompressedImage",
          CAM + "/foxglove": "foxglove_msgs/CompressedVideo", CAM + "/ffmpeg": "ffmpeg_image_transport_msgs/FFMPEGPacket",
          "/other/image_raw/foxglove": "foxglove_msgs/CompressedVideo", CAM + "/theora": "theora_image_transport/Packet"}


def test_video_then_compressed_then_raw_among_what_is_listed():
    c = pick(CAM, "sensor_msgs/Image", LISTED)
    assert (c.topic, c.kind, c.offered) == (CAM + "/foxglove", "video", ("video", "video", "compressed", "raw"))
    assert c.note() == f"via video: {CAM}/foxglove (offered: video, compressed, raw)"
    no_video = {k: v for k, v in LISTED.items() if "foxglove" not in k and "ffmpeg" not in k}
    assert pick(CAM + "/compressed", "sensor_msgs/msg/CompressedImage", no_video).topic == CAM + "/compressed"
    assert pick(CAM, "sensor_msgs/Image", {CAM: "sensor_msgs/Image"}).kind == "raw"
    # a listed name with another type is not taken for the transport
    odd = {CAM: "sensor_msgs/Image", CAM + "/compressed": "std_msgs/String"}
    assert pick(CAM, "sensor_msgs/Image", odd).topic == CAM
    # ROS 2 spellings, and a bound topic the robot no longer lists is still a candidate
    assert pick(CAM + "/ffmpeg", "ffmpeg_image_transport_msgs/msg/FFMPEGPacket", {}).kind == "video"
    assert pick("/scan", "sensor_msgs/LaserScan", LISTED).kind == "as bound"


def test_camera_base():
    assert camera_base("/a/image_raw/compressed") == camera_base("/a/image_raw/foxglove") == "/a/image_raw"
    assert camera_base("/a/image_raw") == "/a/image_raw" and camera_base("/compressed") == "/compressed"


async def test_best_moves_a_raw_binding_to_the_sims_video_and_says_so(sim, client):
    model = ImageModel(ImageSettings(transport="best"),
                       Binding("/camera/front/image_raw", "sensor_msgs/Image", "subscribe"), client.node("best"))
    model.start()
    try:
        await until(lambda: model.transport is not None, 10, "the transport picked")
        assert model.transport.topic == "/camera/front/image_raw/foxglove"
        assert model.transport_note == "via video: /camera/front/image_raw/foxglove (offered: video, raw)"
        frame = await in_thread(model.wait_frame, 0, 15.0)
        while frame.kind != "video":  # a raw frame may have come before the move
            frame = await in_thread(model.wait_frame, frame.index, 15.0)
        assert frame.info == "H.264 640×360"
        await until(lambda: sim.topic_subscriber_count("/camera/front/image_raw") == 0, 10, "raw unsubscribed")
        assert sim.topic_subscriber_count("/camera/front/image_raw/foxglove") == 1
    finally:
        model.stop()
    await until(lambda: sim.topic_subscriber_count("/camera/front/image_raw/foxglove") == 0, 10, "video unsubscribed")


async def test_bound_keeps_the_topic_as_bound(sim, client):
    model = ImageModel(ImageSettings(), Binding("/camera/front/image_raw", "sensor_msgs/Image", "subscribe"),
                       client.node("bound"))
    model.start()
    try:
        frame = await in_thread(model.wait_frame, 0, 15.0)
        assert frame.kind == "image" and model.transport is None and model.transport_note is None
    finally:
        model.stop()
