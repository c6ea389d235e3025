"""The map's "every marker in view" mode (``fit_all`` and the Fit button) against the sim: the vessel's
fix and a second fix published on the sim a few hundred metres off, both in view from the start and again
when one leaves the view; panning, zooming, pinching or Follow by hand stop it for good; Fit brings it
back; a narrow map puts its buttons on two rows and keeps the markers clear of them."""

from __future__ import annotations

import pytest
from map_helpers import make_view
from qtpy import QtCore
from rcon_widgets_map import mercator
from rcon_widgets_map.model import MapModel
from rcon_widgets_map.settings import MapSettings
from rcon_widgets_map.view import MapView

from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import Binding

TYPES = TypeRegistry.standard()
Qt = QtCore.Qt


@pytest.fixture
def two_fixes(qtbot, sim_thread, threaded_client):
    """``(model, publish(east_m, north_m), wait_other(east_m, north_m))``: a started map of the vessel's
    fix plus ``other=/other/fix``, with ``fit_all``; ``publish`` puts the other fix that far from the
    vessel, ``wait_other`` waits until the map has it there."""
    bt, client = threaded_client
    model = MapModel(MapSettings(extra_topics="other=/other/fix", fit_all=True, zoom=18.0, goal_topic=""),
                     Binding("/gps/fix", "sensor_msgs/NavSatFix", "subscribe"), client.node("map-fit"),
                     types=TYPES, dispatch=bt.call)
    bt.call(model.start).result(5)
    qtbot.waitUntil(lambda: model.state.value is not None and model.state.value.main.has_position, timeout=10_000)
    other = client.node("other").advertise("/other/fix", "sensor_msgs/NavSatFix")

    def where(east, north):
        main = model.state.value.main
        return mercator.offset_m(main.lat, main.lon, east, north)

    def publish(east, north):
        msg = TYPES.default("sensor_msgs/NavSatFix")
        msg["latitude"], msg["longitude"] = where(east, north)
        bt.call(other.publish, msg).result(5)

    def wait_other(east, north):
        lat, lon = where(east, north)

        def there():
            publish(east, north)
            track = model.state.value.track("/other/fix")
            return track is not None and track.has_position and mercator.haversine_m(
                track.lat, track.lon, lat, lon) < 5.0
        qtbot.waitUntil(there, timeout=10_000)

    yield model, publish, wait_other
    bt.call(model.stop).result(5)


def in_view(view) -> list[bool]:
    """For each marker with a position: whether it lies on the map, clear of the buttons' corner."""
    block = view.controls_rect().adjusted(-10, -10, 10, 10)
    out = []
    for t in view.value.tracks:
        if t.has_position:
            x, y = view.viewport.to_screen(t.lat, t.lon)
            out.append(view.viewport.shows(t.lat, t.lon) and not block.contains(QtCore.QPoint(round(x), round(y))))
    return out


def test_both_markers_stay_in_view_until_the_map_is_moved_by_hand(qtbot, two_fixes):
    model, publish, wait_other = two_fixes
    wait_other(300.0, 200.0)
    view = make_view(qtbot, model)
    assert view.fit.fitting and not view.following and view.fit.button.isChecked()
    assert in_view(view) == [True, True]
    first = view.viewport.zoom
    assert 14.0 < first < 18.0  # zoomed out as far as both need, no further
    # the other fix moves well out of view: the map fits again, further out
    wait_other(-1500.0, 900.0)
    view.refresh(model.state)
    assert in_view(view) == [True, True]
    assert view.viewport.zoom < first - 1.0
    # a drag by hand: the map stays where the finger left it, whatever the fixes do
    centre = QtCore.QPoint(240, 300)
    qtbot.mousePress(view, Qt.MouseButton.LeftButton, pos=centre)
    for dx in (5, 20, 60):
        qtbot.mouseMove(view, centre + QtCore.QPoint(dx, 0))
    qtbot.mouseRelease(view, Qt.MouseButton.LeftButton, pos=centre + QtCore.QPoint(60, 0))
    assert not view.fit.fitting and not view.fit.button.isChecked()
    kept = (view.viewport.lat, view.viewport.lon, view.viewport.zoom)
    wait_other(4000.0, -3000.0)
    view.refresh(model.state)
    assert (view.viewport.lat, view.viewport.lon, view.viewport.zoom) == kept
    assert in_view(view) == [True, False]  # the other one is out of view and stays so
    # Fit brings it back
    qtbot.mouseClick(view.fit.button, Qt.MouseButton.LeftButton)
    assert view.fit.fitting and in_view(view) == [True, True]


