"""How the window looks to an operator, on the real window against the sim: light, slim scroll bars that
still take a finger; a checked box shows a tick; the empty canvas's hint never points at a hidden panel.

``RCON_SCREENSHOTS=DIR`` writes a PNG of the window at each step (to look at it as a person would).
"""

from __future__ import annotations

import pytest
from app_helpers import (
    LEFT,
    NO_MOD,
    choose_kind,
    settle,
    snap,
    tap,
    tap_topic,
    window_maker,
)
from qtpy import QtCore, QtGui, QtWidgets
from qtpy.QtTest import QTest

from rcon_core.plugins import Role

pytestmark = pytest.mark.usefixtures("qapp")
pytest.importorskip("rcon_widgets_std")
pytest.importorskip("rcon_widgets_sensors")


@pytest.fixture
def make_window(qtbot, tmp_path, sim_thread, plugins):
    yield from window_maker(qtbot, tmp_path, plugins, url=sim_thread.url, wait_connected=True,
                            topics=("/battery", "/camera/front/image_raw"))


# ------------------------------------------------------------------------------------- scroll bars
def thumb_rect(bar: QtWidgets.QScrollBar) -> QtCore.QRect:
    opt = QtWidgets.QStyleOptionSlider()
    bar.initStyleOption(opt)
    return bar.style().subControlRect(QtWidgets.QStyle.ComplexControl.CC_ScrollBar, opt,
                                      QtWidgets.QStyle.SubControl.SC_ScrollBarSlider, bar)


def seen(bar: QtWidgets.QScrollBar) -> QtGui.QImage:
    """The bar as the operator sees it: the window's pixels where the bar is (what shows through too)."""
    window = bar.window()
    return window.grab(QtCore.QRect(bar.mapTo(window, QtCore.QPoint(0, 0)), bar.size())).toImage()


def painted_span(bar: QtWidgets.QScrollBar, behind: QtGui.QColor) -> tuple[int, int]:
    """Across a vertical bar, at the thumb's middle: (how many columns differ from what is behind the
    bar, the darkest value among them)."""
    img = seen(bar)
    y = thumb_rect(bar).center().y()
    values = [QtGui.QColor(img.pixel(x, y)) for x in range(img.width())]
    painted = [c for c in values if abs(c.value() - behind.value()) > 12]
    return len(painted), min((c.value() for c in painted), default=255)


