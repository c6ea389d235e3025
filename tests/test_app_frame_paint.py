"""A live value repaints only its view: not the frame around it, the shield, or the canvas behind."""

from __future__ import annotations

from collections import Counter

import pytest
from qtpy import QtCore, QtWidgets

from rcon_core.app.theme import stylesheet
from rcon_core.app.widget_frame import CornerMark, WidgetFrame
from rcon_core.testing import qt_flushed


class PaintCounter(QtCore.QObject):
    """Counts the paint events each watched widget receives."""

    def __init__(self, widgets: dict[str, QtWidgets.QWidget]) -> None:
        super().__init__()
        self.names = {id(w): name for name, w in widgets.items()}
        self.counts: Counter[str] = Counter()
        for w in widgets.values():
            w.installEventFilter(self)

    def eventFilter(self, obj: QtCore.QObject, event: QtCore.QEvent) -> bool:  # noqa: N802 - Qt's name
        if event.type() == QtCore.QEvent.Type.Paint:
            self.counts[self.names.get(id(obj), "?")] += 1
        return False


@pytest.fixture
def canvas(qtbot):
    surface = QtWidgets.QWidget()
    surface.setObjectName("canvasSurface")
    surface.setStyleSheet(stylesheet(touch=48))
    surface.resize(400, 300)
    frame = WidgetFrame("w-1", "Value", surface)
    view = QtWidgets.QLabel("0.0000")
    frame.set_view(view)
    frame.setGeometry(16, 16, 200, 120)
    qtbot.addWidget(surface)
    surface.show()
    qtbot.waitExposed(surface)
    return surface, frame, view


@pytest.mark.parametrize("editable", [True, False])
def test_value_change_repaints_only_the_view(qtbot, canvas, editable):
    surface, frame, view = canvas
    frame.set_editable(editable)
    qt_flushed(qtbot)  # the repaints the switch asked for are done before counting
    counter = PaintCounter({"surface": surface, "frame": frame, "shield": frame.shield, "view": view,
                            "body": frame.body})
    for i in range(1, 6):
        view.setText(f"{i * 1.25:.4f}")  # a new text each time (the same text repaints nothing)
        qtbot.waitUntil(lambda n=i: counter.counts["view"] >= n, timeout=5000)
    assert frame.body.autoFillBackground(), "the body must stay opaque under the theme"
    assert counter.counts["surface"] == 0 and counter.counts["frame"] == 0
    assert counter.counts["shield"] == 0  # the shield takes presses only; it never paints
    assert counter.counts["body"] >= 5


def test_body_stays_opaque_after_the_theme_is_applied_again(qtbot, canvas):
    surface, frame, view = canvas
    surface.setStyleSheet(stylesheet(touch=56))  # re-polishes every child
    qt_flushed(qtbot)
    assert frame.body.autoFillBackground()
    assert frame.body.palette().color(frame.body.backgroundRole()).name() == "#ffffff"


def test_corner_marks_show_in_edit_mode_only_and_grow_when_selected(qtbot, canvas):
    _surface, frame, _view = canvas
    marks = frame.findChildren(CornerMark)
    assert sorted(m.corner for m in marks) == ["bl", "br", "tl", "tr"]
    frame.set_editable(True)
    assert all(m.isVisible() for m in marks)
    plain = {m.corner: m.pixmap().size() for m in marks}
    frame.set_selected(True)
    for m in marks:
        assert m.pixmap().width() > plain[m.corner].width()
        assert m.testAttribute(QtCore.Qt.WidgetAttribute.WA_TransparentForMouseEvents)
        # flush with the frame's corner, so the resize handles stay where the L is
        rect = m.geometry()
        assert (rect.left() == 0) == (m.corner[1] == "l") and (rect.top() == 0) == (m.corner[0] == "t")
        assert (rect.right() == frame.width() - 1) == (m.corner[1] == "r")
    frame.set_editable(False)
    assert not any(m.isVisible() for m in marks)


@pytest.mark.parametrize("kind, text", [("down", "LINK DOWN"), ("stale", "STALE"), ("problem", "ERROR")])
def test_status_badge_sits_in_the_title_bar_never_over_the_view(qtbot, kind, text):
    frame = WidgetFrame("w-2", "Battery")
    frame.set_view(QtWidgets.QLabel("85 %"))
    frame.resize(260, 140)
    qtbot.addWidget(frame)
    frame.show()
    frame.badge.show_status(kind, text)
    badge = frame.badge.geometry()
    assert frame.badge.isVisible() and badge.width() > 0
    assert not badge.intersects(frame.body.geometry())
    assert frame.title.geometry().contains(badge)
