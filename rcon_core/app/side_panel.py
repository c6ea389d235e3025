"""Whether the side panel (topics, services, actions, params, widgets) is shown: the window's side-panel
policy, kept out of ``main_window.py``.

The automatic choice hides it in a small window in Operate mode (the canvas gets the room) and whenever
it does not fit beside the canvas bar (and the add panel, when that is open) without widening the window.
The operator's toggle (◀/▶) overrides the automatic choice until that choice changes. The policy tells
the canvas where free room is through :attr:`SidePanelPolicy.hint_changed`: ``"side"``, ``"adding"`` or
``"hidden"``.
"""

from __future__ import annotations

from qtpy import QtCore, QtWidgets

from rcon_core.app.theme import current_text_size

__all__ = ["PANEL_MIN", "SIDE_MIN", "SMALL_WINDOW", "SidePanelPolicy"]

#: narrowest side panel (topics, services, widgets) and add panel
SIDE_MIN = 360  # with the tab column down its left edge (about 42 px); room beside the canvas bar at 125 % text
PANEL_MIN = 310
#: a window narrower than this is a small screen: in Operate mode the side panel hides itself
SMALL_WINDOW = 1100


class SidePanelPolicy(QtCore.QObject):
    """Shows or hides ``side`` in ``window``'s splitter ``split`` (side | ``center`` | ``add_panel``)."""

    hint_changed = QtCore.Signal(str)

    def __init__(self, window: QtWidgets.QWidget, side: QtWidgets.QWidget, toggle: QtWidgets.QPushButton,
                 split: QtWidgets.QSplitter, center: QtWidgets.QWidget, add_panel: QtWidgets.QWidget) -> None:
        super().__init__(window)
        self.window, self.side, self.toggle_button = window, side, toggle
        self.split, self.center, self.add_panel = split, center, add_panel
        self.locked = False  #: the current canvas is in Operate mode (the window says so: :meth:`set_locked`)
        #: the operator's own show/hide (the toggle), kept until the automatic choice changes
        self.override: bool | None = None
        self.auto_hidden: bool | None = None
        #: the side panel is shown in place of the canvas column (no room beside it; see update)
        self.drawer = False
        #: the add panel is shown in place of the canvas column (no room beside it)
        self.panel_alone = False
        toggle.clicked.connect(lambda _checked=False: self.toggle())

    def set_locked(self, locked: bool) -> None:
        self.locked = locked
        self.update()

    def centre_min(self) -> int:
        """The canvas column's minimum width as it is now. A box that holds a layout (the mode switch)
        tells its parent's layout its new minimum only once its own pending layout request is handled;
        told now, so a mode or text size that just widened the canvas bar's buttons is counted (else the
        side panel showed and the window grew past the screen)."""
        for bar in self.center.findChildren(QtWidgets.QFrame, "modeBar"):  # the canvas bar's boxes
            for widget in (bar, *bar.findChildren(QtWidgets.QWidget)):
                if widget.layout() is not None:
                    widget.updateGeometry()
        return self.center.minimumSizeHint().width()

    def room_for_side(self) -> bool:
        """Whether the side panel fits beside the canvas bar (and the add panel when it is open) without
        widening the window."""
        need = SIDE_MIN + self.centre_min() + self.split.handleWidth()
        if self.add_panel.isVisible():
            need += PANEL_MIN + self.split.handleWidth()
        return self.window.width() >= need

    def room_for_add_panel(self) -> bool:
        """Whether the add panel, as narrow as its content allows, fits beside the canvas column."""
        # its settings forms need room for a label beside its field, more with a larger text size
        panel = max(round(PANEL_MIN * current_text_size() / 100), self.add_panel.minimumSizeHint().width())
        need = self.centre_min() + panel + self.split.handleWidth()
        return self.window.width() >= need

    def auto_hide(self) -> bool:
        """Whether the side panel should give its room away: a small window in Operate mode, or no room."""
        if self.locked and self.window.width() < SMALL_WINDOW:
            return True
        return not self.room_for_side()

    def update(self) -> None:
        """Show or hide the side panel: the automatic choice, unless the operator used the toggle since
        that choice last changed. Where it has no room beside the canvas (a small window, a large text
        size), the operator's ▶ shows it *in place of* the canvas (:attr:`drawer`) until ◀, or until a
        pick opens the add panel (which then takes the room beside the canvas)."""
        auto = self.auto_hide()
        if auto != self.auto_hidden:
            self.auto_hidden = auto
            self.override = None
        room = self.room_for_side()
        adding = self.add_panel.isVisible()
        if adding and self.override and not room:
            self.override = None  # the pick is made: after adding, the canvas shows again
        shown = self.override if self.override is not None else not auto
        self.drawer = bool(shown and not room and not adding)
        shown = shown and (room or self.drawer)  # never by widening the window past the screen
        # the add panel where the canvas is, when the two do not fit side by side (a large text size)
        self.panel_alone = adding and not self.room_for_add_panel()
        centre = not (self.drawer or self.panel_alone)
        if self.center.isVisibleTo(self.window) != centre:
            self.center.setVisible(centre)
        if shown != self.side.isVisibleTo(self.window):
            self.side.setVisible(shown)
        self.toggle_button.setText("◀" if shown else "▶")
        self.hint_changed.emit("side" if shown else "adding" if adding else "hidden")
        self.toggle_button.setEnabled(shown or room or not adding)
        tip = ("Hide topics, services and widgets (back to the canvas)" if self.drawer
               else "Hide topics, services and widgets (more room for the canvas)" if shown
               else "Show topics, services and widgets" if room
               else "Show topics, services and widgets (in place of the canvas: no room beside it)" if not adding
               else "No room for topics, services and widgets beside the canvas and the add panel")
        self.toggle_button.setToolTip(tip)
        self.toggle_button.setAccessibleName(tip)

    def toggle(self) -> None:
        """The operator shows or hides the side panel."""
        self.override = not self.side.isVisibleTo(self.window)
        self.update()
        if self.add_panel.isVisible():
            self.make_room_for_add_panel()

    def keep_hidden(self) -> None:
        """The side panel stays hidden until ▶ is tapped (a widget was just dropped where it would push)."""
        self.override = False
        self.update()

    def make_room_for_add_panel(self) -> None:
        """The add panel takes its room from the side panel and the canvas, never by growing the window."""
        self.update()
        if not self.add_panel.isVisible():
            return
        sizes = self.split.sizes()
        total = sum(sizes)
        side = max(sizes[0], SIDE_MIN) if self.side.isVisibleTo(self.window) else 0
        if self.panel_alone:  # the canvas gave its place: the panel takes the width
            self.split.setSizes([side, 0, total - side])
            return
        room = total - side - self.centre_min()
        panel = max(PANEL_MIN, min(460, max(400, total // 3), room))
        self.split.setSizes([side, max(0, total - side - panel), panel])
