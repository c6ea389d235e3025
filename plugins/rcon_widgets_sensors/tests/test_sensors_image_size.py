"""The Image widget decodes each frame at the size its view paints it: the model (no Qt) against the sim
and the sim's own camera pictures; the view telling the model its size and zoom, and painting the smaller
array where the full one would go."""

import time

import cv2
import numpy as np
import pytest
from image_helpers import area, feed, grid_picture, jpeg_msg, mean_abs_diff, picture, raw_msg
from qtpy import QtCore
from qtpy.QtTest import QTest
from rcon_widgets_sensors.camera import CameraModel, CameraSettings
from rcon_widgets_sensors.camera_view import CameraView
from rcon_widgets_sensors.decode import (
    DecodeError,
    decode_compressed,
    decode_compressed_sized,
    jpeg_size,
    shrink,
)
from rcon_widgets_sensors.image import Frame, ImageModel, ImageSettings
from rcon_widgets_sensors.image_view import ImageView
from sensors_helpers import in_thread, wheel

from rcon_core.plugins import Binding
from rcon_core.sim.camera import encode_jpeg

RAW = Binding("/camera/front/image_raw", "sensor_msgs/Image", "subscribe")
JPEG = Binding("/camera/rear/image_raw/compressed", "sensor_msgs/CompressedImage", "subscribe")


# -- model, no Qt --------------------------------------------------------------------------------------------
async def test_sim_cameras_arrive_at_the_display_size_and_keep_their_source_size(sim, client):
    for binding, kind in ((RAW, "image"), (JPEG, "compressed")):
        model = ImageModel(ImageSettings(max_fps=0), binding, client.node(f"size-{kind}"))
        model.set_display_size(320, 240)
        model.start()
        try:
            frame = await in_thread(model.wait_frame, 0, 10.0)
            assert frame.kind == kind and frame.rgb.shape == (240, 320, 3)
            assert frame.rgb32.shape == (240, 320, 4) and frame.rgb32.flags.c_contiguous
            assert (frame.width, frame.height) == (640, 480)  # the source, for the overlay and the zoom
            assert (frame.pixel_width, frame.pixel_height) == (320, 240)
            assert frame.info.startswith("640×480 ")
            assert frame.rgb[2].mean() > frame.rgb[-30].mean()  # sky above water, reduced or not
            model.set_display_size(0, 0)  # back to full resolution: the next frame is 640x480
            full = await in_thread(model.wait_frame, frame.index, 10.0)
            while full.rgb.shape != (480, 640, 3):  # one frame may have been decoding already
                assert full.index <= frame.index + 2, full.rgb.shape
                full = await in_thread(model.wait_frame, full.index, 10.0)
            assert (full.width, full.height) == (640, 480) and model.display_size is None
        finally:
            model.stop()


def test_a_jpeg_is_decoded_reduced_and_matches_a_resized_full_decode():
    rgb = picture("rear")
    msg = jpeg_msg(rgb)
    buf = np.frombuffer(msg["data"], np.uint8)
    full = cv2.imdecode(buf, cv2.IMREAD_COLOR_RGB)
    model = ImageModel(ImageSettings(), JPEG, None)
    model.set_display_size(320, 240)
    f = model.decode(msg)
    # OpenCV's reduced decoding itself (1/2 scale), not a full decode shrunk afterwards
    assert np.array_equal(f.rgb, cv2.imdecode(buf, cv2.IMREAD_REDUCED_COLOR_2)[..., ::-1])
    assert (f.width, f.height, f.pixel_width, f.pixel_height) == (640, 480, 320, 240)
    assert mean_abs_diff(f.rgb, area(full, 320, 240)) < 1.5
    # a box of another shape: the picture fitted into it (letterboxed) decides, 320x260 -> still 320x240
    model.set_display_size(320, 260)
    assert model.decode(msg).rgb.shape == (240, 320, 3)
    # 1/8 is the largest reduction; below that an area shrink on top: 50x50 -> 50x38
    model.set_display_size(50, 50)
    small = model.decode(msg)
    assert small.rgb.shape == (38, 50, 3) and mean_abs_diff(small.rgb, area(full, 50, 38)) < 2.5
    # between two reductions: the 1/2 decode, then resized to exactly the fitted 300x225 (drawn 1:1)
    model.set_display_size(300, 300)
    between = model.decode(msg)
    assert between.rgb.shape == (225, 300, 3) and mean_abs_diff(between.rgb, area(full, 300, 225)) < 2.5
    model.set_display_size(0, 0)
    assert np.array_equal(model.decode(msg).rgb, full)


