"""The main window: the composition root that builds the app's parts and wires them together.

The parts live in their own modules: the connection bar (``connection_bar.py``), the side panel's lists
(``catalog_panel.py``, ``params_panel.py``, ``palette_panel.py``) and whether it shows (``side_panel.py``),
the canvas bar (``canvas_bar.py``), the canvases (``canvas_controller.py``), the add panel
(``add_panel.py``) and adding from it (``adding.py``), the Configure dialog (``configure_dialog.py``),
canvas export/import (``canvas_files.py``) and the canvas menu's questions (``canvas_dialogs.py``,
``confirm.py``), the layout file's messages (``layout_file.py``), the robots (``fleet_ui.py``, with their
recordings: ``robot_recordings.py``), the operator lock (``operator_lock.py``, ``lock_controls.py``), the
safety envelope (``envelope_dialog.py``), the flight recorder (``record_control.py``) and the display
settings (``display_settings.py``). Problems go to the notice bar (``notice_bar.py``) floating over the
canvas column.

Each part is given the few objects it works with, typed, never the window, and talks back through Qt
signals that the window connects here (``_wire``). The operator lock is composed in: its ``guard`` is
given to the canvas bar (with the actions it gates), the connection bar, the Parameters panel, the robots'
and the envelope's menu entries when they are built.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from qtpy import QtCore, QtGui, QtWidgets

from rcon_core.app import theme
from rcon_core.app.accessibility import install as install_accessibility
from rcon_core.app.accessibility import name_side_panel
from rcon_core.app.add_panel import AddPanel
from rcon_core.app.adding import Adding
from rcon_core.app.canvas_bar import COMPACT_BELOW, CanvasBar
from rcon_core.app.canvas_controller import CanvasController
from rcon_core.app.canvas_dialogs import delete_current, rename_current
from rcon_core.app.canvas_files import CanvasFiles
from rcon_core.app.catalog_panel import CatalogList
from rcon_core.app.children_editor import link_learner
from rcon_core.app.config import AppConfig
from rcon_core.app.configure_dialog import WidgetConfigurer
from rcon_core.app.confirm import ask
from rcon_core.app.connection_bar import ConnectionBar
from rcon_core.app.display_settings import DisplayMenu
from rcon_core.app.draft import Candidate, Target, rank_widgets, targets_for
from rcon_core.app.envelope_dialog import EnvelopeControl
from rcon_core.app.fleet_ui import FleetUi
from rcon_core.app.focus import has_focus_inside
from rcon_core.app.frame_clock import FrameClock, Waker
from rcon_core.app.layout_file import LayoutFile
from rcon_core.app.link import RobotConnection
from rcon_core.app.live import LiveCanvas
from rcon_core.app.lock_controls import GATED_ACTIONS, LockControls
from rcon_core.app.notice_bar import NoticeBar
from rcon_core.app.operator_lock import OperatorLock
from rcon_core.app.palette_panel import PalettePanel
from rcon_core.app.params_panel import ParamsPanel
from rcon_core.app.preview import PreviewHost
from rcon_core.app.record_control import install_record_control, small_screen
from rcon_core.app.replay_bar import ReplayBar
from rcon_core.app.side_panel import PANEL_MIN, SIDE_MIN, SidePanelPolicy
from rcon_core.app.template_menu import add_template_menu
from rcon_core.app.widget_host import RateMeter, WidgetHost
from rcon_core.bridge import ConnectionState
from rcon_core.canvas import Document, Workspace
from rcon_core.canvas.document import Change, ChangeKind
from rcon_core.gcpolicy import CollectorPolicy
from rcon_core.plugins import Binding, PluginManager, Role, WidgetSpec
from rcon_core.plugins.children import ChildContext

#: seconds between two passes over every widget for what changes without a message (ageing to STALE, link
#: state); new values do not wait for it (the waker)
FULL_PASS_EVERY = 0.1
#: seconds after a robot connects until the collector freezes what its catalogue brought (``gcpolicy.py``)
SETTLE_AFTER_CONNECT = 5.0
ACTIONS_EMPTY = "No actions: a ROS 2 robot's action servers are listed here once connected."


class MainWindow(QtWidgets.QMainWindow):
    """RCON's window. ``plugins`` and ``config`` are injected so tests use their own."""

    # made in __init__ after the lambdas that reach them are wired (declared here so they have a type there)
    fleet_ui: FleetUi
    controller: CanvasController
    canvas_files: CanvasFiles

    def __init__(
        self,
        config: AppConfig,
        plugins: PluginManager,
        *,
        layout_path: Path | None = None,
        types: Any = None,
        link: RobotConnection | None = None,
        demo: Callable[[], Workspace] | None = None,
        collector: CollectorPolicy | None = None,
    ) -> None:
        super().__init__()
        app = QtWidgets.QApplication.instance()
        if isinstance(app, QtWidgets.QApplication):  # the touch-sized theme the operator chose (display_settings)
            theme.apply(app, config.theme, config.text_size)
        self.setAttribute(QtCore.Qt.WidgetAttribute.WA_AcceptTouchEvents)
        self.setWindowTitle("RCON")
        self.config, self.plugins = config, plugins
        self._shut = False  #: shutdown() ran (closing is idempotent)
        self._close_now = False  #: close without asking for the PIN (after it, or on a signal)
        #: the operator lock (PIN) over Operate mode, composed into every part that changes the robot or
        #: the layout (their ``guard``); its menu controls: lock_controls
        self.operator_lock = OperatorLock(config, self)
        #: builds the demo layout (``rcon --demo``): used when there is none yet, or it cannot be read
        self.demo = demo
        self.types = types if types is not None else plugins.type_registry()  # with plugins' types
        self.link = link or RobotConnection()
        self.clock = FrameClock(self)
        self._last_full_pass = 0.0
        #: when the garbage collector may pause the process (``rcon_core/gcpolicy.py``); the app's entry
        #: point passes one, embedders and tests may leave it out (then Python's defaults apply)
        self.collector = collector
        self._remove_gc_listener: Callable[[], object] | None = None
        #: wakes the GUI as soon as the bridge thread has something (a value, new models)
        self.waker = Waker(self._pump, self)
        self._due_timer = QtCore.QTimer(self)
        self._due_timer.setSingleShot(True)
        self._due_timer.setTimerType(QtCore.Qt.TimerType.PreciseTimer)
        self._due_timer.timeout.connect(lambda: self._pump(set()))
        self.host = WidgetHost(plugins)
        self.live = LiveCanvas(plugins, self.link.thread, types=self.types, notify=self.waker.poke)
        self.preview_live = LiveCanvas(plugins, self.link.thread, types=self.types, notify=self.waker.poke)
        self.preview = PreviewHost(self.host, self.preview_live, lambda: self.fleet_ui.side_fleet())
        self.focus_losses = 0
        self.rates = RateMeter()
        self._last_rate_sample = 0.0
        self.catalog: dict[str, list[tuple[str, str]]] = {"topics": [], "services": [], "actions": []}
        self.first_paint_at: float | None = None
        self._build_widgets()
        self._open_workspace(layout_path)
        self._build_parts()
        self._wire()
        self.resize(self.initial_size())

    def _build_widgets(self) -> None:
        """The connection bar, the side panel, the canvas bar, the add panel and the notice bar, laid out."""
        guard = self.operator_lock.guard
        self.connection = ConnectionBar(self.link, self.config, guard=guard)
        self.topics = CatalogList("topics", with_rate=True)
        self.services = CatalogList("services", with_rate=False)
        self.actions_list = CatalogList("actions", with_rate=False, empty=ACTIONS_EMPTY)
        self.palette_panel = PalettePanel()
        self.palette_panel.set_specs(self.plugins.widgets())
        self.params_panel = ParamsPanel(self.link, self.confirm, gate=guard)
        self.side = QtWidgets.QTabWidget()
        self.side.setObjectName("sidePanel")
        for tab, name in ((self.topics, "Topics"), (self.services, "Services"), (self.actions_list, "Actions"),
                          (self.params_panel, "Params"), (self.palette_panel, "Widgets")):
            self.side.addTab(tab, name)
        self.side.setTabPosition(QtWidgets.QTabWidget.TabPosition.West)  # five tabs: all in sight
        self.side.setMinimumWidth(SIDE_MIN)
        self.canvas_bar = bar = CanvasBar({
            "new": ("New canvas", self.new_canvas),
            "rename": ("Rename…", self.rename_canvas_dialog),
            "duplicate": ("Duplicate", self.duplicate_canvas),
            "delete": ("Delete…", self.delete_canvas),
            "export": ("Export canvas…", lambda: self.canvas_files.export_dialog()),
            "import": ("Import canvas…", lambda: self.canvas_files.import_dialog()),
            **({"reset_demo": ("Reset demo layout…", self.reset_demo_dialog)} if self.demo is not None else {}),
        }, self.undo, self.redo, guard=guard, gated=GATED_ACTIONS)
        # its parts, by the names the tests use
        self.tabs, self.menu_button, self.edit_button, self.lock_button = (
            bar.tabs, bar.menu_button, bar.edit_button, bar.lock_button)
        self.canvas_actions, self.canvas_buttons = bar.canvas_actions, bar.canvas_buttons
        self.tabs.currentChanged.connect(self._tab_changed)
        bar.mode_tapped.connect(self._mode_toggled)
        self.template_menu = add_template_menu(self.plugins.canvas_templates(),
                                               lambda path: self.canvas_files.import_from(path),
                                               bar.menu, before=self.canvas_actions["rename"])
        self.stack = QtWidgets.QStackedWidget()
        self.add_panel = AddPanel(self.rank_widgets, self.targets_for, self.preview.build, self.preview.release,
                                  child_context=self.child_context)
        self.add_panel.setMinimumWidth(PANEL_MIN)
        self.add_panel.hide()
        self.center = center = QtWidgets.QWidget()
        ccol = QtWidgets.QVBoxLayout(center)
        ccol.setContentsMargins(0, 0, 0, 0)
        ccol.setSpacing(0)
        ccol.addWidget(self.canvas_bar)
        ccol.addWidget(self.stack, 1)
        self.split = split = QtWidgets.QSplitter()
        split.setHandleWidth(12)
        for part in (self.side, center, self.add_panel):
            split.addWidget(part)
        split.setStretchFactor(1, 1)
        split.setSizes([SIDE_MIN, 900, 380])
        split.setChildrenCollapsible(False)
        # shows or hides the side panel (topics, services, widgets): room for the canvas on a small screen;
        # first on the connection bar, above the side panel
        self.side_toggle = QtWidgets.QPushButton()
        self.side_toggle.setObjectName("sideToggle")
        self.side_toggle.setProperty("square", True)
        self.side_policy = SidePanelPolicy(self, self.side, self.side_toggle, split, center, self.add_panel)
        center.installEventFilter(self)  # the canvas bar gets compact when the centre is narrow
        self.add_panel.installEventFilter(self)  # the add panel gets room when it opens
        conn_row = self.connection.layout()
        if isinstance(conn_row, QtWidgets.QBoxLayout):
            conn_row.insertWidget(0, self.side_toggle)
        root = QtWidgets.QWidget()
        self.rows = QtWidgets.QVBoxLayout(root)  # the connection bar, replay bars, robot chips, the rest
        self.rows.setContentsMargins(0, 0, 0, 0)
        self.rows.setSpacing(0)
        self.rows.addWidget(self.connection)
        #: a layout file that could not be read: says so, that it will not be overwritten, and the way out
        self.notice = NoticeBar("fileBanner")
        self.banner = self.notice.label
        self.rows.addWidget(split, 1)
        self.setCentralWidget(root)
        # over the bottom edge of the canvas column: a notice never pushes a control away, and it leaves the
        # bars, the side panel and the add panel (its Place button) uncovered
        self.notice.float_over(center)

    def _open_workspace(self, layout_path: Path | None) -> None:
        """The layout file, read (or the demo's first start), into the document."""
        self.layout_path = Path(layout_path) if layout_path is not None else self.config.workspace_path
        self.layout_file = LayoutFile(self.layout_path, self.notice, self.demo,
                                      lambda: self.controller.saver.flush())
        self.store = self.layout_file.store
        if not self.config.claim():  # one writer per config folder (config_lock.py): this window saves nothing
            self.store.read_only_reason = self.config.read_only_reason
        self._fresh = self.demo is not None and not self.layout_path.exists()  # the demo's first start
        self.doc = Document(self.demo() if self._fresh and self.demo is not None else self.layout_file.load())

    def _build_parts(self) -> None:
        """The robots, the canvases and the parts that add to the canvas menu, in the menu's order."""
        guard = self.operator_lock.guard
        # one link per robot; hears a change of robots before the controller
        self.fleet_ui = FleetUi(self.doc, self.link, self.connection, self.host, self.live,
                                (self.topics, self.services, self.actions_list), self.canvas_bar, self.notice,
                                self.config, guard, self.confirm, self)
        self.rows.insertWidget(1, self.fleet_ui.chips)  # right under the connection bar
        self.controller = CanvasController(self.doc, self.store, self.host, self.live, self.stack)
        self.controller.client = self.fleet_ui.fleet()
        self.controller.save_failed.connect(self.layout_file.save_failed)
        self.side_policy.hint_changed.connect(self.controller.set_hint)
        # Canvas ▾ → Safety envelope… (the PIN first while locked); the check of a widget just placed
        self.envelope = EnvelopeControl(self.doc, self.notice, guard, self.canvas_bar, self)
        self.adding = Adding(self.add_panel, self.controller, self.operator_lock, self.notice, self.side_policy,
                             self.fleet_ui.bind, self.envelope.check_placed)
        self.canvas_files = CanvasFiles(self, self.controller, self.notice, self.plugins, self.adding.in_edit_mode,
                                        self._dialog_closed)
        self.configurer = WidgetConfigurer(self, self.doc, self.plugins, self.types, self.child_context,
                                           self._dialog_closed)
        self.controller.on_configure = self.configurer.open
        self.lock_controls = LockControls(self.operator_lock, self.canvas_bar, self.connection, self.controller,
                                          self.config, self.notice, self.fleet_ui.side_target)
        recordings = self.fleet_ui.recordings
        #: the Record control on the connection bar (the flight recorder: record_control.py)
        self.record_control = install_record_control(
            self.link.thread, Path(self.config.dir) / "recordings", self.doc, self.fleet_ui.fleet, self.notice,
            self.connection, self.canvas_bar, self.clock, lambda: recordings.open_dialog(self),
            compact=small_screen(self))
        self.display = DisplayMenu(self.config, self.notice, self.canvas_bar, self)  # theme and text size
        install_accessibility()  # the roles of the widgets that paint themselves
        name_side_panel(self.side)

    def _wire(self) -> None:
        """The parts' signals, the shortcuts and the frame clock."""
        controller, fleet, recordings = self.controller, self.fleet_ui, self.fleet_ui.recordings
        controller.canvases_changed.connect(self._sync_tabs)
        controller.current_changed.connect(self._sync_tabs)
        controller.lock_changed.connect(self._show_lock)
        fleet.fleet_changed.connect(lambda: setattr(controller, "client", fleet.fleet()))
        fleet.rerun.connect(controller.run_current)
        fleet.preview_stale.connect(self.preview.restart)
        fleet.side_link_changed.connect(self.params_panel.follow)
        fleet.side_client_changed.connect(self.params_panel.client_changed)
        fleet.side_robot_changed.connect(self._side_robot_changed)
        fleet.link_up.connect(lambda _robot: self.link_came_up())
        recordings.bar_shown.connect(self._show_replay_bar)
        recordings.bar_gone.connect(lambda bar: self.clock.remove(bar.poll))
        recordings.connect_first.connect(lambda url: self.connect_to(url, remember=False))
        recordings.marks_changed.connect(self.apply_view_only)
        recordings.seeked.connect(controller.run_current)
        self.lock_controls.robot_view_only_changed.connect(self.apply_view_only)
        self._sync_tabs()
        self._show_lock(controller.canvas.locked)
        controller.run_current()  # offline (LINK DOWN) until a robot is connected
        if self._fresh or self.layout_file.demo_rebuilt:
            controller.saver.flush()  # the demo layout is on disk from its first start on
        add, panel = self.adding.start, self.add_panel
        self.topics.picked.connect(lambda n, t: add(lambda: panel.start_from_topic(n, t)))
        self.services.picked.connect(lambda n, t: add(lambda: panel.start_from_service(n, t)))
        self.actions_list.picked.connect(lambda n, t: add(lambda: panel.start_from_action(n, t)))
        self.palette_panel.picked.connect(lambda kind: add(lambda: panel.start_from_widget(self.plugins.widget(kind))))
        self.connection.state_changed.connect(self._link_state)
        QtGui.QShortcut(QtGui.QKeySequence.StandardKey.Undo, self, self.undo)
        QtGui.QShortcut(QtGui.QKeySequence.StandardKey.Redo, self, self.redo)
        self.quit_action = QtGui.QAction("Quit", self)
        self.quit_action.setObjectName("quit")
        quit_keys = [QtGui.QKeySequence(QtGui.QKeySequence.StandardKey.Quit), QtGui.QKeySequence("Ctrl+Q")]
        self.quit_action.setShortcuts([k for i, k in enumerate(quit_keys) if not k.isEmpty() and k not in quit_keys[:i]])
        self.quit_action.setShortcutContext(QtCore.Qt.ShortcutContext.ApplicationShortcut)
        self.quit_action.triggered.connect(self.close)
        self.addAction(self.quit_action)
        for poll in (self.connection.poll, fleet.poll, self._poll_catalog, self._ageing_pass):
            self.clock.add(poll)
        if self.collector is not None:
            self.collector.soon(1.0, full=True)  # once the window is built and shown
            self.clock.add(self.collector.poll)
            self._remove_gc_listener = self.doc.add_listener(self._settle_after)
        self.clock.start()
        app = QtWidgets.QApplication.instance()
        if isinstance(app, QtGui.QGuiApplication):
            app.applicationStateChanged.connect(self._app_state_changed)

    @property
    def replay(self) -> ReplayBar | None:
        """The timeline of a recording played as the first robot (replay_bar.py), or None."""
        return self.fleet_ui.recordings.replay

    def _show_replay_bar(self, bar: ReplayBar) -> None:
        """A recording's timeline: under the connection bar, on the frame clock."""
        self.rows.insertWidget(self.rows.indexOf(self.connection) + 1, bar)
        self.clock.add(bar.poll)

    def _side_robot_changed(self, _robot: str) -> None:
        self.rates = RateMeter()  # the topic rates of the robot now listed start afresh
        self.lock_controls.show()

    # ------------------------------------------------------------------------------------ workspace
    def open_workspace(self, workspace: Workspace) -> None:
        """Replace the workspace; saved like any change."""
        self.doc.replace_workspace(workspace)

    def reset_demo_dialog(self) -> QtWidgets.QMessageBox | None:
        """Ask, then replace the layout with a fresh demo layout (``rcon --demo`` only)."""
        if self.demo is None:
            return None
        return self.confirm("Reset the demo layout?",
                            "Every canvas is replaced by the demo's own layout; your changes to it are lost.",
                            "Reset", self.reset_demo_layout)

    def reset_demo_layout(self) -> None:
        if self.demo is not None:
            self.open_workspace(self.demo())

    def confirm(self, question: str, detail: str, yes: str,
                then: Callable[[], object]) -> QtWidgets.QMessageBox:
        """A window-modal question with two large buttons (``yes`` and Cancel; ``confirm.py``); ``then``
        runs on yes. Returns at once (the dialog is open), so the event loop and the robot link keep running."""
        self.confirm_dialog = ask(self, question, detail, yes, then, self._confirm_closed)
        return self.confirm_dialog

    def _sync_tabs(self, *_: Any) -> None:
        canvases = self.controller.workspace.canvases
        self.canvas_bar.show_canvases([c.name for c in canvases], self.controller.index,
                                      self.controller.canvas.locked)

    def _tab_changed(self, index: int) -> None:
        self.controller.switch(index)

    def switch_canvas(self, index: int) -> None:
        self.tabs.setCurrentIndex(index)

    def new_canvas(self) -> None:
        self.controller.add_canvas("Canvas")

    def rename_canvas_dialog(self) -> None:
        rename_current(self, self.controller, self.notice)

    def duplicate_canvas(self) -> None:
        self.controller.duplicate_canvas(self.controller.index)

    def delete_canvas(self) -> None:
        """Delete the current canvas; one with widgets is deleted only after the operator confirms."""
        delete_current(self.controller, self.notice, self.confirm)

    def undo(self) -> None:
        self.controller.undo()

    def redo(self) -> None:
        self.controller.redo()

    def _mode_toggled(self, locked: bool, checked: bool) -> None:
        """A tap on a mode segment: the tapped mode becomes current (tapping the current one keeps it)."""
        if not checked:
            self._show_mode(self.controller.canvas.locked)  # tapping the active segment: nothing changes
            return
        if not locked and self.operator_lock.engaged:
            self._show_mode(True)  # still Operate: the PIN first
            self.operator_lock.guard("leave Operate mode", lambda: self._mode_toggled(False, True))
            return
        if locked != self.controller.canvas.locked:
            self.controller.set_locked(locked)
        self._show_lock(locked)

    # -------------------------------------------------------------------------------- layout
    def eventFilter(self, obj: QtCore.QObject, event: QtCore.QEvent) -> bool:
        if obj is self.center and event.type() == QtCore.QEvent.Type.Resize:
            self._fit_mode_bar()
        elif obj is self.add_panel and event.type() == QtCore.QEvent.Type.Show:
            self._fit_mode_bar()
            self.side_policy.update()  # at once, before the layout would widen the window for the panel
            QtCore.QTimer.singleShot(0, self.side_policy.make_room_for_add_panel)
        elif obj is self.add_panel and event.type() == QtCore.QEvent.Type.Hide:
            self._fit_mode_bar()
            self.side_policy.update()
        return super().eventFilter(obj, event)

    def initial_size(self) -> QtCore.QSize:
        """1280x800, or the screen's free area when it is smaller (a 1024x600 tablet): never larger."""
        screen = self.screen() or QtGui.QGuiApplication.primaryScreen()
        size = QtCore.QSize(1280, 800)
        if screen is not None:
            size = size.boundedTo(screen.availableGeometry().size())
        return size

    def resizeEvent(self, event: QtGui.QResizeEvent) -> None:
        super().resizeEvent(event)
        self.side_policy.update()

    def _fit_mode_bar(self) -> None:
        """Short labels on the canvas bar when the centre is narrow (e.g. the add panel is open)."""
        room = self.width() - self.side.width() - (self.add_panel.width() if self.add_panel.isVisible() else 0)
        self.canvas_bar.set_compact(self.add_panel.isVisible() or room < COMPACT_BELOW)

    def _show_mode(self, locked: bool) -> None:
        self.canvas_bar.show_mode(locked, self.operator_lock.engaged)

    def _show_lock(self, locked: bool) -> None:
        self.canvas_bar.show_lock(locked, len(self.controller.workspace.canvases), self.operator_lock.engaged)
        self.side_policy.set_locked(locked)
        if locked:
            self.add_panel.cancel()
        elif not self._shut:  # Edit mode: the canvas is no longer operated (a shield covers each view), so a
            self.live.focus_lost()  # pad held through the switch stops at once, not when its finger lifts

    # -------------------------------------------------------------------------------------- adding
    def rank_widgets(self, type_name: str, role: Role) -> list[Candidate]:
        return rank_widgets(type_name, role, self.types, self.plugins)

    def targets_for(self, spec: WidgetSpec, role: Role) -> list[Target]:
        return targets_for(spec, role, self.catalog.get(f"{role.noun}s", []), self.types, self.plugins)

    def place_draft(self) -> None:
        self.adding.place()

    def child_context(self, binding: Callable[[], Binding | None]) -> ChildContext:
        """What a settings form's children editor needs: types, widgets, the parent's binding, and a way to
        learn a type from the robot."""
        return ChildContext(self.types, self.plugins, binding, link_learner(self.link))

    def _confirm_closed(self) -> None:
        """After a confirm dialog (either answer) the keyboard is the window's again: Ctrl+Z, Ctrl+Q work."""
        self.activateWindow()
        if not has_focus_inside(self):
            self.adding.focus_work_area()

    def _dialog_closed(self, dialog: QtWidgets.QDialog) -> None:
        """The keyboard goes back to the window (Ctrl+Z right after OK undoes it), the dialog goes away."""
        self.activateWindow()
        dialog.deleteLater()

    # -------------------------------------------------------------------------------------- link
    def apply_view_only(self) -> None:
        """The robot's view-only mark changed: every widget (and the preview) restarts on ports that
        refuse, or no longer refuse, to send (each robot's mark travels in the fleet, see fleet_ui), after
        each robot's link itself took the mark (``view_only.py``)."""
        self.fleet_ui.apply_guards()
        self.controller.client = self.fleet_ui.fleet()
        self.controller.run_current()
        self.preview.restart()

    # -------------------------------------------------------------------------------- painting
    def _ageing_pass(self, now: float) -> None:
        """From the frame clock: every ``FULL_PASS_EVERY`` s a pass over all widgets (their badges age,
        link states show); in the ticks between, only the widgets waiting for their frame interval."""
        if now - self._last_full_pass >= FULL_PASS_EVERY:
            self._last_full_pass = now
            self._pump(None)
        elif self.host.waiting:
            self._pump(set())

    def _pump(self, ids: set[str] | None = None) -> None:
        """Take the runtime's new models and refresh the views that changed (all when ``ids`` is None,
        else those widgets and the ones waiting for their frame interval)."""
        self.host.apply(self.live.take_updates())
        self.host.apply(self.preview_live.take_updates())
        due = self.host.refresh(ids)
        if due is not None and not self._due_timer.isActive():
            self._due_timer.start(max(1, int(due * 1000 + 0.999)))

    # -------------------------------------------------------------------------------- focus
    def focus_lost(self) -> None:
        """The operator's attention left the window: running widgets are told (teleop stops driving)."""
        if self._shut:
            return
        self.focus_losses += 1
        self.live.focus_lost()
        self.preview_live.focus_lost()

    def _app_state_changed(self, state: Any) -> None:
        if state != QtCore.Qt.ApplicationState.ApplicationActive:
            self.focus_lost()

    def changeEvent(self, event: QtCore.QEvent) -> None:
        super().changeEvent(event)
        if event.type() == QtCore.QEvent.Type.ActivationChange and not self.isActiveWindow():
            self.focus_lost()

    def _link_state(self, state: ConnectionState) -> None:
        self.host.set_link_up(state is ConnectionState.CONNECTED, self.fleet_ui.first_id)
        if state is ConnectionState.CONNECTED:
            self.link_came_up()

    def link_came_up(self) -> None:
        """A robot's link is up: its catalogue and message classes arrive in the next seconds, then the
        collector freezes them (a light settle, see ``gcpolicy.py``)."""
        if self.collector is not None:
            self.collector.soon(SETTLE_AFTER_CONNECT)

    def _settle_after(self, change: Change) -> None:
        """Widgets were made and dropped (a workspace opened, another canvas shown): a full settle at
        the next frame, when the pause is not felt."""
        if self.collector is not None and change.what in (ChangeKind.WORKSPACE_REPLACED, ChangeKind.CANVAS_SWITCHED):
            self.collector.soon(0.0, full=True)

    def _poll_catalog(self, now: float) -> None:
        catalog = self.fleet_ui.take_catalog()  # the side panel's robot's
        if catalog is not None:
            self.catalog = catalog
            self.topics.set_entries(catalog["topics"])
            self.services.set_entries(catalog["services"])
            self.actions_list.set_entries(catalog.get("actions", []))
            notes: Any = catalog.get("notes") or {}  # what a Foxglove robot's protocol cannot do (link.py)
            self.actions_list.set_listed_hint(notes.get("actions") or ACTIONS_EMPTY)
        status = self.fleet_ui.catalog_state()  # what the (empty) lists wait for: listing, lost...
        for listing in (self.topics, self.services, self.actions_list):
            listing.set_status(status)
        if now - self._last_rate_sample >= 1.0:
            self._last_rate_sample = now
            self.topics.set_rates(self.rates.sample(self.host.topic_counts(self.fleet_ui.side_robot), now))
        if self.first_paint_at is None:
            self.first_paint_at = time.perf_counter()

    def connect_to(self, url: str, *, remember: bool = True) -> None:
        """Connect to ``url``; ``remember=False`` keeps it out of the URL history (the demo's robot)."""
        self.connection.connect_to(url, remember=remember)

    # -------------------------------------------------------------------------------------- closing
    def closeEvent(self, event: QtGui.QCloseEvent) -> None:
        if self.operator_lock.engaged and not self._close_now and not self._shut:
            event.ignore()  # quitting needs the PIN while the operator lock is on
            self.operator_lock.guard("quit RCON", self.close_now)
            return
        self.shutdown()
        super().closeEvent(event)

    def close_now(self) -> None:
        """Close even while the operator lock is on (after the PIN, or on SIGINT/SIGTERM from a shell)."""
        self._close_now = True
        self.close()

    def shutdown(self) -> None:
        """Stop the clock and the widgets, save, and close the link (idempotent)."""
        if self._shut:
            return
        self._shut = True
        self.clock.stop()
        self.waker.stop()
        self._due_timer.stop()
        if self._remove_gc_listener is not None:
            self._remove_gc_listener()
        app = QtWidgets.QApplication.instance()
        if isinstance(app, QtGui.QGuiApplication):
            try:
                app.applicationStateChanged.disconnect(self._app_state_changed)
            except (RuntimeError, TypeError):
                pass
        self.add_panel.cancel()
        self.record_control.close_files()  # closed properly before the links go
        self.fleet_ui.recordings.close_menu_replay()  # a recording opened from the menu stops playing
        self.controller.shutdown()
        self.preview_live.stop()
        self.fleet_ui.shutdown()
        self.link.shutdown()
        self.config.release()

