"""The map's "every marker in view" mode (Qt): the map centres and zooms so every marker with a position
(every robot's fix, the extra fixes) is on screen, clear of the buttons, the names and the scale bar.

On while the *Fit* button is down: the map opens that way with the setting ``fit_all`` (the fleet demo's
map), and the button brings it back at any time. While it is on, a marker's first position, or a marker
out of view (one that moved out), fits the map again; markers moving about inside the view do not, so the
map does not twitch with every fix. Panning or zooming by hand turns it off for good (the map never jumps
on its own after that), as does *Follow*, which keeps one robot in the middle instead.
"""

from __future__ import annotations

from typing import Any

from qtpy import QtGui, QtWidgets

#: free pixels kept around the markers: left, beside or below the buttons, right of the names, above the
#: scale bar
EDGE_PX, BELOW_BUTTONS_PX, BOTTOM_PX = 24, 24, 56
#: how far (pixels) a marker may stray past the fitted room before the map fits again
SLACK_PX = 12


class FitControls:
    """Owned by a MapView: the *Fit* button and whether the map keeps every marker in view."""

    def __init__(self, view: Any) -> None:
        self.view = view
        self.fitting = bool(getattr(view.settings, "fit_all", False))
        self.button = QtWidgets.QToolButton(view)
        self.button.setObjectName("mapFit")
        self.button.setText("Fit")  # the view draws its icon
        self.button.setCheckable(True)
        self.button.setChecked(self.fitting)
        self.button.setToolTip("Fit: show every marker (panning or zooming by hand turns this off)")
        self.button.setAccessibleName("Fit every marker in view")
        self.button.clicked.connect(self._clicked)
        self.button.setVisible(self.fitting)
        self._fitted: set[str] = set()  #: the markers (track keys) of the last fit

    # -- what to fit ------------------------------------------------------------------------------
    @staticmethod
    def points(value: Any) -> list[tuple[float, float]]:
        tracks = value.tracks if value is not None else ()
        return [(t.lat, t.lon) for t in tracks if t.has_position]

    def inset(self, value: Any) -> tuple[float, float, float, float]:
        """The pixels kept free at the left, top, right and bottom: the longest marker name at the right
        (names are written right of their markers), the scale bar below, and the buttons' corner: either
        a band as tall as the buttons across the top or one as wide as them down the right side, whichever
        leaves the markers more room."""
        view = self.view
        block = view.controls_rect()
        fm = QtGui.QFontMetricsF(view.font())
        names = [t.label for t in value.tracks if t.has_position] if value is not None else []
        named = EDGE_PX + (14 + max(fm.horizontalAdvance(n) for n in names) if len(names) > 1 else 0)
        if block.isEmpty():
            return EDGE_PX, EDGE_PX, named, BOTTOM_PX
        w, h = view.width(), view.height()
        top = max(EDGE_PX, block.bottom() + BELOW_BUTTONS_PX)
        right = max(named, w - block.left() + EDGE_PX)
        below = (w - EDGE_PX - named) * (h - top - BOTTOM_PX)
        beside = (w - EDGE_PX - right) * (h - EDGE_PX - BOTTOM_PX)
        return (EDGE_PX, top, named, BOTTOM_PX) if below >= beside else (EDGE_PX, EDGE_PX, right, BOTTOM_PX)

    # -- state ------------------------------------------------------------------------------------
    def sync(self, value: Any) -> bool:
        """A new map value: show the button when there is more than one marker to fit, and while fitting,
        fit again if a marker has just got its first position or is out of view. True when fitted now."""
        wanted = self.fitting or (value is not None and len(value.tracks) > 1)
        if wanted != self.button.isVisible():
            self.button.setVisible(wanted)
            self.view.place_controls()
        if not self.fitting:
            return False
        points = self.points(value)
        keys = {t.key for t in value.tracks if t.has_position} if value is not None else set()
        left, top, right, bottom = self.inset(value)
        slack = (max(0.0, left - SLACK_PX), max(0.0, top - SLACK_PX), max(0.0, right - SLACK_PX),
                 max(0.0, bottom - SLACK_PX))
        if not keys <= self._fitted or not all(self.view.viewport.shows(lat, lon, slack) for lat, lon in points):
            self.fit(value)
            return True
        return False

    def fit(self, value: Any) -> None:
        """Centre and zoom on every marker now (at the map's zoom setting at most)."""
        points = self.points(value)
        if points:
            self.view.viewport.fit(points, self.inset(value), max_zoom=float(self.view.settings.zoom))
            self._fitted = {t.key for t in value.tracks if t.has_position}

    def stop(self) -> None:
        """The operator moved the map (or chose Follow): never fit on its own again until *Fit*."""
        self.fitting = False
        self.button.setChecked(False)

    def _clicked(self, on: bool) -> None:
        if not on:
            self.stop()
            return
        self.fitting = True
        self.view.set_follow(False)
        self.fit(self.view.value)
        self.view.viewport_changed()