@pytest.mark.parametrize("encoding", ["rgb8", "bgr8", "mono8"])
def test_a_raw_frame_is_shrunk_to_the_display_size_with_area_interpolation(encoding):
    rgb = picture()
    msg = raw_msg(rgb, encoding)
    model = ImageModel(ImageSettings(), RAW, None)
    full = model.decode(msg).rgb  # no display size yet: full resolution
    assert full.shape == (480, 640, 3)
    model.set_display_size(320, 240)
    f = model.decode(msg)
    assert f.rgb.shape == (240, 320, 3) and (f.width, f.height) == (640, 480)
    assert f.info == f"640×480 {encoding}"
    assert mean_abs_diff(f.rgb, area(full, 320, 240)) < 1.0
    model.set_display_size(200.4, 1000)  # device pixels may be fractional: rounded up
    assert model.display_size == (201, 1000)
    assert model.decode(msg).rgb.shape == (151, 201, 3)


@pytest.mark.parametrize("display", [(200, 150), (100, 80), (500, 400), (400, 300), (50, 38)])
@pytest.mark.parametrize("odd", [False, True])
def test_a_shrink_to_any_size_is_close_to_an_area_resize(display, odd):
    """Area halvings, then bilinear for a rest under 2x (fast); odd sides stop the halving early."""
    rgb = picture()
    if odd:
        rgb = np.ascontiguousarray(rgb[:479, :639])
    h, w = rgb.shape[:2]
    scale = min(display[0] / w, display[1] / h)
    out = shrink(rgb, scale)
    want = (int(np.ceil(h * scale - 1e-9)), int(np.ceil(w * scale - 1e-9)))
    assert out.shape[:2] == want or (scale * 1.2 >= 1 and out.shape[:2] == (h, w))
    assert mean_abs_diff(out, area(rgb, out.shape[1], out.shape[0])) < 1.0


def test_never_upscaled_and_a_small_excess_made_the_exact_fitted_size():
    rgb = picture()
    model = ImageModel(ImageSettings(), RAW, None)
    model.set_display_size(2000, 1500)
    assert model.decode(raw_msg(rgb)).rgb.shape == (480, 640, 3)
    # 640 is only 1.07x too big: shrink() leaves it, the model still makes it the fitted 600x450 (drawn 1:1)
    model.set_display_size(600, 450)
    assert shrink(rgb, 600 / 640) is rgb
    near = model.decode(raw_msg(rgb))
    assert near.rgb.shape == (450, 600, 3) and mean_abs_diff(near.rgb, area(rgb, 600, 450)) < 1.5
    model.set_display_size(640, 400)  # 480 rows into 400: fitted 533.33 -> 533 x 400
    assert model.decode(raw_msg(rgb)).rgb.shape == (400, 533, 3)
    model.set_display_size(640, 480)  # exactly the source's size: the array itself, no resize
    assert model.decode(raw_msg(rgb)).rgb.shape == (480, 640, 3)
    tiny = np.ascontiguousarray(rgb[::10, ::10])  # 64x48 source into a 320x240 box: stays 64x48
    f = model.decode(raw_msg(tiny))
    assert f.rgb.shape == (48, 64, 3) and (f.width, f.height) == (64, 48)
    jpeg = ImageModel(ImageSettings(), JPEG, None)
    jpeg.set_display_size(2000, 1500)
    assert jpeg.decode(jpeg_msg(rgb)).rgb.shape == (480, 640, 3)


def test_png_and_broken_jpegs():
    rgb = picture()
    ok, png = cv2.imencode(".png", cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR))
    assert ok
    d = decode_compressed_sized({"format": "png", "data": png.tobytes()}, None, (160, 120))
    assert d.rgb.shape == (120, 160, 3) and (d.width, d.height) == (640, 480)
    assert mean_abs_diff(d.rgb, area(rgb, 160, 120)) < 1.0
    data = encode_jpeg(rgb)
    assert jpeg_size(data) == (640, 480)
    assert jpeg_size(b"\xff\xd8\xff\xe0\x00") is None and jpeg_size(b"\xff\xd8garbage") is None
    with pytest.raises(DecodeError, match="could not decode the JPEG image"):
        decode_compressed({"format": "jpeg", "data": data[:40]}, None, (160, 120))


