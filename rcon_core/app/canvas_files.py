"""Sharing one canvas as a file: the window's *Export canvas…* and *Import canvas…* (kept out of
``main_window.py``).

:class:`CanvasFiles` opens Qt's own file dialog (the same on a tablet and offscreen) in :attr:`share_dir`,
the folder used last in this session; the dialog only picks a path, :meth:`CanvasFiles.export_to` and
:meth:`CanvasFiles.import_from` do the work and say on the notice bar what happened or why not. Importing
changes the workspace, so it needs Edit mode (the caller's ``in_edit_mode`` offers the switch).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from qtpy import QtCore, QtWidgets

from rcon_core.app import theme
from rcon_core.app.canvas_controller import CANVAS_SUFFIX, CanvasController, file_name_for
from rcon_core.app.notice_bar import NoticeBar
from rcon_core.canvas import Canvas, EditError, WorkspaceFileError
from rcon_core.plugins import PluginManager

__all__ = ["CanvasFiles"]


class CanvasFiles:
    """Export and import of single canvases for the window ``parent``."""

    def __init__(self, parent: QtWidgets.QWidget, controller: CanvasController, notice: NoticeBar,
                 plugins: PluginManager, in_edit_mode: Callable[[str, Callable[[], object]], None],
                 dialog_closed: Callable[[QtWidgets.QDialog], None]) -> None:
        self.parent, self.controller, self.notice, self.plugins = parent, controller, notice, plugins
        self.in_edit_mode = in_edit_mode
        self.dialog_closed = dialog_closed
        #: where the export/import file dialogs open (the folder used last in this session)
        self.share_dir = Path.home()
        #: the file dialog opened last (tests pick a file in it)
        self.dialog: QtWidgets.QFileDialog | None = None

    def file_dialog(self, name: str, title: str, *, save: bool) -> QtWidgets.QFileDialog:
        """A window-modal file dialog (Qt's own, not the platform's: the same on a tablet and offscreen),
        opening in :attr:`share_dir`. The caller connects ``fileSelected`` and calls ``open()``."""
        dialog = QtWidgets.QFileDialog(self.parent, title, str(self.share_dir))
        dialog.setObjectName(name)
        dialog.setOption(QtWidgets.QFileDialog.Option.DontUseNativeDialog, True)
        dialog.setNameFilters([f"RCON canvas (*{CANVAS_SUFFIX})", "JSON (*.json)", "All files (*)"])
        if save:
            dialog.setAcceptMode(QtWidgets.QFileDialog.AcceptMode.AcceptSave)
            dialog.setFileMode(QtWidgets.QFileDialog.FileMode.AnyFile)
            dialog.setDefaultSuffix(CANVAS_SUFFIX.lstrip("."))
        else:
            dialog.setAcceptMode(QtWidgets.QFileDialog.AcceptMode.AcceptOpen)
            dialog.setFileMode(QtWidgets.QFileDialog.FileMode.ExistingFile)
        touch = theme.current_touch_px()  # rows a finger can pick, the file name readable in full
        dialog.setStyleSheet(f"QTreeView::item, QListView::item {{ min-height: {touch}px; }}"
                             " QTreeView::item:selected, QListView::item:selected"
                             " { background: #0040a0; color: #ffffff; }")
        screen = self.parent.screen()
        free = screen.availableGeometry() if screen is not None else QtCore.QRect(0, 0, 1024, 700)
        dialog.resize(min(1000, free.width() - 40), min(700, free.height() - 40))
        files = dialog.findChild(QtWidgets.QTreeView, "treeView")
        if files is not None:
            files.header().resizeSection(0, max(files.header().sectionSize(0), dialog.width() // 2))
        dialog.finished.connect(lambda _result: self.dialog_closed(dialog))
        self.dialog = dialog
        return dialog

    def export_dialog(self) -> QtWidgets.QFileDialog:
        """Ask where to write the current canvas (default name from the canvas's name); works in Operate
        mode too (exporting changes nothing). The dialog only picks the path: :meth:`export_to`."""
        canvas = self.controller.canvas
        dialog = self.file_dialog("exportDialog", f"Export canvas “{canvas.name}”", save=True)
        dialog.selectFile(str(self.share_dir / file_name_for(canvas.name)))
        dialog.fileSelected.connect(lambda path: self.export_to(path, canvas))
        dialog.open()
        return dialog

    def export_to(self, path: str | Path, canvas: Canvas | None = None) -> Path | None:
        """Write ``canvas`` (default: the current one) to ``path`` atomically; the notice bar says where,
        or why not. Returns the path written, or None."""
        canvas = canvas if canvas is not None else self.controller.canvas
        canvases = self.controller.workspace.canvases
        if canvas not in canvases:
            self.notice.show_notice(f"⚠ Canvas “{canvas.name}” was not exported: it no longer exists.")
            return None
        try:
            written = self.controller.export_canvas(canvases.index(canvas), path)
        except OSError as exc:
            self.notice.show_notice(f"⚠ Canvas “{canvas.name}” could not be exported to {path}: "
                                    f"{exc.strerror or exc}.")
            return None
        self.share_dir = written.parent
        self.notice.show_notice(f"ℹ Canvas “{canvas.name}” exported to {written}.", kind="info")
        return written

    def import_dialog(self) -> QtWidgets.QFileDialog | None:
        """Ask for a canvas file to add (Edit mode only: in Operate mode the notice offers to switch).
        The dialog only picks the path: :meth:`import_from`."""
        opened: list[QtWidgets.QFileDialog] = []

        def open_dialog() -> None:
            dialog = self.file_dialog("importDialog", "Import canvas", save=False)
            dialog.fileSelected.connect(self.import_from)
            dialog.open()
            opened.append(dialog)

        self.in_edit_mode("import a canvas", open_dialog)
        return opened[0] if opened else None

    def import_from(self, path: str | Path) -> Canvas | None:
        """Add the canvas in ``path`` (one undo step) and show it. A file that cannot be used (corrupt,
        newer, not a canvas file) changes nothing: the notice bar says why. Returns the added canvas."""
        path = Path(path)
        if self.controller.canvas.locked:
            self.in_edit_mode("import a canvas", lambda: self.import_from(path))
            return None
        try:
            canvas = self.controller.import_canvas(path)
        except (WorkspaceFileError, EditError) as exc:
            detail = str(exc) if isinstance(exc, WorkspaceFileError) else f"{path}: {exc}"
            self.notice.show_notice(f"⚠ The canvas could not be imported: {detail}. Nothing was changed.")
            return None
        self.share_dir = path.parent
        missing = sorted({w.kind for w in canvas.widgets if not self.plugins.has_widget(w.kind)})
        count = sum(1 for w in canvas.widgets if w.kind in missing)
        text = f"ℹ Canvas “{canvas.name}” imported from {path.name} (↶ removes it)."
        if missing:
            text += (f" {count} widget{'s' if count != 1 else ''} need{'' if count != 1 else 's'} a package "
                     f"that is not installed ({', '.join(missing)}): shown as placeholders, their settings kept.")
        self.notice.show_notice(text, kind="info")
        return canvas
