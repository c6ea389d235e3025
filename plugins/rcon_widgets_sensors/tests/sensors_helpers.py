"""Shared helpers for this package's tests (imported by basename: keep the name unique)."""

from __future__ import annotations

import asyncio


async def in_thread(fn, *args):
    """Run a blocking call without blocking the test's loop (the bridge and the sim live on it)."""
    return await asyncio.get_running_loop().run_in_executor(None, fn, *args)


def wheel(view, notches: int) -> None:
    """Turn the mouse wheel ``notches`` steps (120 each; positive zooms in) over the centre of ``view``."""
    from qtpy import QtCore, QtGui

    at = QtCore.QPointF(view.width() / 2, view.height() / 2)
    ev = QtGui.QWheelEvent(at, view.mapToGlobal(at), QtCore.QPoint(), QtCore.QPoint(0, 120 * notches),
                           QtCore.Qt.MouseButton.NoButton, QtCore.Qt.KeyboardModifier.NoModifier,
                           QtCore.Qt.ScrollPhase.NoScrollPhase, False)
    view.wheelEvent(ev)
