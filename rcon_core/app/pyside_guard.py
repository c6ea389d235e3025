"""Guard against a PySide6 6.12 defect on Python < 3.12: every call of a Qt method returning ``void``
drops one reference to ``None`` (PySide 6.12 assumes the immortal None of Python 3.12+).  Left alone, a
busy window brings None's count to zero within minutes and the interpreter aborts (``none_dealloc``).

While the defect is present, :func:`top_up` keeps a reserve of references to None and refills it; the
frame clock calls it every frame.  On unaffected versions it does nothing.
"""

from __future__ import annotations

import ctypes
import sys

RESERVE = 200_000
_keep: list[list[None]] = []


def _affected() -> bool:
    if sys.version_info >= (3, 12):
        return False
    try:
        from qtpy import QtCore, QtGui

        before = sys.getrefcount(None)
        color = QtGui.QColor()
        for _ in range(8):
            color.setRed(1)  # a void method
        QtCore  # noqa: B018
        return sys.getrefcount(None) < before
    except Exception:
        return False


AFFECTED = _affected()


def top_up() -> None:
    """Keep at least RESERVE references to None alive (only when the defect is present)."""
    if AFFECTED and sys.getrefcount(None) < RESERVE:
        reserve = [None] * RESERVE
        # never freed, not even at interpreter exit (freeing it would drop the count it protects)
        ctypes.pythonapi.Py_IncRef(ctypes.py_object(reserve))
        _keep.append(reserve)
