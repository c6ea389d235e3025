"""Pure geometry rules of the canvas: grid snapping, minimum sizes, keeping widgets on screen."""

from __future__ import annotations

from qtpy import QtCore

#: grid step in canvas units (device-independent pixels)
GRID = 16


def snap(value: float, grid: int = GRID) -> int:
    return int(round(value / grid) * grid)


def snap_rect(rect: QtCore.QRect, grid: int = GRID) -> QtCore.QRect:
    return QtCore.QRect(snap(rect.x(), grid), snap(rect.y(), grid), snap(rect.width(), grid), snap(rect.height(), grid))


def fit_rect(rect: QtCore.QRect, bounds: QtCore.QRect, min_size: QtCore.QSize) -> QtCore.QRect:
    """``rect`` made at least ``min_size``, at most ``bounds``' size, and moved fully inside ``bounds``."""
    w = max(min_size.width(), min(rect.width(), bounds.width()))
    h = max(min_size.height(), min(rect.height(), bounds.height()))
    x = min(max(rect.x(), bounds.left()), bounds.left() + max(0, bounds.width() - w))
    y = min(max(rect.y(), bounds.top()), bounds.top() + max(0, bounds.height() - h))
    return QtCore.QRect(int(x), int(y), int(w), int(h))


def scaled_about_center(rect: QtCore.QRect, scale: float) -> QtCore.QRect:
    """``rect`` scaled by ``scale`` keeping its centre."""
    center = QtCore.QPointF(rect.center())
    w, h = rect.width() * scale, rect.height() * scale
    return QtCore.QRect(round(center.x() - w / 2), round(center.y() - h / 2), round(w), round(h))
