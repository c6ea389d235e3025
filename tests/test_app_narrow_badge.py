"""The status badge on a narrow widget leaves its title readable (found walking the app on a tablet): LINK
DOWN covered the whole title of Battery, Lights, Dock and Depth, so exactly while the link was down an
operator could not tell which widget was which. The badge now takes a compact form where the frame has no
room for the whole word -- a short word, then a sign -- and says the whole status in its accessible name,
its tooltip and the line a tap on it shows."""

from __future__ import annotations

import pytest
from app_helpers import TIMEOUT_MS, entry_point_plugins, settle, snap, tap_through, window_maker
from qtpy import QtCore, QtGui, QtWidgets

from rcon_core.app import theme
from rcon_core.app.display_settings import set_display
from rcon_core.app.theme import stylesheet
from rcon_core.app.widget_frame import WidgetFrame

pytestmark = pytest.mark.usefixtures("qapp")
DOWN = "the link to this widget's robot is down: nothing arrives, nothing is sent"


def painted_title_end(frame: WidgetFrame) -> int:
    """The right end (frame x) of the title's text as the title would draw it: its left contents edge plus
    the advance of what it shows."""
    title = frame.title
    return title.x() + title.contentsRect().left() + title.fontMetrics().horizontalAdvance(title.text())


def clipped(badge) -> bool:
    """Whether the badge's text is wider or taller than the pill shows (cut at its edges)."""
    fm, inside = badge.fontMetrics(), badge.contentsRect()
    return fm.horizontalAdvance(badge.text()) > inside.width() + 1 or fm.ascent() > inside.height() + 1


# ------------------------------------------------------------------------------------ the real window
@pytest.fixture
def make(qtbot, tmp_path):
    pytest.importorskip("rcon_widgets_std")
    pytest.importorskip("rcon_widgets_sensors")
    yield from window_maker(qtbot, tmp_path, entry_point_plugins(), demo=True)


@pytest.fixture
def standard_look():
    app = QtWidgets.QApplication.instance()
    yield
    theme.apply(app, theme.DEFAULT_THEME, 100)


@pytest.mark.parametrize("text_size", [100, 200])
def test_every_demo_widget_keeps_its_whole_title_under_link_down_on_a_1024x600_tablet(make, qtbot, text_size,
                                                                                     standard_look):
    """The demo's Drive canvas, no robot connected (every widget LINK DOWN), 1024x600, 100 % and 200 %
    text: each frame shows its whole title left of the badge; the badge is in the title bar, as tall as
    the bar allows and at least as wide as tall, in the link-down red, and says LINK DOWN in words where
    it is compact (its status, its accessible name, its tooltip)."""
    win = make((1024, 600))
    set_display(win.config, None, text_size=text_size)
    frames = list(win.controller.surface.frames.values())
    assert {f.title.full_title for f in frames} >= {"Battery", "Lights", "Dock", "Depth"}
    qtbot.waitUntil(lambda: all(f.badge.isVisible() and f.badge.status == "LINK DOWN" for f in frames),
                    timeout=TIMEOUT_MS)
    settle()
    snap(win, f"narrow-badge-{text_size}")
    compact = 0
    for frame in frames:
        badge, title = frame.badge, frame.title
        name = title.full_title
        assert title.text() == name, (name, title.text(), badge.text(), frame.width())
        assert painted_title_end(frame) < badge.x(), (name, badge.geometry())
        assert title.geometry().contains(badge.geometry()), name
        assert badge.width() >= badge.height() >= title.height() // 2, (name, badge.size())
        assert not clipped(badge), (name, badge.text(), badge.size(), badge.contentsRect(), title.geometry(), badge.maximumHeight(), badge.font().pixelSize(), badge.fontMetrics().ascent(), badge.styleSheet())
        assert "#b00000" in badge.styleSheet()
        assert badge.accessibleName() == "status: LINK DOWN"
        if badge.compact:
            compact += 1
            assert badge.text() in ("DOWN", "!") and badge.toolTip() == f"LINK DOWN: {DOWN}", name
        else:
            assert badge.text() == "LINK DOWN" and badge.toolTip() == DOWN, name
    assert compact  # the narrow widgets' badges are compact, the wide ones' whole


# ------------------------------------------------------------------------------------ one frame
@pytest.fixture
def frame(qtbot):
    surface = QtWidgets.QWidget()
    surface.setStyleSheet(stylesheet(touch=48))
    surface.resize(700, 300)
    frame = WidgetFrame("w-1", "Battery", surface)
    frame.set_view(QtWidgets.QLabel("85 %"))
    frame.set_editable(False)
    qtbot.addWidget(surface)
    surface.show()
    yield frame
    surface.close()


def test_the_badge_takes_the_longest_form_that_leaves_the_title_whole(frame):
    frame.setGeometry(16, 16, 400, 96)
    frame.badge.show_status("down", "LINK DOWN", DOWN)
    settle()
    assert frame.badge.text() == "LINK DOWN" and not frame.badge.compact
    widths = {}
    for width in range(400, 47, -8):
        frame.resize(width, 96)
        QtWidgets.QApplication.processEvents()
        widths.setdefault(frame.badge.text(), width)
        if frame.title.fontMetrics().horizontalAdvance("Battery") <= frame.title.contentsRect().width() // 2:
            assert frame.title.text() == "Battery", (width, frame.badge.text())  # whole, where it fits at all
        assert frame.badge.status == "LINK DOWN" and frame.badge.accessibleName() == "status: LINK DOWN"
    assert list(widths) == ["LINK DOWN", "DOWN", "!"]  # whole, short, sign, as the frame narrows
    assert widths["LINK DOWN"] > widths["DOWN"] > widths["!"] > 48
    frame.resize(400, 96)  # room again: the whole word again
    QtWidgets.QApplication.processEvents()
    assert frame.badge.text() == "LINK DOWN" and frame.badge.toolTip() == DOWN
    frame.badge.show_status("", "")  # the link is back: no badge, no status
    assert not frame.badge.isVisible() and frame.badge.status == "" and frame.title.text() == "Battery"


def test_a_tap_on_a_compact_badge_says_the_whole_status_and_why(frame, qtbot):
    frame.setGeometry(16, 16, 144, 96)
    frame.badge.show_status("down", "LINK DOWN", DOWN)
    settle()
    assert frame.badge.compact and frame.title.text() == "Battery"
    tap_through(frame.badge)
    line = frame.reason_line
    assert line.isVisible() and line.toolTip() == f"LINK DOWN: {DOWN}" and line.text().startswith("LINK DOWN")
    tap_through(frame.badge)
    assert not line.isVisible()


def test_a_status_without_a_short_word_or_sign_keeps_its_word(frame):
    """VIEW ONLY has a short word and no sign: the narrowest frame shows VIEW, never nothing."""
    frame.setGeometry(16, 16, 96, 96)
    frame.badge.show_status("view-only", "VIEW ONLY", "robot is view-only: nothing is sent to the robot")
    settle()
    assert frame.badge.isVisible() and frame.badge.text() == "VIEW" and frame.badge.status == "VIEW ONLY"
    image = frame.grab().toImage()
    centre = frame.badge.geometry().center()
    assert QtGui.QColor(image.pixel(centre.x(), frame.badge.y() + 2)) == QtGui.QColor("#3a3a3a")
    assert frame.rect().contains(frame.badge.geometry()) and QtCore.QRect(frame.badge.geometry()).width() > 0
