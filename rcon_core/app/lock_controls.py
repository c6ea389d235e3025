"""The window's operator-lock and view-only controls (kept out of ``main_window.py``).

:func:`install` adds to a :class:`~rcon_core.app.main_window.MainWindow`:

- *Lock Operate mode…* in the canvas menu (``canvas_lock``): engages the operator lock (asking for a new
  PIN first when none is set). While engaged the Edit segment shows a padlock and a tap on it asks for
  the PIN (no extra button: the bars have no room to spare on a 1024 px tablet);
- the PIN gate on the canvas menu's editing actions, on the robot's Connect/Disconnect button (the
  URL field is disabled while locked), on the connection bar's Security dialog (the robot's TLS files and
  rosauth secret) and on the Parameters panel's Set; the window itself gates leaving Operate mode, adding
  widgets (and so calling a service from the side panel) and quitting, the robots menu gates the Robots
  dialog (see :class:`~rcon_core.app.operator_lock.OperatorLock`);
- *View only* in the canvas menu, for the side panel's robot, named in the action (``robot_view_only``:
  that robot's URL never gets anything sent, remembered in the app config, enforced on its link; see
  :mod:`rcon_core.app.view_only`) and for the canvas (``canvas_view_only``: saved in the layout).
  Turning either on is always allowed; turning it off is an edit (the PIN when locked);
- the app config's problems on the notice bar: a change that could not be saved (a full or read-only
  disk: it holds for this run), and a config folder another RCON is writing (this window saves nothing).
"""

from __future__ import annotations

from typing import Any

from qtpy import QtCore, QtGui

from rcon_core.app.operator_lock import lock_tooltip
from rcon_core.app.theme import colour as theme_colour
from rcon_core.app.view_only import show_action
from rcon_core.app.view_only import toggle as toggle_robot_view_only

#: canvas menu actions that change the layout: the PIN first while the lock is engaged
GATED_ACTIONS = {
    "new": "add a canvas",
    "rename": "rename the canvas",
    "duplicate": "duplicate the canvas",
    "delete": "delete the canvas",
    "import": "import a canvas",
    "reset_demo": "reset the demo layout",
}


def install(window: Any) -> None:
    lock = window.operator_lock
    # ---- the canvas menu: gated editing actions, the lock, view-only, the PIN
    for name, what in GATED_ACTIONS.items():
        action = window.canvas_actions.get(name)
        if action is None:
            continue
        slot = {"new": window.new_canvas, "rename": window.rename_canvas_dialog,
                "duplicate": window.duplicate_canvas, "delete": window.delete_canvas,
                "import": window.canvas_files.import_dialog, "reset_demo": window.reset_demo_dialog}[name]
        action.triggered.disconnect()
        action.triggered.connect(lambda _=False, slot=slot, what=what: lock.guard(what, slot))
    menu = window.menu_button.menu()
    before = window.canvas_actions["export"]  # after the editing actions, before export/import

    def add(text: str) -> QtGui.QAction:
        action = QtGui.QAction(text, menu)
        menu.insertAction(before, action)
        return action

    engage = add("Lock Operate mode…")
    engage.setObjectName("canvas_lock")
    engage.triggered.connect(lambda: toggle_lock(window))
    window.canvas_actions["lock"] = engage
    menu.insertSeparator(engage)
    view_only = add("View only: this canvas never sends")
    view_only.setObjectName("canvas_view_only")
    view_only.setCheckable(True)
    view_only.triggered.connect(lambda checked: set_canvas_view_only(window, checked))
    window.canvas_actions["view_only"] = view_only
    robot_view_only = add("View only: nothing is sent to this robot")  # names the robot (show())
    robot_view_only.setObjectName("robot_view_only")
    robot_view_only.setCheckable(True)
    robot_view_only.triggered.connect(lambda checked: toggle_robot_view_only(window, checked))
    window.canvas_actions["robot_view_only"] = robot_view_only
    pin = add("Operator PIN…")
    pin.setObjectName("canvas_pin")
    pin.triggered.connect(lambda: lock.guard("change the operator PIN", lock.set_pin_dialog))
    window.canvas_actions["pin"] = pin
    menu.insertSeparator(before)

    # ---- the connection bar: the robot and its connection settings gated; the Parameters panel's Set
    bar = window.connection
    bar.connect_button.clicked.disconnect()
    bar.connect_button.clicked.connect(lambda: lock.guard("change the robot", bar.toggle))
    open_settings = bar.open_settings  # the Security button, and a Connect that needs a secret first

    def gated_settings(ask_secret: bool = False) -> None:
        lock.guard("change the robot's connection settings", lambda: open_settings(ask_secret))

    bar.open_settings = gated_settings
    window.params_panel.gate = lock.guard

    # ---- the app config's problems
    config = window.config
    config.add_problem_listener(lambda text: window.notice.show_notice(f"⚠ {text}"))
    window.controller.save_failed.connect(lambda _text: keep_config_problem(window))
    lock.problem.connect(lambda text: window.notice.show_notice(text))
    if config.read_only_reason:
        window.notice.show_notice(
            f"⚠ This window is read-only: {config.read_only_reason}. Nothing changed here is saved (the "
            "layout, the PIN, view-only marks, the URL history). To keep separate settings, start RCON with "
            "RCON_CONFIG_DIR set to another folder.")

    lock.changed.connect(lambda _engaged: show(window))
    menu.aboutToShow.connect(lambda: show(window))
    window.fleet_ui.side_robot_changed.connect(lambda _robot: show(window))
    window.controller.current_changed.connect(lambda _i: show(window))
    window.controller.lock_changed.connect(lambda _locked: show(window))
    show(window)


