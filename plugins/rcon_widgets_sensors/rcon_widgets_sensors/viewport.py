"""Fit / zoom / pan arithmetic for showing an image in a widget (pure Python; the view feeds it events).

``zoom`` is relative to "fit" (1 = the whole image fits, letterboxed); ``pan`` is the image centre's
offset from the widget centre in widget pixels. The image may not be dragged out of sight: at least a
quarter of the widget stays covered.

**Drawing 1:1.** Fitted (unzoomed), the view draws the frame unscaled when its pixel array is exactly
the rectangle the picture fills in device pixels; the decode worker makes it that size. Both sides get
that rectangle from the same arithmetic here: :func:`device_box` (the widget in device pixels, rounded
up) and :func:`fitted_pixels` (the picture fitted into that box, sides rounded to whole pixels, centred
on a whole pixel); :func:`unscaled_origin` is the view's choice between the 1:1 draw and the scaled one.
"""

from __future__ import annotations

import math

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


def device_box(widget_w: float, widget_h: float, ratio: float, zoom: float = 1.0) -> tuple[int, int]:
    """The box the picture is fitted into, in device pixels: the widget's size x device pixel ratio x zoom,
    each side rounded up (what the view hands the model's ``set_display_size``)."""
    k = ratio * zoom
    return (max(1, math.ceil(widget_w * k - 1e-6)), max(1, math.ceil(widget_h * k - 1e-6)))


def fitted_pixels(box: tuple[int, int], image_w: float, image_h: float) -> tuple[int, int, int, int]:
    """Where an ``image_w`` x ``image_h`` picture goes when fitted (letterboxed) into ``box`` (device
    pixels): ``(x, y, w, h)``, all whole device pixels; the sides are rounded to the nearest pixel (at
    least 1, at most the box), the offsets centre it (rounded down). Upscaling too: this is the drawn
    rectangle, not the decoded size (the worker never makes more pixels than the source has)."""
    bw, bh = box
    if image_w <= 0 or image_h <= 0 or bw <= 0 or bh <= 0:
        return (0, 0, max(0, bw), max(0, bh))
    scale = min(bw / image_w, bh / image_h)
    w = min(bw, max(1, round(image_w * scale)))
    h = min(bh, max(1, round(image_h * scale)))
    return ((bw - w) // 2, (bh - h) // 2, w, h)


def unscaled_origin(widget_w: float, widget_h: float, ratio: float, image_w: float, image_h: float,
                    array_w: int, array_h: int, fitted: bool) -> tuple[float, float] | None:
    """The view's choice of path: the top-left corner (widget pixels) to draw a ``array_w`` x ``array_h``
    pixel array at, unscaled, with its device pixel ratio set to ``ratio``; or None for the scaled draw.
    1:1 only when the view is fitted (not zoomed or panned) and the array is exactly the fitted rectangle
    in device pixels (:func:`fitted_pixels` of :func:`device_box`); else (zoomed, a frame decoded for the
    size before a resize, a picture smaller than the view, a static image) the scaled draw."""
    if not fitted or not ratio > 0:
        return None
    x, y, w, h = fitted_pixels(device_box(widget_w, widget_h, ratio), image_w, image_h)
    if (array_w, array_h) != (w, h):
        return None
    return (x / ratio, y / ratio)
