"""The Image view draws a fitted frame 1:1: the decode worker makes the pixel array exactly the rectangle
the picture fills in device pixels, and the view copies it unscaled; zoomed, resized before a new frame,
or a picture smaller than the view, it draws scaled as before. The arithmetic at device pixel ratios 1,
1.5 and 2 (pure functions), the real offscreen view at ratio 1, and at 1.5 and 2 in a subprocess
(``QT_SCALE_FACTOR``)."""

import json
import os
import subprocess
import sys

import cv2
import numpy as np
import pytest
from image_helpers import feed, grab_rgb, mean_abs_diff, picture, raw_msg
from qtpy import QtCore
from qtpy.QtTest import QTest
from rcon_widgets_sensors.decode import resize_exactly
from rcon_widgets_sensors.image import ImageModel, ImageSettings
from rcon_widgets_sensors.image_view import ImageView
from rcon_widgets_sensors.viewport import device_box, fitted_pixels, unscaled_origin
from sensors_helpers import wheel

from rcon_core.plugins import Binding

RAW = Binding("/camera/front/image_raw", "sensor_msgs/Image", "subscribe")


# -- the arithmetic (no Qt), with faked device pixel ratios ---------------------------------------------------
@pytest.mark.parametrize(("ratio", "box", "rect"), [
    (1.0, (301, 221), (3, 0, 295, 221)),      # 640x480 fitted by height: 294.7 -> 295 wide, centred
    (1.5, (452, 332), (4, 0, 443, 332)),      # 451.5 x 331.5 device pixels, rounded up to whole ones
    (2.0, (602, 442), (6, 0, 589, 442)),
])
def test_the_fitted_rectangle_in_device_pixels(ratio, box, rect):
    assert device_box(301, 221, ratio) == box
    assert fitted_pixels(box, 640, 480) == rect
    x, y, w, h = rect
    # the view's choice: this array size -> 1:1 at the rectangle's corner in widget pixels
    assert unscaled_origin(301, 221, ratio, 640, 480, w, h, fitted=True) == pytest.approx((x / ratio, y / ratio))
    # one pixel off (a frame decoded for another size), zoomed, or no ratio: the scaled draw
    assert unscaled_origin(301, 221, ratio, 640, 480, w - 1, h, fitted=True) is None
    assert unscaled_origin(301, 221, ratio, 640, 480, w, h, fitted=False) is None
    assert unscaled_origin(301, 221, 0.0, 640, 480, w, h, fitted=True) is None
    assert device_box(301, 221, ratio, zoom=2.0) == (int(np.ceil(602 * ratio - 1e-6)), int(np.ceil(442 * ratio - 1e-6)))


def test_fitted_pixels_by_width_and_degenerate_sizes():
    assert fitted_pixels((300, 400), 640, 480) == (0, 87, 300, 225)  # letterboxed above and below
    assert fitted_pixels((100, 100), 1, 1000) == (49, 0, 1, 100)  # never narrower than a pixel; centred, rounded down
    assert fitted_pixels((50, 40), 0, 480) == (0, 0, 50, 40)


@pytest.mark.parametrize("ratio", [1.0, 1.5, 2.0])
def test_the_worker_makes_exactly_what_the_view_draws_1_to_1(ratio):
    """The model gets the device box from the view and makes the array the size the view then draws
    unscaled, at any device pixel ratio."""
    src = picture()
    model = ImageModel(ImageSettings(), RAW, None)
    model.set_display_size(*device_box(301, 221, ratio))
    f = model.decode(raw_msg(src))
    x, y = unscaled_origin(301, 221, ratio, f.width, f.height, f.pixel_width, f.pixel_height, fitted=True)
    assert (x, y) == pytest.approx((fitted_pixels(device_box(301, 221, ratio), 640, 480)[0] / ratio, 0.0))
    w, h = f.pixel_width, f.pixel_height
    assert mean_abs_diff(f.rgb, cv2.resize(src, (w, h), interpolation=cv2.INTER_AREA)) < 2.0


def test_resize_exactly():
    src = picture()
    assert resize_exactly(src, 640, 480) is src
    out = resize_exactly(src, 161, 117)  # halvings to 320x240, then bilinear the rest
    assert out.shape == (117, 161, 3) and mean_abs_diff(out, cv2.resize(src, (161, 117),
                                                                        interpolation=cv2.INTER_AREA)) < 2.0
    with pytest.raises(ValueError, match="cannot become 641x480"):
        resize_exactly(src, 641, 480)


# -- the real view offscreen at ratio 1 ---------------------------------------------------------------------
@pytest.fixture
def view(qtbot):
    v = ImageView(ImageModel(ImageSettings(show_overlay=False), RAW, None))
    qtbot.addWidget(v)
    v.resize(301, 221)
    v.show()
    QTest.qWaitForWindowExposed(v)
    yield v
    v.model.on_stop()


def painted(view):
    """The pixels in the fitted rectangle of the view's grab (ratio 1)."""
    x, y, w, h = fitted_pixels(device_box(view.width(), view.height(), 1.0), 640, 480)
    return grab_rgb(view)[y:y + h, x:x + w]


