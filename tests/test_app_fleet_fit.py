"""The fleet demo's canvas on a real window (``rcon --demo --robots N``), laid out for the screen it opens
on (issue 21.7): at 1024x600 and at 1280x800, for 2 to 6 vessels, it fills the canvas's width (and its
height, scrolling down only where the vessels do not fit), every pad's disc is at least 160 px, every tap
target at least 48 px, the map's buttons a small block in its corner; with real sims the titles are
whole and a finger on a pad drives its own vessel. Then the map: it opens showing every vessel, fits
again when one is out of view, and keeps still once the operator has moved it by hand (until Fit)."""

from __future__ import annotations

import pytest
from app_helpers import TIMEOUT_MS, open_window, settle, snap, tap
from fit_check import problems
from qtpy import QtCore, QtWidgets
from qtpy.QtTest import QTest

from rcon_core.app.fleet_demo import GAP, connect_fleet, fit_fleet, fleet_sims, fleet_workspace

pytestmark = pytest.mark.usefixtures("qapp")
PACKAGES = ("rcon_widgets_std", "rcon_widgets_sensors", "rcon_widgets_map")
SIZES = ((1024, 600), (1280, 800))
TOUCH = 48


@pytest.fixture(scope="module")
def fleet_plugins():
    from app_helpers import entry_point_plugins

    for name in PACKAGES:
        pytest.importorskip(name, reason=f"the fleet demo needs the {name} widget package installed")
    return entry_point_plugins()


def open_fleet(qtbot, tmp_path, plugins, n, size, urls=()):
    """The fleet demo's window at ``size``, laid out for it as ``rcon --demo --robots N`` does on its first
    start, connected to ``urls`` if given, every widget's view built: (window, {(kind, robot): hosted})."""
    window = open_window(qtbot, tmp_path, plugins, size=size, layout=tmp_path / "fleet.json",
                         demo=lambda: fleet_workspace(n, plugins))
    fit_fleet(window, n, plugins)
    if urls:
        connect_fleet(window, list(urls))
    canvas = window.controller.canvas
    assert canvas.name == "Fleet"
    hosted = {(w.kind, w.binding.robot): window.host.hosted[w.id] for w in canvas.widgets}
    assert len(hosted) == 2 * n + 1
    qtbot.waitUntil(lambda: all(h.view is not None for h in hosted.values()), timeout=TIMEOUT_MS)
    settle()
    return window, hosted


def tap_targets(widget: QtWidgets.QWidget) -> list[QtWidgets.QAbstractButton]:
    return [b for b in widget.findChildren(QtWidgets.QAbstractButton) if b.isVisible()]


