"""The fleet demo on a small screen (``rcon --demo --robots N``, real sims on loopback, the real window):
the Fleet canvas fits a 1024x600 tablet and a 1280x800 window without scrolling for 2, 3 and 4 vessels,
and its map opens showing every vessel, fits again when one is out of view, and keeps still once the
operator has moved it by hand (until Fit)."""

from __future__ import annotations

import pytest
from app_helpers import TIMEOUT_MS, open_window, settle, snap, tap
from qtpy import QtCore
from qtpy.QtTest import QTest

from rcon_core.app.fleet_demo import connect_fleet, fleet_sims, fleet_workspace

pytestmark = pytest.mark.usefixtures("qapp")
PACKAGES = ("rcon_widgets_std", "rcon_widgets_sensors", "rcon_widgets_map")
SIZES = ((1024, 600), (1280, 800))


@pytest.fixture(scope="module")
def fleet_plugins():
    from app_helpers import entry_point_plugins

    for name in PACKAGES:
        pytest.importorskip(name, reason=f"the fleet demo needs the {name} widget package installed")
    return entry_point_plugins()


def open_fleet(qtbot, tmp_path, plugins, sims, size):
    """The fleet demo's window at ``size`` on the Fleet canvas, every vessel connected and every widget's view
    built: (window, {(kind, robot id): hosted widget})."""
    n = len(sims)
    window = open_window(qtbot, tmp_path, plugins, size=size, layout=tmp_path / "fleet.json",
                         demo=lambda: fleet_workspace(n, plugins))
    connect_fleet(window, [s.url for s in sims])
    canvas = window.controller.canvas
    assert canvas.name == "Fleet"
    hosted = {(w.kind, w.binding.robot): window.host.hosted[w.id] for w in canvas.widgets}
    assert len(hosted) == 2 * n + 1
    qtbot.waitUntil(lambda: all(h.view is not None for h in hosted.values()), timeout=TIMEOUT_MS)
    return window, hosted


@pytest.mark.parametrize("n", [2, 3, 4])
def test_the_fleet_canvas_fits_a_tablet_without_scrolling(qtbot, tmp_path, fleet_plugins, n):
    with fleet_sims(n, rate_scale=1.0) as sims:
        window, hosted = open_fleet(qtbot, tmp_path, fleet_plugins, sims, SIZES[0])
        try:
            for size in SIZES:
                window.resize(*size)
                settle(90)
                assert (window.width(), window.height()) == size
                scroll = window.controller.surface.scroll_area
                viewport = scroll.viewport()
                frames = [h.frame.geometry() for h in hosted.values()]
                for (kind, robot), h in hosted.items():
                    g = h.widget.geometry  # shown at the layout's size (none grown into a neighbour)...
                    assert h.frame.geometry() == QtCore.QRect(int(g.x), int(g.y), int(g.w), int(g.h)), (kind, robot)
                    # ...over no other
                    assert sum(h.frame.geometry().intersects(f) for f in frames) == 1, (kind, robot)
                for (kind, robot), h in hosted.items():  # every widget wholly in sight
                    corner = h.frame.mapTo(viewport, QtCore.QPoint(0, 0))
                    assert viewport.rect().contains(QtCore.QRect(corner, h.frame.size())), (
                        n, size, kind, robot, corner, h.frame.size(), viewport.size())
                # nothing to scroll to, sideways or down
                assert scroll.horizontalScrollBar().maximum() == 0, (n, size, viewport.size())
                assert scroll.verticalScrollBar().maximum() == 0, (n, size, viewport.size())
                snap(window, f"fleet-{n}-{size[0]}x{size[1]}")
            # each vessel's camera and pad side by side, on the same row
            for k in range(1, n + 1):
                camera = hosted[("sensors.image", f"r-{k}")].frame.geometry()
                pad = hosted[("sensors.teleop", f"r-{k}")].frame.geometry()
                assert camera.right() < pad.left() and camera.top() == pad.top(), k
        finally:
            window.shutdown()


def test_the_fleet_map_shows_every_vessel_and_keeps_still_after_a_pan(qtbot, tmp_path, fleet_plugins):
    with fleet_sims(3, rate_scale=1.0) as sims:
        window, hosted = open_fleet(qtbot, tmp_path, fleet_plugins, sims, SIZES[0])
        try:
            fleet_map = hosted[("map.gps", "r-1")]

            def fixes():  # the map's view is rebuilt as each vessel's link comes up: always the current one
                value = fleet_map.view.value if fleet_map.view is not None else None
                return {t.label: t for t in value.tracks if t.has_position} if value is not None else {}

            def in_view():
                """Vessel name -> whether its marker lies on the map, clear of the buttons above it."""
                view = fleet_map.view
                if view is None or not view.isVisible():  # a view just rebuilt, not laid out yet
                    return {}
                top = max(b.geometry().bottom() for b in view.control_buttons() if b.isVisible())
                return {name: view.viewport.shows(t.lat, t.lon, inset=(0, top, 0, 0)) for name, t in fixes().items()}

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
            qtbot.waitUntil(lambda: at_sim("boat2", sims[1]), timeout=TIMEOUT_MS)
            settle(300)
            assert (view.viewport.lat, view.viewport.lon, view.viewport.zoom) == kept
            assert in_view()["boat2"] is False
            # Fit brings every vessel back in view
            tap(view.fit.button)
            assert view.fit.fitting and all_in_view()
            assert fleet_map.view is view  # one view all along since the three fixes came in
            snap(window, "fleet-map-3-fit-again")
        finally:
            window.shutdown()