@pytest.mark.parametrize("by_hand", ["wheel", "pinch", "zoom button", "follow"])
def test_zooming_or_following_by_hand_stops_fitting(qtbot, two_fixes, by_hand):
    model, _publish, wait_other = two_fixes
    wait_other(300.0, 200.0)
    view = make_view(qtbot, model)
    assert view.fit.fitting
    if by_hand == "wheel":
        view.zoom_by(1.0, QtCore.QPointF(100, 200))
    elif by_hand == "pinch":
        view.pinch(2.0, QtCore.QPointF(100, 200))
    elif by_hand == "zoom button":
        qtbot.mouseClick(view.zoom_in, Qt.MouseButton.LeftButton)
    else:
        qtbot.mouseClick(view.follow_button, Qt.MouseButton.LeftButton)
        assert view.following
    assert not view.fit.fitting and not view.fit.button.isChecked()
    kept = (view.viewport.lat, view.viewport.lon, view.viewport.zoom)
    wait_other(-2500.0, 2500.0)
    view.refresh(model.state)
    if by_hand == "follow":  # the vessel in the middle, not both in view
        main = view.value.main
        assert view.viewport.to_screen(main.lat, main.lon) == pytest.approx((240, 200), abs=1.0)
        assert view.viewport.zoom == kept[2]
    else:
        assert (view.viewport.lat, view.viewport.lon, view.viewport.zoom) == kept
    assert in_view(view)[1] is False
    qtbot.mouseClick(view.fit.button, Qt.MouseButton.LeftButton)  # and Fit brings both back
    assert view.fit.fitting and not view.following and in_view(view) == [True, True]


def test_the_buttons_sit_in_a_small_corner_block_and_the_markers_clear_of_it(qtbot, two_fixes):
    model, _publish, wait_other = two_fixes
    wait_other(0.0, 400.0)  # straight north: the fit is as tall as it can be
    view = MapView(model)
    qtbot.addWidget(view)
    view.setStyleSheet("QToolButton { min-width: 48px; min-height: 48px; }")  # finger-sized, as the app's theme
    view.resize(224, 330)
    view.show()
    qtbot.waitExposed(view)
    view.refresh(model.state)
    buttons = [b for b in view.control_buttons() if b.isVisible()]
    assert len(buttons) == 4
    rect = view.rect()
    for b in buttons:
        assert rect.contains(b.geometry()), (b.objectName(), b.geometry())
        assert b.width() == b.height() >= 48  # square, a finger's size
        assert b.accessibleName() and b.toolTip()
    for a in buttons:  # none over another
        assert not any(a.geometry().intersects(b.geometry()) for b in buttons if b is not a), a.objectName()
    assert len({b.y() for b in buttons}) == 2 and len({b.x() for b in buttons}) == 2  # two by two
    block = view.controls_rect()
    assert block.right() >= view.width() - 10 and block.top() <= 10  # in the top right corner
    assert block.width() * block.height() < 0.25 * view.width() * view.height()
    assert in_view(view) == [True, True]


def test_a_map_with_one_marker_has_no_fit_button(qtbot, sim_thread, threaded_client):
    bt, client = threaded_client
    model = MapModel(MapSettings(zoom=18.0), Binding("/gps/fix", "sensor_msgs/NavSatFix", "subscribe"),
                     client.node("map-one"), types=TYPES, dispatch=bt.call)
    bt.call(model.start).result(5)
    qtbot.waitUntil(lambda: model.state.value is not None and model.state.value.main.has_position, timeout=10_000)
    view = make_view(qtbot, model)
    assert view.following and not view.fit.fitting and not view.fit.button.isVisible()
    main = view.value.main
    assert view.viewport.to_screen(main.lat, main.lon) == pytest.approx((240, 200), abs=1.0)
    bt.call(model.stop).result(5)


def test_the_goal_bubble_stays_below_the_second_row_of_buttons(qtbot, sim_thread, threaded_client):
    bt, client = threaded_client
    model = MapModel(MapSettings(zoom=18.0, fit_all=True), Binding("/gps/fix", "sensor_msgs/NavSatFix", "subscribe"),
                     client.node("map-narrow"), types=TYPES, dispatch=bt.call)
    bt.call(model.start).result(5)
    qtbot.waitUntil(lambda: model.state.value is not None and model.state.value.main.has_position, timeout=10_000)
    view = MapView(model)
    qtbot.addWidget(view)
    view.setStyleSheet("QToolButton { min-width: 64px; min-height: 48px; }")
    view.resize(224, 400)
    view.show()
    qtbot.waitExposed(view)
    view.refresh(model.state)
    buttons = [b for b in view.control_buttons() if b.isVisible()]
    assert len(buttons) == 4 and len({b.y() for b in buttons}) == 2
    lowest = max(b.geometry().bottom() for b in buttons)
    qtbot.mouseClick(view, Qt.MouseButton.LeftButton, pos=QtCore.QPoint(60, 130))  # near the top: a goal there
    assert view.bubble.isVisible()
    bubble = view.bubble.geometry()
    assert bubble.top() > lowest and not any(bubble.intersects(b.geometry()) for b in buttons)  # over no button
    bt.call(model.stop).result(5)
