"""The canvas bar above the canvas: the canvas tabs, the *Canvas ▾* menu, undo/redo and the two-segment
mode control (``✎ Edit | Operate``), kept out of ``main_window.py``.

The bar only shows and reports: the window tells it the canvases (:meth:`CanvasBar.show_canvases`), the
mode (:meth:`CanvasBar.show_mode`) and whether to be compact (:meth:`CanvasBar.set_compact`); a tab tap
arrives as ``tabs.currentChanged``, a segment tap as :attr:`CanvasBar.mode_tapped` ``(locked, checked)``.
The menu's actions run the slots the window passes in (``menu``: name -> (text, slot)); those named in
``gated`` (name -> what it does, in words) go through ``guard`` first: the operator lock's PIN while it is
engaged (:data:`~rcon_core.app.operator_lock.Guard`), composed in when the bar is built.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

from qtpy import QtCore, QtGui, QtWidgets

from rcon_core.app import theme
from rcon_core.app.canvas_tabs import CanvasTabs
from rcon_core.app.operator_lock import Guard, no_guard

__all__ = ["CanvasBar"]

#: a canvas bar narrower than this gets the short labels (☰ for the menu)
COMPACT_BELOW = 820


class CanvasBar(QtWidgets.QFrame):
    """The bar; ``canvas_actions`` (the menu's, by name) and ``canvas_buttons`` (undo, redo) are public,
    the operator lock's controls add theirs to the same menu."""

    mode_tapped = QtCore.Signal(bool, bool)  #: (the tapped segment's mode is locked, it is now checked)

    def __init__(self, menu: dict[str, tuple[str, Callable[[], object]]], undo: Callable[[], object],
                 redo: Callable[[], object], parent: QtWidgets.QWidget | None = None, *,
                 guard: Guard = no_guard, gated: Mapping[str, str] | None = None) -> None:
        super().__init__(parent)
        self.setObjectName("modeBar")
        self.tabs = CanvasTabs()  # whole names, scrolling when they do not all fit
        # the mode: a two-segment control, the active segment filled ("Edit | Operate"); lock_button is the
        # Operate segment (checked = the canvas is locked)
        self.edit_button = QtWidgets.QPushButton("✎ Edit")
        self.edit_button.setObjectName("editButton")
        self.lock_button = QtWidgets.QPushButton("Operate")
        self.lock_button.setObjectName("lockButton")
        for button, locked in ((self.edit_button, False), (self.lock_button, True)):
            button.setCheckable(True)
            button.toggled.connect(lambda checked, locked=locked: self.mode_tapped.emit(locked, checked))
        mode_switch = QtWidgets.QFrame()
        mode_switch.setObjectName("modeSwitch")
        mode_switch.setToolTip("Edit: move, resize, add and delete widgets. Operate: the canvas is locked and "
                               "the widgets take your touches.")
        seg = QtWidgets.QHBoxLayout(mode_switch)
        seg.setContentsMargins(0, 0, 0, 0)
        seg.setSpacing(0)
        seg.addWidget(self.edit_button)
        seg.addWidget(self.lock_button)
        row = QtWidgets.QHBoxLayout(self)
        row.setContentsMargins(6, 6, 12, 6)  # the last segment clear of the window's edge
        row.setSpacing(4)
        row.addWidget(self.tabs, 1)
        self.canvas_buttons: dict[str, QtWidgets.QPushButton] = {}
        self.canvas_actions: dict[str, QtGui.QAction] = {}
        self.menu_button = QtWidgets.QPushButton("Canvas ▾")
        self.menu_button.setObjectName("canvasMenuButton")
        self.menu_button.setToolTip("New, rename, duplicate, delete, export or import canvases")
        self.compact = False
        self._locked = False
        self._padlock = False
        self.menu = QtWidgets.QMenu(self.menu_button)
        gated = gated or {}
        for name, (text, slot) in menu.items():
            action = self.menu.addAction(text)
            action.setObjectName(f"canvas_{name}")
            what = gated.get(name)
            if what is None:
                action.triggered.connect(lambda _checked=False, slot=slot: slot())
            else:
                action.triggered.connect(lambda _checked=False, slot=slot, what=what: guard(what, slot))
            self.canvas_actions[name] = action
        self.menu_button.setMenu(self.menu)
        row.addWidget(self.menu_button)
        for name, text, slot in (("undo", "↶", undo), ("redo", "↷", redo)):
            b = QtWidgets.QPushButton(text)
            b.setObjectName(f"canvas_{name}")
            b.setToolTip(name.capitalize())
            b.setProperty("square", True)
            b.clicked.connect(lambda _checked=False, slot=slot: slot())
            self.canvas_buttons[name] = b
            row.addWidget(b)
        row.addWidget(mode_switch)

    # -- the canvases ------------------------------------------------------------------------------
    def show_canvases(self, names: list[str], index: int, locked: bool) -> None:
        """The tabs show ``names`` with ``index`` current (no ``currentChanged`` for this)."""
        self.tabs.blockSignals(True)
        while self.tabs.count():
            self.tabs.removeTab(0)
        for name in names:
            self.tabs.addTab(name)
        self.tabs.setCurrentIndex(index)
        self.tabs.blockSignals(False)
        self._fit_tabs()
        self.canvas_actions["delete"].setEnabled(len(names) > 1 and not locked)

    def _fit_tabs(self) -> None:
        """The canvas tabs never get so narrow that only the scroll arrows show: room for the widest tab
        (up to about 12 letters) and, when they overflow, the two scroll buttons."""
        fm = self.tabs.fontMetrics()
        widest = max((self.tabs.tabSizeHint(i).width() for i in range(self.tabs.count())), default=0)
        readable = min(widest, fm.horizontalAdvance("M" * 12))
        scrollers = 2 * theme.current_touch_px() + 4 if self.tabs.count() > 1 else 0
        every = sum(self.tabs.tabSizeHint(i).width() for i in range(self.tabs.count()))
        self.tabs.setMinimumWidth(min(every, readable + scrollers))

    def changeEvent(self, event: QtCore.QEvent) -> None:  # noqa: N802 - Qt's name
        super().changeEvent(event)
        if event.type() in (QtCore.QEvent.Type.StyleChange, QtCore.QEvent.Type.FontChange) and \
                hasattr(self, "_locked"):
            self._fit_tabs()  # another text size: the tabs' and the segments' room measured again
            self.show_mode(self._locked, self._padlock)

    # -- the mode ----------------------------------------------------------------------------------
    def show_lock(self, locked: bool, canvases: int, padlock: bool) -> None:
        """Edit or Operate mode: the segments, undo/redo and the editing actions follow."""
        self.show_mode(locked, padlock)
        for name in ("undo", "redo"):
            self.canvas_buttons[name].setEnabled(not locked)
        for name in ("rename", "delete"):
            self.canvas_actions[name].setEnabled(not locked and (name != "delete" or canvases > 1))

    def show_mode(self, locked: bool, padlock: bool) -> None:
        """The mode control shows the current mode: its segment is filled (checked), the other is not;
        ``padlock``: the operator lock is on (the Edit segment is as wide as its text and padlock)."""
        self._locked, self._padlock = locked, padlock
        for button, checked in ((self.lock_button, locked), (self.edit_button, not locked)):
            button.blockSignals(True)
            button.setChecked(checked)
            button.blockSignals(False)
            fm = button.fontMetrics()
            button.setMinimumWidth(fm.horizontalAdvance(button.text()) + 32)  # the border, a little room
        self.lock_button.setToolTip("Operate (current): the canvas is locked, the widgets take your touches"
                                    if locked else "Tap to lock the canvas for operation")
        self.edit_button.setToolTip("Edit (current): move, resize, add and delete widgets" if not locked
                                    else "Tap to unlock the canvas for editing")
        if padlock:
            self.edit_button.setMinimumWidth(self.edit_button.sizeHint().width())  # text and padlock

    def set_compact(self, compact: bool) -> None:
        """Short labels when the centre is narrow (e.g. the add panel is open), so the tabs keep their
        room and no button text is cut."""
        if compact != self.compact:
            self.compact = compact
            self.menu_button.setText("☰" if compact else "Canvas ▾")
            self.show_mode(self._locked, self._padlock)
