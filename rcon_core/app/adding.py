"""Adding a widget from the side panel: opening the add panel (in Edit mode only), placing its draft with
*Place* or by dropping it on the canvas, and giving the keyboard back to the work area (kept out of
``main_window.py``).

:class:`Adding` is given the few parts it works with, typed: the add panel, the canvas controller, the
operator lock (leaving Operate mode to add asks for its PIN), the notice bar, the side panel's policy, and
two steps the window composes in: ``bind`` (the draft talks to the side panel's robot,
``FleetUi.bind``) and ``check_placed`` (beyond the robot's safety envelope, ``EnvelopeControl``).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from qtpy import QtCore, QtWidgets

from rcon_core.app.add_panel import AddPanel
from rcon_core.app.canvas_controller import CanvasController
from rcon_core.app.draft import Draft
from rcon_core.app.focus import focus_into
from rcon_core.app.notice_bar import NoticeBar
from rcon_core.app.operator_lock import OperatorLock
from rcon_core.app.side_panel import SidePanelPolicy

__all__ = ["Adding"]


class Adding:
    """The add panel's way from a pick in the side panel to a widget on the canvas."""

    def __init__(self, add_panel: AddPanel, controller: CanvasController, lock: OperatorLock, notice: NoticeBar,
                 side_policy: SidePanelPolicy, bind: Callable[[Draft | None], Draft | None],
                 check_placed: Callable[[Draft], object]) -> None:
        self.add_panel, self.controller, self.lock, self.notice = add_panel, controller, lock, notice
        self.side_policy, self.bind, self.check_placed = side_policy, bind, check_placed
        add_panel.place_requested.connect(self.place)
        controller.on_drop = self.dropped

    def start(self, start: Callable[[], object]) -> None:
        """Open the add panel; on a locked canvas say why not and offer to switch to Edit mode."""
        self.in_edit_mode("add widgets", start)

    def in_edit_mode(self, what: str, start: Callable[[], object]) -> None:
        """Run ``start`` now in Edit mode; in Operate mode the notice says why not and offers to switch
        (then runs it)."""
        if not self.controller.canvas.locked:
            start()
            return

        def unlock_and_start() -> None:
            if self.lock.engaged:
                self.lock.guard(what, unlock_and_start)
                return
            self.notice.dismiss()
            self.controller.set_locked(False)
            start()
            self.focus_work_area()  # the tapped notice button is gone: not the URL field next in line

        self.notice.show_notice(f"ℹ Switch to Edit mode to {what}: this canvas is in Operate mode "
                                "(locked).", kind="info", actions=[("Switch to Edit mode", unlock_and_start)])

    def place(self) -> None:
        """*Place*: the draft goes to a free spot of the current canvas."""
        draft = self.bind(self.add_panel.take_draft())  # the panel closes
        if draft is not None:
            settle_layout()  # the free spot is looked for in the canvas as it is without the panel
            try:
                self.controller.add_draft(draft)
            except ValueError as exc:
                self.notice.show_notice(f"⚠ {exc}")
                return
            self.check_placed(draft)  # beyond the robot's safety envelope: kept only when the operator says

    def dropped(self, _surface: Any, point: QtCore.QPoint) -> None:
        """The draft was dropped on the canvas at ``point``."""
        policy = self.side_policy
        side_hidden = not policy.side.isVisibleTo(policy.window)
        draft = self.bind(self.add_panel.take_draft())  # the panel closes
        if side_hidden and policy.side.isVisibleTo(policy.window):
            # the side panel gave its room to the add panel; coming back now it would push the canvas
            # (and the widget just dropped under the finger) sideways: it stays hidden until ▶ is tapped
            policy.keep_hidden()
        if draft is not None:
            self.controller.add_draft(draft, point)
            self.check_placed(draft)  # beyond the robot's safety envelope: kept only when the operator says

    def focus_work_area(self) -> None:
        """Give the keyboard to what the operator works on: the add panel's page when it is open, else
        the canvas."""
        if self.add_panel.isVisible():
            page = self.add_panel.stack.currentWidget()
            focus_into(page if page is not None else self.add_panel)
        else:
            self.controller.surface.setFocus(QtCore.Qt.FocusReason.OtherFocusReason)


def settle_layout() -> None:
    """Apply pending layout changes now (the add panel just closed, the side panel may be back), so the
    canvas view has its new size."""
    for _ in range(3):
        QtWidgets.QApplication.sendPostedEvents(None, QtCore.QEvent.Type.LayoutRequest)
