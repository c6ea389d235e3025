"""The window's operator-lock and view-only controls (kept out of ``main_window.py``).

The lock is composed in, not patched in afterwards: the window builds the canvas bar (gating
:data:`GATED_ACTIONS`), the connection bar and the Parameters panel with the lock's ``guard``
(:data:`~rcon_core.app.operator_lock.Guard`), so each asks for the PIN itself. :class:`LockControls` is
given the few parts it acts on, typed, talks back through its signal, and adds:

- *Lock Operate mode…* in the canvas menu (``canvas_lock``): engages the operator lock (asking for a new
  PIN first when none is set). While engaged the Edit segment shows a padlock and a tap on it asks for
  the PIN (no extra button: the bars have no room to spare on a 1024 px tablet);
- (through the guard each part was built with) the PIN gate on the canvas menu's editing actions, on the
  robot's Connect/Disconnect button (the URL field is disabled while locked), on the connection bar's
  Security dialog (the robot's TLS files and rosauth secret) and on the Parameters panel's Set; the
  window itself gates leaving Operate mode, adding
  widgets (and so calling a service from the side panel) and quitting, the robots menu gates the Robots
  dialog (see :class:`~rcon_core.app.operator_lock.OperatorLock`);
- *View only* in the canvas menu, for the side panel's robot, named in the action (``robot_view_only``:
  that robot's URL never gets anything sent, remembered in the app config, enforced on its link; see
  :mod:`rcon_core.app.view_only`; ``robot_view_only_changed`` tells the window to restart the widgets on
  ports that carry the mark) and for the canvas (``canvas_view_only``: saved in the layout).
  Turning either on is always allowed; turning it off is an edit (the PIN when locked);
- the app config's problems on the notice bar: a change that could not be saved (a full or read-only
  disk: it holds for this run), and a config folder another RCON is writing (this window saves nothing).
"""

from __future__ import annotations

from collections.abc import Callable

from qtpy import QtCore, QtGui

from rcon_core.app.canvas_bar import CanvasBar
from rcon_core.app.canvas_controller import CanvasController
from rcon_core.app.config import AppConfig
from rcon_core.app.connection_bar import ConnectionBar
from rcon_core.app.notice_bar import NoticeBar
from rcon_core.app.operator_lock import OperatorLock, lock_tooltip
from rcon_core.app.theme import colour as theme_colour
from rcon_core.canvas.robots import Robot

#: the side panel's robot and its URL ("" when none yet): what the robot view-only action acts on
SideRobot = Callable[[], tuple[Robot | None, str]]

#: canvas menu actions that change the layout: the PIN first while the lock is engaged
GATED_ACTIONS = {
    "new": "add a canvas",
    "rename": "rename the canvas",
    "duplicate": "duplicate the canvas",
    "delete": "delete the canvas",
    "import": "import a canvas",
    "reset_demo": "reset the demo layout",
}


