"""Place on canvas looks for a free spot in the canvas as it is once the add panel has closed, not in the
part the open panel left visible. Driven with taps against the sim."""

from __future__ import annotations

import pytest
from app_helpers import choose_kind, entry_point_plugins, tap, tap_topic, window_session
from qtpy import QtCore, QtWidgets

from rcon_core.app.main_window import MainWindow
from rcon_core.plugins import Role

pytestmark = pytest.mark.usefixtures("qapp")


@pytest.fixture
def window(qtbot, tmp_path, sim_thread):
    pytest.importorskip("rcon_widgets_std")
    # a wide window: the open add panel hides a good part of the canvas
    yield from window_session(qtbot, tmp_path / "config", entry_point_plugins(), url=sim_thread.url,
                              size=(1600, 900), topics=("/battery",))


def place_label(window: MainWindow) -> QtCore.QRect:
    tap_topic(window, "/battery")
    panel = choose_kind(window, Role.SUBSCRIBE, "std.label")
    QtWidgets.QApplication.processEvents()
    open_view = window.controller.surface.scroll_area.viewport().width()
    tap(panel.place_button)
    assert not panel.isVisible()
    widget = window.controller.canvas.widgets[-1]
    window.last_open_view = open_view  # type: ignore[attr-defined]
    return window.controller.surface.frames[widget.id].geometry()


def test_place_uses_the_canvas_width_without_the_add_panel(window):
    rects = [place_label(window) for _ in range(4)]
    QtWidgets.QApplication.processEvents()
    closed_view = window.controller.surface.scroll_area.viewport().width()
    open_view = window.last_open_view
    width = rects[0].width()
    # the open panel left room for fewer labels in a row than the canvas has once it closes
    per_row_open = (open_view - 16) // (width + 16)
    per_row_closed = (closed_view - 16) // (width + 16)
    assert per_row_open < 4 <= per_row_closed, (open_view, closed_view, width)
    # all four went on the first row, in reading order, inside the visible canvas
    assert [r.y() for r in rects] == [16] * 4, rects
    assert [r.x() for r in rects] == sorted(r.x() for r in rects)
    assert max(r.right() for r in rects) < closed_view
    assert window.controller.surface.scroll_area.horizontalScrollBar().value() == 0
