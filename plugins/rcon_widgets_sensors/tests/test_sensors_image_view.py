"""Image view offscreen: paints the newest frame letterboxed, overlay, pinch/pan/double-tap, a laser scan.
(The README's pictures are made by docs/make_screenshots.py, not by the tests.)"""

import math
import time

import attrs
import numpy as np
import pytest
from qtpy import QtCore, QtGui
from qtpy.QtTest import QTest
from rcon_widgets_sensors.image import Frame, ImageModel, ImageSettings
from rcon_widgets_sensors.image_view import ImageView
from rcon_widgets_sensors.viewport import Viewport

from rcon_core.plugins import Binding
from rcon_core.sim.camera import CameraRenderer, encode_jpeg
from rcon_core.sim.vessel import Vessel


def feed(model, msg):
    before = model.state.value.index if isinstance(model.state.value, Frame) else 0
    model.on_message(msg)
    return model.wait_frame(before, 5.0)


def camera_msg():
    stamp = time.time()
    img = CameraRenderer("front").frame(Vessel(), stamp)
    return {"header": {"stamp": {"secs": int(stamp), "nsecs": int(stamp % 1 * 1e9)}, "frame_id": "cam"},
            "format": "jpeg", "data": encode_jpeg(img)}


@pytest.fixture
def view(qtbot):
    model = ImageModel(ImageSettings(), Binding("/camera/rear/image_raw/compressed", "sensor_msgs/CompressedImage",
                                                "subscribe"), None)
    v = ImageView(model)
    qtbot.addWidget(v)
    v.resize(480, 320)
    v.show()
    yield v
    model.on_stop()


def grab(view):
    return view.grab().toImage()


def test_paints_the_frame_letterboxed_with_overlay(view, qtbot):
    frame = feed(view.model, camera_msg())
    painted = []
    view.on_painted = lambda f, t: painted.append((f.index, t))
    view.refresh(view.model.state)
    qtbot.waitUntil(lambda: bool(painted), timeout=3000)
    assert painted[0][0] == frame.index
    img = grab(view)
    # 640x480 into 480x320: 426.7 px wide, centred -> dark bars left and right, picture in the middle
    left, mid = img.pixelColor(5, 300), img.pixelColor(240, 100)
    assert (left.red(), left.green(), left.blue()) == (14, 17, 22)
    assert mid.blue() > 100  # the sky
    # the overlay box is in the top left corner over the picture
    assert view.painted_fps >= 0 and "640×480 jpeg" in frame.info


def test_waiting_and_error_texts(view, qtbot):
    view.refresh(view.model.state)
    view.model.set_error("could not decode the JPEG image (12 bytes; format 'jpeg')")
    view.refresh(view.model.state)
    assert view.frame is None
    grab(view)  # paints without a frame (no exception)


def test_viewport_arithmetic():
    vp = Viewport(480, 320, 640, 480)
    x, y, w, h = vp.rect()
    assert math.isclose(w, 426.666, rel_tol=1e-3) and h == 320 and math.isclose(x, 26.666, rel_tol=1e-3)
    ix, iy = vp.to_image(240, 160)
    assert math.isclose(ix, 320) and math.isclose(iy, 240)
    vp.zoom_at(2.0, 100, 100)  # the image point under (100, 100) stays there
    before = Viewport(480, 320, 640, 480).to_image(100, 100)
    after = vp.to_image(100, 100)
    assert math.isclose(before[0], after[0], abs_tol=1e-6) and math.isclose(before[1], after[1], abs_tol=1e-6)
    vp.pan_by(10_000, 0)  # cannot throw the image away
    assert vp.rect()[0] < 480
    vp.zoom_at(100, 0, 0)
    assert vp.zoom == 16.0
    vp.fit()
    assert vp.fitted


def touch_device():
    return QTest.createTouchDevice()


