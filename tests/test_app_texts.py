"""Texts a person must be able to read: frame titles cut with "…" (never mid-letter, never under the status
badge), the add panel's hint wrapped, text settings wide enough for a message."""

from __future__ import annotations

import pytest
from qtpy import QtCore, QtGui, QtWidgets

from rcon_core.app.theme import stylesheet
from rcon_core.app.widget_frame import WidgetFrame

pytestmark = pytest.mark.usefixtures("qapp")


def _text_columns(frame: WidgetFrame) -> tuple[int, int]:
    """The first and last pixel column (frame coordinates) where the title's white text is painted, left
    of the badge when one shows."""
    image = frame.grab().toImage()
    title = frame.title.geometry()
    stop = frame.badge.x() if frame.badge.isVisible() else title.right()
    cols = [x for x in range(title.left(), stop)
            if any(QtGui.QColor(image.pixel(x, y)).lightness() > 200
                   for y in range(title.top() + 2, title.bottom() - 1))]
    assert cols, "no title text painted"
    return cols[0], cols[-1]


@pytest.fixture
def frame(qtbot):
    surface = QtWidgets.QWidget()
    surface.setStyleSheet(stylesheet(touch=48))
    surface.resize(400, 200)
    frame = WidgetFrame("w-1", "Battery voltage, main pack", surface)
    frame.set_view(QtWidgets.QLabel("24.36 V"))
    frame.setGeometry(16, 16, 160, 112)
    qtbot.addWidget(surface)
    surface.show()
    yield frame  # the surface (its parent) lives until the test ends
    surface.close()


@pytest.mark.parametrize("editable", [True, False])
def test_a_long_frame_title_is_cut_with_an_ellipsis_and_shown_whole_in_its_tooltip(frame, editable):
    frame.set_editable(editable)
    QtWidgets.QApplication.processEvents()
    shown = frame.title.text()
    assert shown.endswith("…") and "Battery voltage, main pack".startswith(shown[:-1]) and len(shown) >= 4, shown
    assert frame.title.toolTip() == "Battery voltage, main pack"
    start, end = _text_columns(frame)
    # what is drawn is the whole elided text: nothing clipped at the title's right edge
    advance = frame.title.fontMetrics().horizontalAdvance(shown)
    assert start + advance <= frame.title.geometry().right() + 1 - 4
    # a frame wide enough shows the whole title again
    frame.resize(600, 112)
    QtWidgets.QApplication.processEvents()
    assert frame.title.text() == "Battery voltage, main pack"


def test_the_title_leaves_room_for_the_status_badge(frame):
    frame.resize(300, 112)
    QtWidgets.QApplication.processEvents()
    assert frame.title.text() == "Battery voltage, main pack"
    frame.badge.show_status("down", "LINK DOWN")
    QtWidgets.QApplication.processEvents()
    shown = frame.title.text()
    assert shown.endswith("…"), shown
    start, end = _text_columns(frame)
    advance = frame.title.fontMetrics().horizontalAdvance(shown)
    assert start + advance < frame.badge.x(), (start, advance, frame.badge.geometry())
    frame.badge.show_status("", "")  # the link is back: the whole title again
    QtWidgets.QApplication.processEvents()
    assert frame.title.text() == "Battery voltage, main pack"
    assert frame.title.geometry().contains(QtCore.QPoint(frame.width() // 2, frame.title.y() + 2))