def show(window: Any) -> None:
    """Bring every control in line with the lock, the canvas and the robot URL."""
    lock = window.operator_lock
    engaged = lock.engaged
    if engaged and not window.controller.canvas.locked:
        window.controller.set_locked(True)  # every canvas shown while locked is in Operate mode
    edit = window.edit_button
    edit.setIcon(padlock_icon() if engaged else QtGui.QIcon())
    edit.setIconSize(QtCore.QSize(20, 20))
    edit.setText("Edit" if engaged else "✎ Edit")
    edit.setAccessibleName("Edit (locked: needs the operator PIN)" if engaged else "Edit")
    if engaged:
        edit.setToolTip(lock_tooltip(lock))
    window.canvas_actions["lock"].setText("Unlock Operate mode…" if engaged else "Lock Operate mode…")
    window.canvas_actions["lock"].setToolTip(lock_tooltip(lock))
    window.connection.url.setEnabled(not engaged)
    window.connection.url.setToolTip("Locked: tap Connect/Disconnect and enter the PIN to change the robot"
                                     if engaged else "")
    window.canvas_actions["view_only"].setChecked(window.controller.canvas.view_only)
    show_action(window)


def keep_config_problem(window: Any) -> None:
    """A layout save failed (its notice was just shown, e.g. on a full disk): an app-settings change that
    could not be saved either (the PIN) stays in sight under it instead of being replaced."""
    problem = window.config.problem_text
    text = window.notice.label.text()
    if problem and not window.store.read_only and problem not in text:
        window.notice.show_notice(f"{text}\n⚠ {problem}")


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


def toggle_lock(window: Any) -> None:
    lock = window.operator_lock
    if lock.engaged:
        lock.guard("unlock", lambda: None)
    else:
        lock.engage_dialog()


def set_canvas_view_only(window: Any, on: bool) -> None:
    canvas = window.controller.canvas
    if on:
        window.doc.set_view_only(canvas.id, True)
    else:
        window.canvas_actions["view_only"].setChecked(True)  # until the PIN (if asked) is right
        window.operator_lock.guard("let this canvas send commands",
                                   lambda: window.doc.set_view_only(canvas.id, False))
    show(window)