def test_pinch_zooms_pan_moves_double_tap_fits(view, qtbot):
    feed(view.model, camera_msg())
    view.refresh(view.model.state)
    dev = touch_device()
    c = QtCore.QPoint(240, 160)
    QTest.touchEvent(view, dev).press(0, c - QtCore.QPoint(40, 0), view).press(1, c + QtCore.QPoint(40, 0), view)
    for step in range(1, 6):
        d = 40 + step * 16
        QTest.touchEvent(view, dev).move(0, c - QtCore.QPoint(d, 0), view).move(1, c + QtCore.QPoint(d, 0), view)
    QTest.touchEvent(view, dev).release(0, c - QtCore.QPoint(120, 0), view).release(1, c + QtCore.QPoint(120, 0),
                                                                                    view)
    assert view.viewport.zoom == pytest.approx(3.0, rel=0.05)  # fingers 80 px -> 240 px apart
    z_rect = view.viewport.rect()
    # one finger drags the picture
    QTest.touchEvent(view, dev).press(0, c, view)
    QTest.touchEvent(view, dev).move(0, c + QtCore.QPoint(30, 20), view)
    QTest.touchEvent(view, dev).release(0, c + QtCore.QPoint(30, 20), view)
    moved = view.viewport.rect()
    assert moved[0] == pytest.approx(z_rect[0] + 30) and moved[1] == pytest.approx(z_rect[1] + 20)
    # double tap fits again
    for _ in range(2):
        QTest.touchEvent(view, dev).press(0, c, view)
        QTest.touchEvent(view, dev).release(0, c, view)
    assert view.viewport.fitted


def test_mouse_wheel_and_double_click(view, qtbot):
    feed(view.model, camera_msg())
    view.refresh(view.model.state)
    pos = QtCore.QPointF(240, 160)
    ev = QtGui.QWheelEvent(pos, view.mapToGlobal(pos), QtCore.QPoint(), QtCore.QPoint(0, 240),
                           QtCore.Qt.MouseButton.NoButton, QtCore.Qt.KeyboardModifier.NoModifier,
                           QtCore.Qt.ScrollPhase.NoScrollPhase, False)
    view.wheelEvent(ev)
    assert view.viewport.zoom == pytest.approx(1.5625)
    QTest.mouseDClick(view, QtCore.Qt.MouseButton.LeftButton, pos=QtCore.QPoint(240, 160))
    assert view.viewport.fitted


def test_a_laser_scan_is_drawn_as_a_scan(qtbot):
    model = ImageModel(None, Binding("/scan", "sensor_msgs/LaserScan", "subscribe"), None)
    view = ImageView(model)
    qtbot.addWidget(view)
    view.resize(360, 360)
    view.show()
    from rcon_core.sim import world
    lidar = world.Lidar()
    ranges = lidar.scan(0.0, 0.0, math.radians(30)).astype(np.float64)
    msg = {"header": {"stamp": {"secs": int(time.time()), "nsecs": 0}}, "angle_min": lidar.angle_min,
           "angle_max": lidar.angle_max, "angle_increment": lidar.angle_increment, "range_min": lidar.range_min,
           "range_max": lidar.range_max, "ranges": [None if not np.isfinite(r) else float(r) for r in ranges]}
    frame = feed(model, msg)
    view.refresh(model.state)
    assert frame.kind == "scan" and frame.counts.valid > 0
    assert view.frame is frame  # the view shows it
    model.on_stop()


class PaintRects(QtCore.QObject):
    """Records the rectangle of every paint event of a widget."""

    def __init__(self, widget):
        super().__init__()
        self.rects = []
        widget.installEventFilter(self)

    def eventFilter(self, obj, event):  # noqa: N802 - Qt override
        if event.type() == QtCore.QEvent.Type.Paint:
            self.rects.append(event.rect())
        return False


