"""Canvas ▾ → *New canvas from template*: the example canvases installed plugins offer.

Plugins contribute them through the ``rcon_canvas_templates`` hook (``docs/hooks.md``); each is a canvas
file in the ``rcon-canvas`` format, added the way *Import canvas…* adds a file (a unique name, fresh ids,
one undo step, Edit mode first), so a file that cannot be used changes nothing and the notice bar says why.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path

from qtpy import QtGui, QtWidgets

from rcon_core.plugins.manager import CanvasTemplate


def add_template_menu(templates: Sequence[CanvasTemplate], import_from: Callable[[Path], object],
                      menu: QtWidgets.QMenu, before: QtGui.QAction | None = None) -> QtWidgets.QMenu:
    """Insert the submenu into ``menu`` (before ``before``); one action per template, ``template_<n>``,
    which adds its file (``import_from(path)``)."""
    sub = QtWidgets.QMenu("New canvas from template", menu)
    sub.setObjectName("canvas_templates")
    if before is not None:
        menu.insertMenu(before, sub)
    else:
        menu.addMenu(sub)
    for n, template in enumerate(templates):
        action = sub.addAction(template.title)
        action.setObjectName(f"template_{n}")
        action.setToolTip(template.description or f"from {template.package}")
        action.triggered.connect(lambda _checked=False, path=template.path: import_from(path))
    if not templates:
        none = sub.addAction("No installed package offers one")
        none.setObjectName("template_none")
        none.setEnabled(False)
    return sub
