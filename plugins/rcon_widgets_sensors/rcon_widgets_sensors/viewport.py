"""Fit / zoom / pan arithmetic for showing an image in a widget (pure Python; the view feeds it events).

``zoom`` is relative to "fit" (1 = the whole image fits, letterboxed); ``pan`` is the image centre's
offset from the widget centre in widget pixels. The image may not be dragged out of sight: at least a
quarter of the widget stays covered.
"""

from __future__ import annotations

import attrs

MIN_ZOOM = 1.0
MAX_ZOOM = 16.0


@attrs.define
class Viewport:
    widget_w: float = 1.0
    widget_h: float = 1.0
    image_w: float = 1.0
    image_h: float = 1.0
    zoom: float = 1.0
    pan_x: float = 0.0
    pan_y: float = 0.0

    def resize(self, widget_w: float, widget_h: float) -> None:
        self.widget_w, self.widget_h = max(1.0, widget_w), max(1.0, widget_h)
        self._clamp()

    def set_image(self, image_w: float, image_h: float) -> None:
        if (image_w, image_h) != (self.image_w, self.image_h):
            self.image_w, self.image_h = max(1.0, image_w), max(1.0, image_h)
            self._clamp()

    @property
    def fit_scale(self) -> float:
        return min(self.widget_w / self.image_w, self.widget_h / self.image_h)

    @property
    def scale(self) -> float:
        """Widget pixels per image pixel."""
        return self.fit_scale * self.zoom

    @property
    def fitted(self) -> bool:
        return self.zoom == 1.0 and self.pan_x == 0.0 and self.pan_y == 0.0

    def rect(self) -> tuple[float, float, float, float]:
        """Where the whole image goes in the widget: (x, y, w, h)."""
        w, h = self.image_w * self.scale, self.image_h * self.scale
        return (self.widget_w / 2 + self.pan_x - w / 2, self.widget_h / 2 + self.pan_y - h / 2, w, h)

    def to_image(self, x: float, y: float) -> tuple[float, float]:
        """Widget point -> image pixel coordinates."""
        rx, ry, _w, _h = self.rect()
        return ((x - rx) / self.scale, (y - ry) / self.scale)

    def fit(self) -> None:
        self.zoom, self.pan_x, self.pan_y = 1.0, 0.0, 0.0

    def pan_by(self, dx: float, dy: float) -> None:
        self.pan_x += dx
        self.pan_y += dy
        self._clamp()

    def zoom_at(self, factor: float, x: float, y: float) -> None:
        """Zoom by ``factor`` keeping the image point under widget point (x, y) where it is."""
        if not factor > 0:
            return
        new = min(MAX_ZOOM, max(MIN_ZOOM, self.zoom * factor))
        real = new / self.zoom
        # the point's offset from the image centre scales with the zoom
        cx, cy = self.widget_w / 2 + self.pan_x, self.widget_h / 2 + self.pan_y
        self.pan_x += (x - cx) * (1 - real)
        self.pan_y += (y - cy) * (1 - real)
        self.zoom = new
        if self.zoom == 1.0:
            self.pan_x = self.pan_y = 0.0
        self._clamp()

    def _clamp(self) -> None:
        _x, _y, w, h = self.rect()
        lim_x = max(0.0, (w - self.widget_w) / 2) + self.widget_w / 4 * (self.zoom > 1.0)
        lim_y = max(0.0, (h - self.widget_h) / 2) + self.widget_h / 4 * (self.zoom > 1.0)
        self.pan_x = min(lim_x, max(-lim_x, self.pan_x))
        self.pan_y = min(lim_y, max(-lim_y, self.pan_y))
