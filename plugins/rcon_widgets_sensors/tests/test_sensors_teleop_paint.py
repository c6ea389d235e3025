"""The teleop pad paints what stays put (background, disc, rings, axes, axis labels) once into cached
pixmaps: moving the finger repaints only the knob, trail and status line over them; a resize, another
dead zone, other axes or another palette repaint the cache, and the picture shows the change."""

import numpy as np
import pytest
from qtpy import QtCore, QtGui
from qtpy.QtTest import QTest
from rcon_widgets_sensors.teleop import TeleopModel, TeleopSettings
from rcon_widgets_sensors.teleop_view import TeleopView

from rcon_core.app.link import OFFLINE
from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import Binding

KNOB = (70, 160, 255)  # the knob's fill while a finger holds it


@pytest.fixture
def make(qtbot):
    models = []

    def make_pad(w=300, h=300, **settings):
        """An offline preview pad (nothing reaches a robot), shown at w x h."""
        model = TeleopModel(TeleopSettings(**settings), Binding("/cmd_vel", "geometry_msgs/Twist", "publish"),
                            OFFLINE.node("paint-pad"), types=TypeRegistry.standard())
        model.dry_run = True
        model.set_link(False)
        model.start()
        models.append(model)
        view = TeleopView(model)
        qtbot.addWidget(view)
        view.resize(w, h)
        view.show()
        QTest.qWaitForWindowExposed(view)
        view.refresh(model.state)
        return view

    yield make_pad
    for m in models:
        m.stop()


def grab(view):
    """The view's picture in device pixels, H x W x 3."""
    img = view.grab().toImage().convertToFormat(QtGui.QImage.Format.Format_RGB888)
    rows = np.frombuffer(img.constBits(), np.uint8, img.sizeInBytes()).reshape(img.height(), img.bytesPerLine())
    return rows[:, :img.width() * 3].reshape(img.height(), img.width(), 3).copy()


def at(view, pic, point):
    k = view.devicePixelRatioF()
    return tuple(int(v) for v in pic[int(point.y() * k), int(point.x() * k)])


def near(rgb, want, tol=12):
    return max(abs(a - b) for a, b in zip(rgb, want, strict=True)) <= tol


def labels_strip(view, pic):
    return pic[:int(18 * view.devicePixelRatioF())]


def test_the_knob_moves_over_the_cached_pad_without_repainting_the_cache(make):
    view = make()
    grab(view)
    built = view.layer_builds
    assert built >= 1
    c, r = view.pad()
    a, b = c + QtCore.QPointF(-0.5 * r, -0.4 * r), c + QtCore.QPointF(0.5 * r, 0.3 * r)
    QTest.mousePress(view, QtCore.Qt.MouseButton.LeftButton, QtCore.Qt.KeyboardModifier.NoModifier, a.toPoint())
    first = grab(view)
    assert near(at(view, first, a), KNOB)
    QTest.mouseMove(view, b.toPoint())
    second = grab(view)
    assert near(at(view, second, b), KNOB) and not near(at(view, second, a), KNOB)
    QTest.mouseRelease(view, QtCore.Qt.MouseButton.LeftButton, QtCore.Qt.KeyboardModifier.NoModifier, b.toPoint())
    released = grab(view)
    assert not near(at(view, released, b), KNOB)  # back in the middle, grey
    assert view.layer_builds == built  # the finger never repainted the backdrop or the labels


def test_a_resize_repaints_the_cache_at_the_new_size(make):
    view = make(300, 300)
    small = grab(view)
    built = view.layer_builds
    view.resize(420, 360)
    big = grab(view)
    assert view.layer_builds == built + 1
    k = view.devicePixelRatioF()
    assert big.shape[:2] == (int(round(360 * k)), int(round(420 * k))) != small.shape[:2]
    c, r = view.pad()
    ring = at(view, big, QtCore.QPointF(c.x() - r, c.y()))  # the pad's ring where the new radius puts it
    assert near(ring, (120, 128, 140), 40), ring
    # the whole picture is what a pad made at that size paints
    assert np.array_equal(big, grab(make(420, 360)))


@pytest.mark.parametrize("change", [{"vertical": "linear.y"}, {"horizontal": "angular.z"}, {"dead_zone": 0.4}])
def test_other_axes_or_dead_zone_repaint_the_cache(make, change):
    view = make(300, 300, dead_zone=0.1)
    before = grab(view)
    built = view.layer_builds
    for name, value in change.items():
        setattr(view.model.settings, name, value)
    view.update()
    after = grab(view)
    assert view.layer_builds == built + 1
    assert not np.array_equal(after, before)
    if "dead_zone" not in change:  # the label's text changed in the picture, the pad did not
        assert not np.array_equal(labels_strip(view, after), labels_strip(view, before))
    assert np.array_equal(after, grab(make(300, 300, **{"dead_zone": 0.1, **change})))


def test_a_palette_change_repaints_the_cache(make):
    view = make()
    grab(view)
    built = view.layer_builds
    pal = QtGui.QPalette(view.palette())
    pal.setColor(QtGui.QPalette.ColorRole.Window, QtGui.QColor(10, 20, 30))
    pal.setColor(QtGui.QPalette.ColorRole.WindowText, QtGui.QColor(250, 240, 90))
    view.setPalette(pal)
    pic = grab(view)
    assert view.layer_builds == built + 1
    assert at(view, pic, QtCore.QPointF(2, view.height() / 2)) == (10, 20, 30)  # the new background
    strip = labels_strip(view, pic).reshape(-1, 3).astype(int)
    assert (np.abs(strip - (250, 240, 90)).max(axis=1) <= 30).any()  # the labels in the new text colour
