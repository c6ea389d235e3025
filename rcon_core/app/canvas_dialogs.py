"""The canvas menu's questions (kept out of ``main_window.py``): *Rename…* asks for the name, *Delete…*
asks before a canvas with widgets goes. A refused edit (an empty name, the last canvas) is said on the
notice bar and changes nothing."""

from __future__ import annotations

from qtpy import QtWidgets

from rcon_core.app.canvas_controller import CanvasController
from rcon_core.app.notice_bar import NoticeBar
from rcon_core.app.params_panel import Confirm

__all__ = ["delete_current", "rename_current"]


def rename_current(parent: QtWidgets.QWidget, controller: CanvasController, notice: NoticeBar) -> None:
    """Ask for the current canvas's new name, then rename it."""
    index = controller.index
    name, ok = QtWidgets.QInputDialog.getText(parent, "Rename canvas", "Name", text=controller.canvas.name)
    if ok:
        try:
            controller.rename_canvas(index, name)
        except ValueError as exc:
            notice.show_notice(f"⚠ {exc}")


def delete_current(controller: CanvasController, notice: NoticeBar, confirm: Confirm) -> None:
    """Delete the current canvas; one with widgets is deleted only after the operator confirms."""
    canvas = controller.canvas

    def delete() -> None:
        if canvas in controller.workspace.canvases:
            try:
                controller.delete_canvas(controller.workspace.canvases.index(canvas))
            except ValueError as exc:
                notice.show_notice(f"⚠ {exc}")

    if not canvas.widgets or len(controller.workspace.canvases) < 2:
        delete()  # nothing to lose (or refused with a message: the last canvas stays)
        return
    count = len(canvas.widgets)
    confirm(f"Delete canvas “{canvas.name}”?",
            f"It holds {count} widget{'s' if count != 1 else ''}. Undo (↶, Ctrl+Z) brings it back.", "Delete", delete)
