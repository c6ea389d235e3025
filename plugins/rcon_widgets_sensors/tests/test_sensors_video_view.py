"""The Image view on video: "waiting for a keyframe" before the first picture, the overlay's codec, size, bit
rate, fps and age, and a held picture said as held."""

from __future__ import annotations

import re

import pytest
import video_helpers as vh
from rcon_widgets_sensors.image import Frame, ImageModel, ImageSettings
from rcon_widgets_sensors.image_view import ImageView

from rcon_core.plugins import Binding


class _Port:
    def subscribe(self, *_a, **_k):
        return self

    def unsubscribe(self):
        pass


@pytest.fixture
def view(qtbot):
    model = ImageModel(ImageSettings(), Binding("/cam/foxglove", "foxglove_msgs/CompressedVideo", "subscribe"),
                       _Port())
    model.start()
    v = ImageView(model)
    qtbot.addWidget(v)
    v.resize(480, 320)
    v.show()
    yield v
    model.stop()


def test_waiting_picture_and_held_picture_are_said(view, qtbot):
    model = view.model
    stream = vh.encode("h264", 24, gop=10)
    for data, _key in stream[4:8]:  # joined mid-GOP
        model.on_message(vh.compressed_video(data))
    qtbot.waitUntil(lambda: model.notice is not None, timeout=10000)
    view.refresh(model.state)
    qtbot.waitUntil(lambda: view.center_text == "waiting for a keyframe (joined mid-stream)…", timeout=3000)

    for data, _key in stream[10:16]:
        model.on_message(vh.compressed_video(data))
    frame = model.wait_frame(0, 10)
    while vh.frame_number(frame.rgb, 24) != 15:
        frame = model.wait_frame(frame.index, 10)
    view.refresh(model.state)
    qtbot.waitUntil(lambda: len(view.overlay_text) >= 2, timeout=3000)
    assert view.center_text == ""
    assert "fps · age" in view.overlay_text[0]
    codec = view.overlay_text[1]
    assert re.fullmatch(r"H\.264 320×192 · [\d.]+ [kM]bit/s \([\d.]+ [kM]?B/s\)", codec), codec
    assert isinstance(view.frame, Frame) and view.frame.kind == "video"

    for data, _key in stream[17:20]:  # frame 16 lost
        model.on_message(vh.compressed_video(data))
    qtbot.waitUntil(lambda: model.notice is not None, timeout=10000)
    view.refresh(model.state)
    qtbot.waitUntil(lambda: any(line.startswith("⏸ picture held") for line in view.overlay_text), timeout=3000)
    assert "⏸ picture held: waiting for a keyframe (packets were lost)" in view.overlay_text
    assert vh.frame_number(view.frame.rgb, 24) == 15  # the last good picture, not a smeared one