# -- view ----------------------------------------------------------------------------------------------------
@pytest.fixture
def view(qtbot):
    v = ImageView(ImageModel(ImageSettings(), RAW, None))
    qtbot.addWidget(v)
    v.resize(320, 240)
    v.show()
    QTest.qWaitForWindowExposed(v)
    yield v
    v.model.on_stop()


def device(view, w, h, zoom=1.0):
    k = view.devicePixelRatioF() * zoom
    return (int(np.ceil(w * k - 1e-6)), int(np.ceil(h * k - 1e-6)))


def test_resize_and_zoom_reach_the_model(view, qtbot):
    model = view.model
    assert model.display_size == device(view, 320, 240)
    view.resize(200, 100)
    assert model.display_size == device(view, 200, 100)
    feed(view, raw_msg(grid_picture()))
    wheel(view, 2)  # zoom x1.5625
    assert view.viewport.zoom == pytest.approx(1.5625)
    assert model.display_size == device(view, 200, 100, 1.5625)
    QTest.mouseDClick(view, QtCore.Qt.MouseButton.LeftButton, pos=QtCore.QPoint(100, 50))  # fit again
    assert view.viewport.fitted and model.display_size == device(view, 200, 100)


def test_the_smaller_frame_is_painted_where_the_full_one_would_be(view, qtbot):
    src = grid_picture()
    frame = feed(view, raw_msg(src))
    side = device(view, 320, 240)
    assert (frame.pixel_width, frame.pixel_height) == (min(640, side[0]), min(480, side[1]))
    assert (frame.width, frame.height) == (640, 480)
    assert view.viewport.image_w == 640 and view.viewport.image_h == 480  # zoom/pan work in source pixels

    def check_cells():
        img = view.grab().toImage()
        seen = 0
        for r in range(4):
            for c in range(4):
                sx, sy = (c + 0.5) * 160, (r + 0.5) * 120  # the cell's centre in source pixels
                x0, y0, ww, hh = view.viewport.rect()
                wx, wy = x0 + sx * ww / 640, y0 + sy * hh / 480
                if not (4 <= wx < view.width() - 4 and 4 <= wy < view.height() - 4):
                    continue  # zoomed: out of sight
                if view.overlay_rect.adjusted(-2, -2, 2, 2).contains(int(wx), int(wy)):
                    continue
                got = img.pixelColor(int(wx), int(wy))
                want = src[int(sy), int(sx)]
                assert abs(got.red() - want[0]) <= 3 and abs(got.green() - want[1]) <= 3 and \
                    abs(got.blue() - want[2]) <= 3, (r, c, got.getRgb(), want)
                seen += 1
        return seen

    assert check_cells() >= 14  # the whole picture fills the 320x240 view (the overlay hides a cell or two)
    wheel(view, 4)  # zoom x2.44: the view now wants more pixels than the source has
    assert view.model.display_size == device(view, 320, 240, 1.25 ** 4)
    zoomed = feed(view, raw_msg(src))
    assert zoomed.rgb.shape == (480, 640, 3)  # full resolution when zoomed in
    assert check_cells() >= 1


def test_a_camera_preview_has_no_display_size_and_is_painted_whole(qtbot):
    """The Camera widget's view is the Image view over a model that publishes what it captures: it gets no
    display size (its preview is the published picture itself) and paints as before."""
    model = CameraModel(CameraSettings(source="test pattern"), Binding("/c", "sensor_msgs/Image", "publish"), None)
    v = CameraView(model)
    qtbot.addWidget(v)
    v.resize(320, 240)
    v.show()
    assert v.display_size_sent is None and not hasattr(model, "set_display_size")
    now = time.time()
    model.set_value(Frame(rgb=grid_picture(), kind="camera", info="preview", stamp=now, received=now,
                          decoded=now, index=1))
    v.refresh(model.state)
    img = v.grab().toImage()
    x0, y0, ww, hh = v.viewport.rect()
    got = img.pixelColor(int(x0 + ww * 7 / 8), int(y0 + hh * 7 / 8))  # the bottom right cell
    want = grid_picture()[420, 560]
    assert max(abs(got.red() - want[0]), abs(got.green() - want[1]), abs(got.blue() - want[2])) <= 3