@pytest.mark.parametrize("size", [(1280, 800), (1024, 600)])
def test_scroll_bars_are_slim_and_light_but_take_a_finger(make_window, qtbot, size):
    window = make_window(size, demo=True)
    window.resize(size[0], size[1] * 2 // 3)  # the demo fits the screen: a shorter window makes the canvas scroll
    settle()
    scroll = window.controller.surface.scroll_area
    bar = scroll.verticalScrollBar()
    qtbot.waitUntil(lambda: bar.isVisible() and bar.maximum() > 0, timeout=5_000)
    snap(window, f"scrollbar-{size[0]}")
    behind = window.controller.surface.grab().toImage().pixelColor(4, 4)  # the canvas background
    img = seen(bar)
    # the groove is see-through: above and below the thumb the canvas shows
    groove_y = [y for y in range(img.height()) if not thumb_rect(bar).adjusted(0, -4, 0, 4).contains(2, y)]
    assert groove_y
    assert all(abs(img.pixelColor(x, groove_y[-1]).value() - behind.value()) <= 12 for x in range(img.width()))
    # still a finger's strip...
    assert bar.width() >= 28, bar.width()
    # ...with a slim, grey (not black) thumb in it
    width, darkest = painted_span(bar, behind)
    assert 4 <= width <= bar.width() * 0.4, (width, bar.width())
    assert darkest > 100, darkest
    # held by the finger, the thumb widens and darkens: one can see what is grabbed
    centre = thumb_rect(bar).center()
    QTest.mousePress(bar, LEFT, NO_MOD, centre)
    settle()
    held, held_darkest = painted_span(bar, behind)
    snap(window, f"scrollbar-{size[0]}-held")
    QTest.mouseRelease(bar, LEFT, NO_MOD, centre)
    assert held > width and held_darkest < darkest, (width, held, darkest, held_darkest)


# ------------------------------------------------------------------------------------- checkbox tick
@pytest.mark.parametrize("size", [(1280, 800), (1024, 600)])
def test_a_checked_checkbox_shows_a_tick(make_window, qtbot, size):
    window = make_window(size)
    tap_topic(window, "/camera/front/image_raw")
    panel = choose_kind(window, Role.SUBSCRIBE, "sensors.image")
    boxes = [b for b in panel.settings_page.findChildren(QtWidgets.QCheckBox) if b.isVisible()]
    assert boxes, "the Image settings have on/off settings"
    box = boxes[0]
    settle()
    panel.settings_scroll.ensureWidgetVisible(box, 0, 60)
    settle()

    def indicator_colours() -> set[tuple[int, int, int]]:
        opt = QtWidgets.QStyleOptionButton()
        box.initStyleOption(opt)
        rect = box.style().subElementRect(QtWidgets.QStyle.SubElement.SE_CheckBoxIndicator, opt, box)
        img = box.grab().toImage()
        inner = rect.adjusted(6, 6, -6, -6)
        return {QtGui.QColor(img.pixel(x, y)).getRgb()[:3] for x in range(inner.left(), inner.right())
                for y in range(inner.top(), inner.bottom())}

    opt = QtWidgets.QStyleOptionButton()
    box.initStyleOption(opt)
    on_box = box.style().subElementRect(QtWidgets.QStyle.SubElement.SE_CheckBoxIndicator, opt, box).center()
    if not box.isChecked():
        tap(box, on_box)
    assert box.isChecked()
    snap(window, f"checkbox-checked-{size[0]}")
    checked = indicator_colours()
    assert (255, 255, 255) in checked, "no white tick on the checked box"
    assert any(b > 120 and r < 60 for r, _g, b in checked), "the checked box is not blue"
    tap(box, on_box)
    assert not box.isChecked()
    unchecked = indicator_colours()
    assert not any(b > 120 and r < 60 for r, _g, b in unchecked), "an unchecked box stays white"


# ------------------------------------------------------------------------------------- empty canvas hint
def test_the_empty_canvas_hint_says_what_to_tap_when_the_side_panel_is_hidden(make_window, qtbot):
    window = make_window((1024, 600))
    tap(window.edit_button)
    settle()
    hint = window.controller.surface.placeholder
    assert window.side.isVisible() and hint.isVisible()
    assert "on the left" in hint.text()
    tap(window.side_toggle)  # the operator hides the side panel for room
    settle()
    assert not window.side.isVisible()
    snap(window, "empty-canvas-side-hidden")
    assert "on the left" not in hint.text()
    assert window.side_toggle.text() in hint.text()  # names the button that brings the panel back
    # a canvas made now says the same
    window.controller.add_canvas("Second")
    window.switch_canvas(1)
    settle()
    assert window.side_toggle.text() in window.controller.surface.placeholder.text()
    tap(window.side_toggle)
    settle()
    assert window.side.isVisible() and "on the left" in window.controller.surface.placeholder.text()


def test_the_empty_canvas_hint_points_at_the_add_panel_while_it_is_open(make_window, qtbot):
    window = make_window((1024, 600))
    tap(window.edit_button)
    tap_topic(window, "/battery")
    tap(window.add_panel.role_buttons[Role.SUBSCRIBE])
    settle()
    hint = window.controller.surface.placeholder
    assert not window.side.isVisible() and not window.side_toggle.isEnabled()  # no room: ▶ cannot help
    snap(window, "empty-canvas-adding")
    assert "on the right" in hint.text() and "▶" not in hint.text()
    [cancel] = [b for b in window.add_panel.findChildren(QtWidgets.QPushButton, "cancelButton") if b.isVisible()]
    tap(cancel)
    settle()
    assert window.side.isVisible() and "on the left" in hint.text()
