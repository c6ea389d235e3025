"""A widget's ERROR badge tells why (issue 21.8), on the real window against the sim: at the widget's
default size the reason is the badge's tooltip (hover), and a tap on the badge shows it on one elided line
across the frame; a second tap hides it."""

from __future__ import annotations

import pytest
from app_helpers import TIMEOUT_MS, settle, snap, tap, tap_through, window_session
from qtpy import QtCore, QtGui, QtWidgets

from rcon_core.canvas import Binding, Canvas, Geometry, WidgetInstance, Workspace, new_id
from rcon_core.plugins import PluginManager, hookimpl

pytest.importorskip("rcon_widgets_std")
pytestmark = pytest.mark.usefixtures("qapp")

REASON = "the robot does not know lab_msgs/Winch (is its package installed there?)"


class WinchTypes:
    """A lab package that only contributes its message type (the sim does not know it)."""

    @hookimpl
    def rcon_register_types(self, registry):
        registry.add_msg("lab_msgs/Winch", "float64 payout\nfloat64 tension\nbool braked\n")


def layout(size: tuple[int, int]) -> Workspace:
    canvas = Canvas(new_id("c"), "Lab", locked=True)
    canvas.widgets.append(WidgetInstance(new_id("w"), "std.label",
                                         Binding("/winch", "lab_msgs/Winch", "subscribe", ("payout",)),
                                         Geometry(32, 32, *size), {}, "Winch payout"))
    return Workspace([canvas], canvas.id)


def hover_text(widget: QtWidgets.QWidget, pos: QtCore.QPoint) -> str:
    """What hovering ``pos`` of the frame shows: the tooltip of the widget the pointer is over."""
    target = widget.childAt(pos) or widget
    local = target.mapFrom(widget, pos)
    QtWidgets.QToolTip.hideText()
    QtWidgets.QApplication.sendEvent(target, QtGui.QHelpEvent(QtCore.QEvent.Type.ToolTip, local,
                                                              target.mapToGlobal(local)))
    return QtWidgets.QToolTip.text() if QtWidgets.QToolTip.isVisible() else target.toolTip()


@pytest.mark.parametrize("edit", [False, True])
def test_the_error_badge_shows_its_reason_on_hover_and_on_a_tap(qtbot, tmp_path, sim_thread, edit):
    pm = PluginManager(environ={})
    pm.load_entry_points()
    pm.register(WinchTypes(), name="winch")
    default = pm.widget("std.label").default_size
    for win in window_session(qtbot, tmp_path / "config", pm, url=sim_thread.url, demo=lambda: layout(default),
                              wait_connected=True):
        if edit:
            tap(win.edit_button)
        [frame] = win.controller.surface.frames.values()
        qtbot.waitUntil(lambda frame=frame: frame.badge.status == "ERROR", timeout=TIMEOUT_MS)
        settle()
        assert (frame.width(), frame.height()) == default
        badge = frame.badge.geometry()
        centre = badge.center()
        assert hover_text(frame, centre) == REASON  # not the title
        if edit:
            return  # in Edit mode a tap selects and drags the widget; the reason is on hover
        assert not frame.reason_line.isVisible()
        tap_through(frame, centre)  # what is under the finger gets it
        assert frame.reason_line.isVisible()
        snap(win, "badge-reason")
        line = frame.reason_line
        fm = line.fontMetrics()
        assert line.toolTip() == REASON and line.text().endswith("…") and line.text()[:-1] in REASON
        assert fm.horizontalAdvance(line.text()) <= line.contentsRect().width()
        assert line.height() < 2 * fm.lineSpacing()  # one line
        assert frame.rect().contains(line.geometry())
        assert not line.geometry().intersects(badge)  # the badge stays tappable
        tap_through(frame, centre)
        assert not frame.reason_line.isVisible()