@pytest.mark.parametrize("size", SIZES, ids=["1024x600", "1280x800"])
@pytest.mark.parametrize("n", [2, 3, 4, 5, 6])
def test_the_fleet_canvas_fills_the_screen_with_finger_sized_tiles(qtbot, tmp_path, fleet_plugins, n, size):
    window, hosted = open_fleet(qtbot, tmp_path, fleet_plugins, n, size)
    try:
        assert (window.width(), window.height()) == size
        scroll = window.controller.surface.scroll_area
        viewport = scroll.viewport()
        frames = [h.frame.geometry() for h in hosted.values()]
        for (kind, robot), h in hosted.items():
            g = h.widget.geometry  # shown at the layout's size, over no other frame
            assert h.frame.geometry() == QtCore.QRect(int(g.x), int(g.y), int(g.w), int(g.h)), (kind, robot)
            assert sum(h.frame.geometry().intersects(f) for f in frames) == 1, (kind, robot)
        # never sideways; the first screen is filled across and down
        assert scroll.horizontalScrollBar().maximum() == 0, (n, size, viewport.size())
        content = QtCore.QRect()
        for f in frames:
            content = content.united(f)
        assert content.right() + 1 + GAP >= viewport.width() - GAP, (n, size, content, viewport.size())
        first_screen = [f for f in frames if f.top() < viewport.height()]
        assert max(f.bottom() for f in first_screen) + 1 + GAP >= viewport.height() - GAP, (n, size)
        # each pad: a disc of 160 px or more, its whole frame in one screenful
        for k in range(1, n + 1):
            pad = hosted[("sensors.teleop", f"r-{k}")]
            _centre, radius = pad.view.pad()
            assert 2 * radius >= 160, (k, 2 * radius, pad.frame.size())
            assert pad.frame.height() <= viewport.height()
            camera = hosted[("sensors.image", f"r-{k}")].frame.geometry()
            assert camera.right() < pad.frame.geometry().left() and camera.top() == pad.frame.geometry().top()
        assert problems(window) == [], problems(window)  # no text cut (the robots' chips: six on 1024 px)
        # every button in the window (the map's too) is a finger's size
        for b in tap_targets(window):
            assert b.width() >= TOUCH and b.height() >= TOUCH, (b.objectName(), b.accessibleName(), b.size())
        # the map: in sight where it fits (2 vessels on a tablet, 2 and 3 at 1280x800), its buttons a small
        # block in its top right corner
        fleet_map = hosted[("map.gps", "r-1")]
        view = fleet_map.view
        if (size, n) in (((1024, 600), 2), ((1280, 800), 2), ((1280, 800), 3)):
            assert scroll.verticalScrollBar().maximum() == 0, (n, size)
            corner = fleet_map.frame.mapTo(viewport, QtCore.QPoint(0, 0))
            assert viewport.rect().contains(QtCore.QRect(corner, fleet_map.frame.size()))
        block = view.controls_rect()
        assert block.right() >= view.width() - 10 and block.top() <= 10
        assert block.width() * block.height() <= 0.2 * view.width() * view.height(), (block, view.size())
        snap(window, f"fleet-{n}-{size[0]}x{size[1]}")
    finally:
        window.shutdown()


@pytest.mark.parametrize("size", SIZES, ids=["1024x600", "1280x800"])
def test_three_vessels_show_whole_titles_and_each_pad_drives_its_own(qtbot, tmp_path, fleet_plugins, size):
    with fleet_sims(3, rate_scale=1.0) as sims:
        window, hosted = open_fleet(qtbot, tmp_path, fleet_plugins, 3, size, [s.url for s in sims])
        try:
            for k in (1, 2, 3):  # live: no badge left on a vessel's camera or pad
                for kind in ("sensors.image", "sensors.teleop"):
                    frame = hosted[(kind, f"r-{k}")].frame
                    qtbot.waitUntil(lambda frame=frame: not frame.badge.isVisible(), timeout=TIMEOUT_MS)
            settle()
            for (kind, robot), h in hosted.items():
                title = h.frame.title
                assert title.text() == title.full_title, (kind, robot, title.text())  # whole, never "boat1 · Fr…"
                if kind != "map.gps":
                    assert title.full_title.startswith(("boat1 · ", "boat2 · ", "boat3 · "))
            # a finger on boat 3's pad (scrolled into sight if need be) drives boat 3 only
            pad = hosted[("sensors.teleop", "r-3")]
            window.controller.surface.reveal(pad.frame.geometry())
            settle()
            centre, radius = pad.view.pad()
            c = centre.toPoint()
            QTest.mousePress(pad.view, QtCore.Qt.MouseButton.LeftButton, pos=c)
            QTest.mouseMove(pad.view, c - QtCore.QPoint(0, int(radius * 0.9)))
            qtbot.waitUntil(lambda: sims[2].robot.cmd_surge > 0.5, timeout=TIMEOUT_MS)
            QTest.mouseRelease(pad.view, QtCore.Qt.MouseButton.LeftButton, pos=c)
            qtbot.waitUntil(lambda: sims[2].robot.cmd_surge == 0.0, timeout=TIMEOUT_MS)
            assert sims[0].robot.cmd_surge == 0.0 and sims[1].robot.cmd_surge == 0.0
            window.controller.surface.reveal(QtCore.QRect(0, 0, 10, 10))
            settle()
            snap(window, f"fleet-live-3-{size[0]}x{size[1]}")
        finally:
            window.shutdown()


