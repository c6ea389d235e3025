"""Qt helpers for the standard widgets' view tests: framed offscreen screenshots, a live bridge thread."""

from __future__ import annotations

import os
from pathlib import Path

from qtpy import QtGui, QtWidgets

from rcon_core.app.theme import stylesheet
from rcon_core.app.widget_frame import WidgetFrame
from rcon_core.bridge import BridgeClient
from rcon_core.bridge.threaded import BridgeThread

#: set RCON_SCREENSHOTS=1 to refresh the PNGs in docs/screenshots/std (otherwise they go to tmp_path)
DOCS = Path(__file__).resolve().parents[3] / "docs" / "screenshots" / "std"


def shoot(qtbot, view: QtWidgets.QWidget, title: str, size: tuple[int, int], name: str, tmp_path: Path) -> Path:
    """Put ``view`` in the app's widget frame with the app's theme, render it offscreen, save a PNG."""
    frame = WidgetFrame("w-shot", title)
    frame.set_view(view)
    frame.set_editable(False)  # operator mode: no resize handles over the view
    frame.setStyleSheet(stylesheet(touch=48))
    frame.resize(*size)
    qtbot.addWidget(frame)
    frame.show()
    qtbot.waitExposed(frame)
    QtWidgets.QApplication.processEvents()
    target = DOCS if os.environ.get("RCON_SCREENSHOTS") else tmp_path
    target.mkdir(parents=True, exist_ok=True)
    path = target / f"{name}.png"
    assert frame.grab().save(str(path))
    img = QtGui.QImage(str(path))
    assert img.width() >= size[0] - 2 and not img.isNull()
    colours = {img.pixel(x, y) for x in range(0, img.width(), 7) for y in range(0, img.height(), 7)}
    assert len(colours) > 3, "the screenshot is blank"
    assert path.stat().st_size < 150_000
    return path


class LiveBridge:
    """A bridge client on its own loop thread, connected to a threaded sim, as the app runs it."""

    def __init__(self, url: str) -> None:
        self.thread = BridgeThread().start()
        self.client = BridgeClient(url, reconnect=False)
        self.thread.run(self.client.connect()).result(10)

    def node(self, name: str):
        return self.client.node(name)

    def close(self) -> None:
        try:
            self.thread.run(self.client.close()).result(10)
        finally:
            self.thread.stop()
