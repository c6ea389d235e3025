"""Pure geometry rules of the canvas: grid snapping, minimum sizes, never at negative coordinates.

A widget's geometry belongs to the layout, not to the window: nothing here squeezes a widget into the
visible part of the canvas. The canvas scrolls instead (its logical size covers every widget), so the
only rule is that a widget never sits left of or above the canvas origin, where nobody could reach it.
"""

from __future__ import annotations

import math

from qtpy import QtCore

#: grid step in canvas units (device-independent pixels)
GRID = 16
#: free room the canvas keeps right of and below its widgets (dragging a widget into it grows the canvas)
MARGIN = GRID


def snap(value: float, grid: int = GRID) -> int:
    return int(round(value / grid) * grid)


def snap_up(value: float, grid: int = GRID) -> int:
    """The smallest grid multiple >= ``value``."""
    return int(math.ceil(value / grid) * grid)


def snap_rect(rect: QtCore.QRect, grid: int = GRID) -> QtCore.QRect:
    return QtCore.QRect(snap(rect.x(), grid), snap(rect.y(), grid), snap(rect.width(), grid), snap(rect.height(), grid))


def fit_rect(rect: QtCore.QRect, bounds: QtCore.QRect, min_size: QtCore.QSize) -> QtCore.QRect:
    """``rect`` made at least ``min_size`` (rounded up to the grid) and moved so it never starts left of or
    above ``bounds``' top-left corner. The right and bottom of ``bounds`` are not limits: the canvas grows
    (and scrolls) to cover its widgets, so a smaller window never moves or shrinks a widget."""
    w = max(snap_up(min_size.width()), rect.width())
    h = max(snap_up(min_size.height()), rect.height())
    x = max(rect.x(), bounds.left())
    y = max(rect.y(), bounds.top())
    return QtCore.QRect(int(x), int(y), int(w), int(h))


def on_grid(rect: QtCore.QRect, min_size: QtCore.QSize, grid: int = GRID) -> QtCore.QRect:
    """What is saved: ``rect`` snapped to the grid, at least ``min_size``, never at negative coordinates."""
    return fit_rect(snap_rect(rect, grid), QtCore.QRect(0, 0, 1, 1), min_size)


def scaled_about_center(rect: QtCore.QRect, scale: float) -> QtCore.QRect:
    """``rect`` scaled by ``scale`` keeping its centre."""
    center = QtCore.QPointF(rect.center())
    w, h = rect.width() * scale, rect.height() * scale
    return QtCore.QRect(round(center.x() - w / 2), round(center.y() - h / 2), round(w), round(h))