def test_the_fleet_map_shows_every_vessel_and_keeps_still_after_a_pan(qtbot, tmp_path, fleet_plugins):
    with fleet_sims(3, rate_scale=1.0) as sims:
        window, hosted = open_fleet(qtbot, tmp_path, fleet_plugins, 3, SIZES[1], [s.url for s in sims])
        try:
            fleet_map = hosted[("map.gps", "r-1")]

            def fixes():  # the map's view is rebuilt as each vessel's link comes up: always the current one
                value = fleet_map.view.value if fleet_map.view is not None else None
                return {t.label: t for t in value.tracks if t.has_position} if value is not None else {}

            def in_view():
                """Vessel name -> whether its marker lies on the map, clear of its buttons' corner."""
                view = fleet_map.view
                if view is None or not view.isVisible():  # a view just rebuilt, not laid out yet
                    return {}
                block = view.controls_rect().adjusted(-10, -10, 10, 10)
                out = {}
                for name, t in fixes().items():
                    x, y = view.viewport.to_screen(t.lat, t.lon)
                    out[name] = view.viewport.shows(t.lat, t.lon) and not block.contains(QtCore.QPoint(round(x),
                                                                                                       round(y)))
                return out

            def all_in_view():
                shown = in_view()
                return len(shown) == 3 and all(shown.values())

            def at_sim(name, sim):
                lat, lon = sim.robot.lat_lon()
                track = fixes().get(name)
                return track is not None and abs(track.lat - lat) < 1e-4 and abs(track.lon - lon) < 1e-4

            # it opens showing all three, as close as they allow (they start a few hundred metres apart)
            qtbot.waitUntil(lambda: sorted(fixes()) == ["boat1", "boat2", "boat3"], timeout=TIMEOUT_MS)
            qtbot.waitUntil(all_in_view, timeout=TIMEOUT_MS)
            view = fleet_map.view
            assert view.fit.fitting and not view.following
            assert view.viewport.zoom <= view.settings.zoom

            def spread():
                """How much of the room for markers (the map less the buttons, names and scale bar) they spread
                over, across or down, whichever is more."""
                left, top, right, bottom = view.fit.inset(view.value)
                xs, ys = zip(*(view.viewport.to_screen(t.lat, t.lon) for t in fixes().values()), strict=True)
                return max((max(xs) - min(xs)) / (view.width() - left - right),
                           (max(ys) - min(ys)) / (view.height() - top - bottom))

            assert spread() > 0.9  # zoomed out as far as they need, not further
            opened = view.viewport.zoom
            snap(window, "fleet-map-3-opened")
            # boat3 turns up 3 km away: the map fits again, further out
            sims[2].robot.x += 3000.0
            qtbot.waitUntil(lambda: at_sim("boat3", sims[2]), timeout=TIMEOUT_MS)
            qtbot.waitUntil(all_in_view, timeout=TIMEOUT_MS)
            assert view.viewport.zoom < opened - 1.0
            # the operator drags the map: from then on it never moves on its own
            centre = view.rect().center()
            QTest.mousePress(view, QtCore.Qt.MouseButton.LeftButton, pos=centre)
            for dx in (5, 20, 40):
                QTest.mouseMove(view, centre + QtCore.QPoint(dx, 10))
            QTest.mouseRelease(view, QtCore.Qt.MouseButton.LeftButton, pos=centre + QtCore.QPoint(40, 10))
            assert not view.fit.fitting and view.pending is None  # a drag, not a tap: no goal offered
            kept = (view.viewport.lat, view.viewport.lon, view.viewport.zoom)
            sims[1].robot.y -= 6000.0  # boat2 goes far out of view
            qtbot.waitUntil(lambda: at_sim("boat2", sims[1]), timeout=TIMEOUT_MS)  # the map was given it...
            seen = view.state.seq
            qtbot.waitUntil(lambda: view.state.seq > seen, timeout=TIMEOUT_MS)  # ...and a value after it
            assert (view.viewport.lat, view.viewport.lon, view.viewport.zoom) == kept
            assert in_view()["boat2"] is False
            # Fit brings every vessel back in view
            tap(view.fit.button)
            assert view.fit.fitting and all_in_view()
            assert fleet_map.view is view  # one view all along since the three fixes came in
            snap(window, "fleet-map-3-fit-again")
        finally:
            window.shutdown()