def test_a_fitted_frame_is_drawn_1_to_1_and_a_zoom_goes_back_to_scaling(view, qtbot):
    if view.devicePixelRatioF() != 1.0:
        pytest.skip("this test reads the grab at device pixel ratio 1 (the subprocess test covers 1.5 and 2)")
    src = picture()
    frame = feed(view, raw_msg(src))
    assert (frame.pixel_width, frame.pixel_height) == (295, 221)  # exactly the fitted rectangle
    got = painted(view)
    assert view.drawn_unscaled
    assert np.array_equal(got, frame.rgb)  # a plain copy: the array's own pixels
    assert mean_abs_diff(got, cv2.resize(src, (295, 221), interpolation=cv2.INTER_AREA)) < 2.0

    # resized: the frame on screen was made for the old size -> scaled, still filling the view
    view.resize(400, 300)
    qtbot.waitUntil(lambda: view.model.display_size == (400, 300))
    stretched = painted(view)
    assert not view.drawn_unscaled and stretched.shape == (300, 400, 3)
    assert mean_abs_diff(stretched, cv2.resize(src, (400, 300), interpolation=cv2.INTER_AREA)) < 6.0
    # the next frame is made for the new size and drawn 1:1 again
    frame = feed(view, raw_msg(src))
    assert (frame.pixel_width, frame.pixel_height) == (400, 300)
    assert np.array_equal(painted(view), frame.rgb) and view.drawn_unscaled

    # zoomed in: the scaled path, and the next frame at full resolution
    wheel(view, 4)
    assert not view.viewport.fitted
    view.grab()
    assert not view.drawn_unscaled
    frame = feed(view, raw_msg(src))
    assert frame.rgb.shape == (480, 640, 3)
    view.grab()
    assert not view.drawn_unscaled
    # fitted again (double click): once the next frame comes at the fitted size, 1:1 again
    QTest.mouseDClick(view, QtCore.Qt.MouseButton.LeftButton, pos=QtCore.QPoint(200, 150))
    frame = feed(view, raw_msg(src))
    assert (frame.pixel_width, frame.pixel_height) == (400, 300)
    assert np.array_equal(painted(view), frame.rgb) and view.drawn_unscaled


def test_a_picture_smaller_than_the_view_is_scaled_up_by_the_painter(view, qtbot):
    small = np.ascontiguousarray(picture()[::4, ::4])  # 160x120 into 301x221: never upscaled by the worker
    frame = feed(view, raw_msg(small))
    assert frame.rgb.shape == (120, 160, 3)
    view.grab()
    assert not view.drawn_unscaled


# -- a real device pixel ratio of 1.5 and 2: offscreen Qt scaled in a subprocess ---------------------------------
_PROBE = r"""
import json, time
import numpy as np
from qtpy import QtGui, QtWidgets
from qtpy.QtTest import QTest
from rcon_widgets_sensors.image import ImageModel, ImageSettings
from rcon_widgets_sensors.image_view import ImageView
from rcon_widgets_sensors.viewport import device_box, fitted_pixels
from rcon_core.plugins import Binding
from rcon_core.sim.camera import CameraRenderer
from rcon_core.sim.vessel import Vessel

app = QtWidgets.QApplication([])
src = CameraRenderer("front").frame(Vessel(), time.time())
msg = {"header": {"stamp": {"secs": 1, "nsecs": 0}, "frame_id": "c"}, "height": 480, "width": 640,
       "encoding": "rgb8", "is_bigendian": 0, "step": 1920, "data": src.tobytes()}
model = ImageModel(ImageSettings(show_overlay=False), Binding("/c", "sensor_msgs/Image", "subscribe"), None)
view = ImageView(model)
view.resize(301, 221)
view.show()
QTest.qWaitForWindowExposed(view)
model.on_message(msg)
frame = model.wait_frame(0, 5.0)
view.refresh(model.state)
img = view.grab().toImage().convertToFormat(QtGui.QImage.Format.Format_RGB888)
rows = np.frombuffer(img.constBits(), np.uint8, img.sizeInBytes()).reshape(img.height(), img.bytesPerLine())
got = rows[:, :img.width() * 3].reshape(img.height(), img.width(), 3)
ratio = view.devicePixelRatioF()
x, y, w, h = fitted_pixels(device_box(301, 221, ratio), 640, 480)
part = got[y:y + h, x:x + w]
same = part.shape == frame.rgb.shape and bool(np.array_equal(part, frame.rgb))
print(json.dumps({"ratio": ratio, "unscaled": view.drawn_unscaled, "array": [frame.pixel_width, frame.pixel_height],
                  "rect": [x, y, w, h], "same": same}))
model.on_stop()
"""


@pytest.mark.parametrize("factor", ["1.5", "2"])
def test_a_real_device_pixel_ratio_draws_1_to_1(factor):
    env = dict(os.environ, QT_QPA_PLATFORM="offscreen", QT_SCALE_FACTOR=factor)
    out = subprocess.run([sys.executable, "-c", _PROBE], env=env, capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr[-2000:]
    got = json.loads(out.stdout.strip().splitlines()[-1])
    assert got["ratio"] == float(factor)
    assert got["array"] == got["rect"][2:]  # made exactly the fitted rectangle in device pixels
    assert got["unscaled"] and got["same"]  # drawn 1:1: the device pixels are the array's own
