"""The theme's style sheet on real widgets, offscreen: overflowing tab bars keep touch-sized scroll buttons
with arrows, disabled menu items look disabled, labels do not sit in white boxes on grey surfaces."""

import pytest
from qtpy import QtCore, QtGui, QtWidgets

from rcon_core.app.theme import stylesheet
from rcon_core.testing import qt_flushed

TOUCH = 48


@pytest.fixture
def themed(qtbot):
    host = QtWidgets.QWidget()
    host.setStyleSheet(stylesheet(touch=TOUCH))
    qtbot.addWidget(host)
    return host


def _ink_pixels(img: QtGui.QImage, rect: QtCore.QRect) -> int:
    return sum(1 for x in range(rect.left(), rect.right()) for y in range(rect.top(), rect.bottom())
               if QtGui.QColor(img.pixel(x, y)).value() < 200)


def test_tab_scroll_buttons_are_touch_sized_with_arrows(themed, qtbot):
    tabs = QtWidgets.QTabBar(themed)
    tabs.setExpanding(False)
    for name in ["Drive", "Sensors", "Mission", "Map view", "Diagnostics"]:
        tabs.addTab(name)
    tabs.setGeometry(0, 0, 420, 70)
    themed.resize(440, 90)
    themed.show()
    qtbot.waitExposed(themed)
    buttons = [b for b in tabs.findChildren(QtWidgets.QToolButton) if b.isVisible()]
    assert len(buttons) == 2, "five tabs in 420 px must scroll"
    for b in buttons:
        assert b.width() >= TOUCH - 4 and b.height() >= TOUCH - 4, f"scroll button {b.size()} is not touch-sized"
        img = b.grab().toImage()
        inner = QtCore.QRect(b.width() // 3, b.height() // 3, b.width() // 3, b.height() // 3)
        assert _ink_pixels(img, inner) > 20, "no arrow drawn in the scroll button"
    tabs.setCurrentIndex(4)  # the last tab is reachable
    qt_flushed(qtbot)
    assert tabs.tabRect(4).right() <= tabs.width()


def test_disabled_menu_items_look_disabled(themed, qtbot):
    menu = QtWidgets.QMenu(themed)
    enabled = menu.addAction("Rename…")
    disabled = menu.addAction("Delete")
    disabled.setEnabled(False)
    menu.popup(QtCore.QPoint(0, 0))
    qtbot.waitExposed(menu)
    img = menu.grab().toImage()

    def darkest(action):
        r = menu.actionGeometry(action)
        return min(QtGui.QColor(img.pixel(x, y)).value() for x in range(r.left() + 2, r.right() - 2)
                   for y in range(r.top() + 2, r.bottom() - 2))

    assert darkest(enabled) < 60 and darkest(disabled) > 100  # black text vs grey text
    menu.close()


def test_form_labels_have_no_white_box_on_a_grey_dialog(qtbot):
    dialog = QtWidgets.QDialog()
    dialog.setStyleSheet(stylesheet(touch=TOUCH))
    qtbot.addWidget(dialog)
    form = QtWidgets.QFormLayout(dialog)
    label = QtWidgets.QLabel("Decimals")
    form.addRow(label, QtWidgets.QSpinBox())
    check = QtWidgets.QCheckBox("Follow the topic")
    form.addRow(check)
    dialog.show()
    qtbot.waitExposed(dialog)
    img = dialog.grab().toImage()
    grey = QtGui.QColor(img.pixel(2, 2))
    for w in (label, check):
        corner = w.geometry().topRight() + QtCore.QPoint(-2, 2)
        assert QtGui.QColor(img.pixel(corner)) == grey, f"{w.text()!r} sits in a box of another colour"