def test_overlay_ages_and_says_stale_without_new_frames(view, qtbot):
    """Link down: no new frame, so no refresh; the overlay must still age and say STALE (it showed
    '10.0 fps · age 97 ms' twelve seconds later), repainting only its own rectangle."""

    frame = feed(view.model, camera_msg())
    view.refresh(view.model.state)
    qtbot.waitUntil(lambda: bool(view.overlay_text), timeout=3000)
    assert "fps · age" in view.overlay_text[0] and view.stale_for() is None
    old = time.time() - 12.0  # as if this frame came 12 s ago and nothing since
    view.frame = attrs.evolve(frame, received=old, stamp=old, decoded=old)
    paints = PaintRects(view)
    qtbot.waitUntil(lambda: view.overlay_text and view.overlay_text[0].startswith("STALE"), timeout=3000)
    first = view.overlay_text[0]
    assert first.startswith("STALE · no new frame for 1") and "fps" not in first
    view.frame = attrs.evolve(view.frame, received=old - 60)  # a minute later, still nothing
    qtbot.waitUntil(lambda: view.overlay_text[0] != first, timeout=3000)
    assert view.overlay_text[0] in {f"STALE · no new frame for {n} s" for n in range(72, 80)}
    assert paints.rects and all(r.width() < view.width() // 2 and r.height() < view.height() // 2
                                for r in paints.rects), "the ticker repainted more than the overlay"
    img = grab(view)
    c = QtGui.QColor(img.pixel(view.overlay_rect.left() + 2, view.overlay_rect.top() + 2))
    assert c.red() > 120 and c.blue() < 60  # amber: cannot pass for the dark live overlay


def test_overlay_ticker_leaves_a_fresh_picture_alone(view, qtbot):
    frame = feed(view.model, camera_msg())
    view.refresh(view.model.state)
    qtbot.waitUntil(lambda: bool(view.overlay_text), timeout=3000)
    view.frame = attrs.evolve(frame, received=time.time())
    view.age_overlay()  # a fresh frame: the ticker schedules nothing
    paints = PaintRects(view)
    QtCore.QCoreApplication.processEvents()
    assert paints.rects == []


def test_an_rgb8_frame_is_painted_with_its_own_colours(view, qtbot):
    """The view paints the frame's RGB32 copy (made by the decode worker, so the GUI thread converts no
    format): red, green, blue and a grey stay themselves, in the right places."""
    h, w = 48, 64
    rgb = np.zeros((h, w, 3), np.uint8)
    rgb[: h // 2, : w // 2] = (220, 30, 10)
    rgb[: h // 2, w // 2:] = (20, 200, 40)
    rgb[h // 2:, : w // 2] = (15, 25, 210)
    rgb[h // 2:, w // 2:] = (128, 128, 128)
    msg = {"header": {"stamp": {"secs": 1, "nsecs": 0}, "frame_id": "cam"}, "height": h, "width": w,
           "encoding": "rgb8", "is_bigendian": 0, "step": w * 3, "data": rgb.tobytes()}
    frame = feed(view.model, msg)
    assert frame.rgb32.shape == (h, w, 4) and frame.rgb32.dtype == np.uint8
    view.resize(w * 4, h * 4)  # fits exactly: the picture fills the widget
    view.refresh(view.model.state)
    qtbot.waitUntil(lambda: view.frame is frame, timeout=3000)
    img = grab(view)
    x0, y0, ww, hh = view.viewport.rect()

    def at(fx, fy):
        c = img.pixelColor(int(x0 + fx * ww), int(y0 + fy * hh))
        return c.red(), c.green(), c.blue()

    def near(a, b):
        return all(abs(p - q) <= 3 for p, q in zip(a, b, strict=True))

    assert near(at(0.25, 0.6 * 0.5), (220, 30, 10))
    assert near(at(0.75, 0.6 * 0.5), (20, 200, 40))
    assert near(at(0.25, 0.75), (15, 25, 210))
    assert near(at(0.75, 0.75), (128, 128, 128))