class LockControls(QtCore.QObject):
    """The lock's and the view-only controls in the canvas menu, the Edit segment's padlock, the URL
    field's state while locked, and the app config's problems (see the module docstring)."""

    #: the side panel's robot was marked or unmarked view-only in the app config (the window restarts
    #: the widgets and the preview on ports that say so)
    robot_view_only_changed = QtCore.Signal()

    def __init__(self, lock: OperatorLock, bar: CanvasBar, connection: ConnectionBar,
                 controller: CanvasController, config: AppConfig, notice: NoticeBar,
                 side_robot: SideRobot) -> None:
        super().__init__(bar)
        self.lock, self.bar, self.connection, self.controller = lock, bar, connection, controller
        self.config, self.notice, self.side_robot = config, notice, side_robot
        actions = bar.canvas_actions
        menu = bar.menu
        before = actions["export"]  # after the editing actions, before export/import

        def add(name: str, text: str, slot: Callable[..., object], checkable: bool = False) -> QtGui.QAction:
            action = QtGui.QAction(text, menu)
            action.setObjectName(f"canvas_{name}" if name != "robot_view_only" else name)
            action.setCheckable(checkable)
            action.triggered.connect(slot)
            menu.insertAction(before, action)
            actions[name] = action
            return action

        engage = add("lock", "Lock Operate mode…", lambda _c=False: self.toggle_lock())
        menu.insertSeparator(engage)
        add("view_only", "View only: this canvas never sends", self.set_canvas_view_only, checkable=True)
        # names the robot (show_robot_action)
        add("robot_view_only", "View only: nothing is sent to this robot", self.set_robot_view_only,
            checkable=True)
        add("pin", "Operator PIN…", lambda _c=False: lock.guard("change the operator PIN", lock.set_pin_dialog))
        menu.insertSeparator(before)

        # ---- the app config's problems
        config.add_problem_listener(lambda text: notice.show_notice(f"⚠ {text}"))
        controller.save_failed.connect(lambda _text: self.keep_config_problem())
        lock.problem.connect(lambda text: notice.show_notice(text))
        if config.read_only_reason:
            notice.show_notice(
                f"⚠ This window is read-only: {config.read_only_reason}. Nothing changed here is saved (the "
                "layout, the PIN, view-only marks, the URL history). To keep separate settings, start RCON with "
                "RCON_CONFIG_DIR set to another folder.")

        lock.changed.connect(lambda _engaged: self.show())
        menu.aboutToShow.connect(self.show)
        controller.current_changed.connect(lambda _i: self.show())
        controller.lock_changed.connect(lambda _locked: self.show())
        self.show()

    def show(self) -> None:
        """Bring every control in line with the lock, the canvas and the robot URL."""
        lock = self.lock
        engaged = lock.engaged
        canvas = self.controller.canvas
        if engaged and not canvas.locked:
            self.controller.set_locked(True)  # every canvas shown while locked is in Operate mode
        edit = self.bar.edit_button
        edit.setIcon(padlock_icon() if engaged else QtGui.QIcon())
        edit.setIconSize(QtCore.QSize(20, 20))
        edit.setText("Edit" if engaged else "✎ Edit")
        edit.setAccessibleName("Edit (locked: needs the operator PIN)" if engaged else "Edit")
        if engaged:
            edit.setToolTip(lock_tooltip(lock))
        actions = self.bar.canvas_actions
        actions["lock"].setText("Unlock Operate mode…" if engaged else "Lock Operate mode…")
        actions["lock"].setToolTip(lock_tooltip(lock))
        self.connection.url.setEnabled(not engaged)
        self.connection.url.setToolTip("Locked: tap Connect/Disconnect and enter the PIN to change the robot"
                                       if engaged else "")
        actions["view_only"].setChecked(self.controller.canvas.view_only)
        self.show_robot_action()

    def keep_config_problem(self) -> None:
        """A layout save failed (its notice was just shown, e.g. on a full disk): an app-settings change that
        could not be saved either (the PIN) stays in sight under it instead of being replaced."""
        problem = self.config.problem_text
        text = self.notice.label.text()
        if problem and not self.controller.store.read_only and problem not in text:
            self.notice.show_notice(f"{text}\n⚠ {problem}")

    def toggle_lock(self) -> None:
        if self.lock.engaged:
            self.lock.guard("unlock", lambda: None)
        else:
            self.lock.engage_dialog()

    def set_canvas_view_only(self, on: bool) -> None:
        canvas = self.controller.canvas
        doc = self.controller.doc
        if on:
            doc.set_view_only(canvas.id, True)
        else:
            self.bar.canvas_actions["view_only"].setChecked(True)  # until the PIN (if asked) is right
            self.lock.guard("let this canvas send commands", lambda: doc.set_view_only(canvas.id, False))
        self.show()

    # ---- the side panel's robot's view-only mark (in the app config; view_only.py)
    def show_robot_action(self) -> None:
        """The robot action's words (naming the robot), tick and state."""
        action = self.bar.canvas_actions["robot_view_only"]
        robot, url = self.side_robot()
        name = robot.label if robot is not None else "this robot"
        action.setText(f"View only: nothing is sent to “{name}”")
        action.setEnabled(bool(url))
        action.setToolTip(f"{name} at {url}: marked in this app's settings, for every canvas" if url
                          else f"{name} has no URL yet: connect it first")
        action.setChecked(bool(url) and self.config.is_view_only(url))

    def set_robot_view_only(self, on: bool) -> None:
        """The menu action: mark (or, with the PIN while locked, unmark) the side panel's robot."""
        robot, url = self.side_robot()
        if robot is None or not url:
            self.show_robot_action()
            return

        def apply(value: bool) -> None:
            self.config.set_view_only(url, value, save=False)
            self.robot_view_only_changed.emit()  # the link first: from here on nothing reaches the robot
            self.config.save_view_only(url)  # a failure is said by the config's listeners
            self.show_robot_action()

        if on:
            apply(True)
        else:
            self.bar.canvas_actions["robot_view_only"].setChecked(True)  # until the PIN (if asked) is right
            self.lock.guard(f"let “{robot.label}” be commanded", lambda: apply(False))


def padlock_icon() -> QtGui.QIcon:
    """A closed padlock drawn in the theme's text colour (no font needed: the theme's font has no emoji)."""
    pix = QtGui.QPixmap(56, 56)
    pix.fill(QtCore.Qt.GlobalColor.transparent)
    p = QtGui.QPainter(pix)
    p.setRenderHint(QtGui.QPainter.RenderHint.Antialiasing)
    colour = theme_colour("TEXT")
    p.setPen(QtGui.QPen(colour, 6))
    shackle = QtCore.QRectF(16, 6, 24, 28)
    p.drawArc(shackle, 0, 180 * 16)
    p.drawLine(shackle.bottomLeft() - QtCore.QPointF(0, 14), shackle.bottomLeft() - QtCore.QPointF(0, 4))
    p.drawLine(shackle.bottomRight() - QtCore.QPointF(0, 14), shackle.bottomRight() - QtCore.QPointF(0, 4))
    p.setPen(QtCore.Qt.PenStyle.NoPen)
    p.setBrush(colour)
    p.drawRoundedRect(QtCore.QRectF(8, 26, 40, 28), 4, 4)
    p.end()
    return QtGui.QIcon(pix)
