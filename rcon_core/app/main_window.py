"""The main window: the composition root that builds the app's parts and wires them together.

The parts live in their own modules: the connection bar (``connection_bar.py``), the side panel's lists
(``catalog_panel.py``, ``params_panel.py``, ``palette_panel.py``) and whether it shows (``side_panel.py``),
the canvas bar (``canvas_bar.py``), the canvases (``canvas_controller.py``), the add panel
(``add_panel.py``), the Configure dialog (``configure_dialog.py``), canvas export/import
(``canvas_files.py``), the layout file's messages (``layout_file.py``), the robots (``fleet_ui.py``) and the
operator lock (``operator_lock.py``, ``lock_controls.py``). Problems go to the notice bar (``notice_bar.py``)
floating over the canvas column.
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
from rcon_core.app.canvas_bar import COMPACT_BELOW, CanvasBar
from rcon_core.app.canvas_controller import CanvasController
from rcon_core.app.canvas_files import CanvasFiles
from rcon_core.app.catalog_panel import CatalogList
from rcon_core.app.children_editor import link_learner
from rcon_core.app.config import AppConfig
from rcon_core.app.configure_dialog import WidgetConfigurer
from rcon_core.app.connection_bar import ConnectionBar
from rcon_core.app.display_settings import install as install_display
from rcon_core.app.draft import Candidate, Target, rank_widgets, targets_for
from rcon_core.app.envelope_dialog import check_placed
from rcon_core.app.envelope_dialog import install as install_envelope
from rcon_core.app.fleet_ui import FleetUi
from rcon_core.app.focus import focus_into, has_focus_inside
from rcon_core.app.frame_clock import FrameClock, Waker
from rcon_core.app.layout_file import LayoutFile
from rcon_core.app.link import RobotConnection
from rcon_core.app.live import LiveCanvas
from rcon_core.app.lock_controls import install as install_lock_controls
from rcon_core.app.notice_bar import NoticeBar
from rcon_core.app.operator_lock import OperatorLock
from rcon_core.app.palette_panel import PalettePanel
from rcon_core.app.params_panel import ParamsPanel
from rcon_core.app.preview import PreviewHost
from rcon_core.app.record_control import install_record_control
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
        self.config = config
        self._shut = False  #: shutdown() ran (closing is idempotent)
        self._close_now = False  #: close without asking for the PIN (after it, or on a signal)
        #: the operator lock (PIN) over Operate mode; its controls are installed at the end (lock_controls)
        self.operator_lock = OperatorLock(config, self)
        self.plugins = plugins
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

        # ---- widgets
        self.connection = ConnectionBar(self.link, config)
        self.topics = CatalogList("topics", with_rate=True)
        self.services = CatalogList("services", with_rate=False)
        self.actions_list = CatalogList("actions", with_rate=False, empty=ACTIONS_EMPTY)
        self.palette_panel = PalettePanel()
        self.palette_panel.set_specs(plugins.widgets())
        self.side = QtWidgets.QTabWidget()
        self.side.setObjectName("sidePanel")
        self.side.addTab(self.topics, "Topics")
        self.side.addTab(self.services, "Services")
        self.side.addTab(self.actions_list, "Actions")
        self.params_panel = ParamsPanel(self.link, self.confirm)
        self.side.addTab(self.params_panel, "Params")
        self.side.addTab(self.palette_panel, "Widgets")
        self.side.setTabPosition(QtWidgets.QTabWidget.TabPosition.West)  # five tabs: all in sight
        self.side.setMinimumWidth(SIDE_MIN)

        self.canvas_bar = CanvasBar({
            "new": ("New canvas", self.new_canvas),
            "rename": ("Rename…", self.rename_canvas_dialog),
            "duplicate": ("Duplicate", self.duplicate_canvas),
            "delete": ("Delete…", self.delete_canvas),
            "export": ("Export canvas…", lambda: self.canvas_files.export_dialog()),
            "import": ("Import canvas…", lambda: self.canvas_files.import_dialog()),
            **({"reset_demo": ("Reset demo layout…", self.reset_demo_dialog)} if demo is not None else {}),
        }, self.undo, self.redo)
        bar = self.canvas_bar  # its parts, by the names the lock controls and the tests use
        self.tabs, self.menu_button, self.edit_button, self.lock_button = (
            bar.tabs, bar.menu_button, bar.edit_button, bar.lock_button)
        self.canvas_actions, self.canvas_buttons = bar.canvas_actions, bar.canvas_buttons
        self.tabs.currentChanged.connect(self._tab_changed)
        bar.mode_tapped.connect(self._mode_toggled)
        self.template_menu = add_template_menu(self, bar.menu, before=self.canvas_actions["rename"])

        self.stack = QtWidgets.QStackedWidget()
        self.add_panel = AddPanel(self.rank_widgets, self.targets_for, self.preview.build, self.preview.release,
                                  child_context=self.child_context)
        self.add_panel.setMinimumWidth(PANEL_MIN)
        self.add_panel.hide()
        self.add_panel.place_requested.connect(self.place_draft)

        center = QtWidgets.QWidget()
        ccol = QtWidgets.QVBoxLayout(center)
        ccol.setContentsMargins(0, 0, 0, 0)
        ccol.setSpacing(0)
        ccol.addWidget(self.canvas_bar)
        ccol.addWidget(self.stack, 1)
        split = QtWidgets.QSplitter()
        split.setHandleWidth(12)
        split.addWidget(self.side)
        split.addWidget(center)
        split.addWidget(self.add_panel)
        split.setStretchFactor(1, 1)
        split.setSizes([SIDE_MIN, 900, 380])
        split.setChildrenCollapsible(False)
        self.split = split
        self.center = center
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
        rcol = QtWidgets.QVBoxLayout(root)
        rcol.setContentsMargins(0, 0, 0, 0)
        rcol.setSpacing(0)
        rcol.addWidget(self.connection)
        #: a layout file that could not be read: says so, that it will not be overwritten, and the way out
        self.notice = NoticeBar("fileBanner")
        self.banner = self.notice.label
        rcol.addWidget(split, 1)
        self.setCentralWidget(root)
        # over the bottom edge of the canvas column: a notice never pushes a control away, and it leaves the
        # bars, the side panel and the add panel (its Place button) uncovered
        self.notice.float_over(center)

        # ---- workspace
        self.layout_path = Path(layout_path) if layout_path is not None else config.workspace_path
        self.layout_file = LayoutFile(self.layout_path, self.notice, demo, lambda: self.controller.saver.flush())
        self.store = self.layout_file.store
        if not config.claim():  # one writer per config folder (config_lock.py): this window saves nothing
            self.store.read_only_reason = config.read_only_reason
        fresh = self.demo is not None and not self.layout_path.exists()  # the demo's first start
        self.doc = Document(self.demo() if fresh and self.demo is not None else self.layout_file.load())
        self.fleet_ui = FleetUi(self)  # one link per robot; hears a change of robots before the controller
        self.controller = CanvasController(self.doc, self.store, self.host, self.live, self.stack)
        self.controller.client = self.fleet_ui.fleet()
        self.controller.save_failed.connect(self.layout_file.save_failed)
        self.controller.on_drop = self._dropped
        self.side_policy.hint_changed.connect(self.controller.set_hint)
        self.canvas_files = CanvasFiles(self, self.controller, self.notice, plugins, self._in_edit_mode,
                                        self._dialog_closed)
        self.configurer = WidgetConfigurer(self, self.doc, plugins, self.types, self.child_context,
                                           self._dialog_closed)
        self.controller.on_configure = self.configurer.open
        self.controller.canvases_changed.connect(self._sync_tabs)
        self.controller.current_changed.connect(self._sync_tabs)
        self.controller.lock_changed.connect(self._show_lock)
        self._sync_tabs()
        self._show_lock(self.controller.canvas.locked)
        self.controller.run_current()  # offline (LINK DOWN) until a robot is connected
        if fresh or self.layout_file.demo_rebuilt:
            self.controller.saver.flush()  # the demo layout is on disk from its first start on

        # ---- signals and the frame clock
        self.topics.picked.connect(lambda n, t: self._start_adding(lambda: self.add_panel.start_from_topic(n, t)))
        self.services.picked.connect(
            lambda n, t: self._start_adding(lambda: self.add_panel.start_from_service(n, t)))
        self.actions_list.picked.connect(
            lambda n, t: self._start_adding(lambda: self.add_panel.start_from_action(n, t)))
        self.palette_panel.picked.connect(self._palette_picked)
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
        self.clock.add(self.connection.poll)
        self.clock.add(self.fleet_ui.poll)
        self.clock.add(self._poll_catalog)
        self.clock.add(self._ageing_pass)
        if collector is not None:
            collector.soon(1.0, full=True)  # once the window is built and shown
            self.clock.add(collector.poll)
            self._remove_gc_listener = self.doc.add_listener(self._settle_after)
        self.clock.start()
        app = QtWidgets.QApplication.instance()
        if isinstance(app, QtGui.QGuiApplication):
            app.applicationStateChanged.connect(self._app_state_changed)
        install_lock_controls(self)  # the operator lock's and the view-only controls
        install_envelope(self)  # Canvas ▾ → Safety envelope… (the PIN first while locked)
        #: the Record control on the connection bar (the flight recorder: record_control.py)
        self.record_control: Any = install_record_control(self)
        #: the timeline of a recording played as the robot (replay_bar.py), or None
        self.replay: Any = None
        self.replay_stack: Any = None  # what plays a recording opened from the menu (closed at shutdown)
        install_display(self)  # Canvas ▾ → Display…: theme and text size
        install_accessibility()  # the roles of the widgets that paint themselves
        name_side_panel(self.side)
        self.resize(self.initial_size())

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
        """A window-modal question with two large buttons (``yes`` and Cancel); ``then`` runs on yes.
        Returns at once (the dialog is open), so the event loop and the robot link keep running."""
        box = QtWidgets.QMessageBox(self)
        box.setObjectName("confirmDialog")
        box.setIcon(QtWidgets.QMessageBox.Icon.Warning)
        box.setWindowTitle(question)
        box.setText(question)
        box.setInformativeText(detail)
        ok = box.addButton(yes, QtWidgets.QMessageBox.ButtonRole.DestructiveRole)
        ok.setObjectName("confirmYes")
        cancel = box.addButton(QtWidgets.QMessageBox.StandardButton.Cancel)
        cancel.setObjectName("confirmCancel")
        box.setDefaultButton(cancel)
        for button in (ok, cancel):
            button.setMinimumWidth(max(button.sizeHint().width(), 160))
        box.buttonClicked.connect(lambda button: then() if button is ok else None)
        box.finished.connect(lambda _result: self._confirm_closed())
        self.confirm_dialog = box
        box.open()
        return box

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
        index = self.controller.index
        name, ok = QtWidgets.QInputDialog.getText(
            self, "Rename canvas", "Name", text=self.controller.canvas.name
        )
        if ok:
            try:
                self.controller.rename_canvas(index, name)
            except ValueError as exc:
                self.notice.show_notice(f"⚠ {exc}")

    def duplicate_canvas(self) -> None:
        self.controller.duplicate_canvas(self.controller.index)

    def delete_canvas(self) -> None:
        """Delete the current canvas; one with widgets is deleted only after the operator confirms."""
        canvas = self.controller.canvas

        def delete() -> None:
            if canvas in self.controller.workspace.canvases:
                try:
                    self.controller.delete_canvas(self.controller.workspace.canvases.index(canvas))
                except ValueError as exc:
                    self.notice.show_notice(f"⚠ {exc}")

        if not canvas.widgets or len(self.controller.workspace.canvases) < 2:
            delete()  # nothing to lose (or refused with a message: the last canvas stays)
            return
        count = len(canvas.widgets)
        self.confirm(f"Delete canvas “{canvas.name}”?",
                     f"It holds {count} widget{'s' if count != 1 else ''}. Undo (↶, Ctrl+Z) brings it back.",
                     "Delete", delete)

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

    # -------------------------------------------------------------------------------------- adding
    def _palette_picked(self, kind: str) -> None:
        self._start_adding(lambda: self.add_panel.start_from_widget(self.plugins.widget(kind)))

    def _start_adding(self, start: Callable[[], object]) -> None:
        """Open the add panel; on a locked canvas say why not and offer to switch to Edit mode."""
        self._in_edit_mode("add widgets", start)

    def _in_edit_mode(self, what: str, start: Callable[[], object]) -> None:
        """Run ``start`` now in Edit mode; in Operate mode the notice says why not and offers to switch
        (then runs it)."""
        if not self.controller.canvas.locked:
            start()
            return

        def unlock_and_start() -> None:
            if self.operator_lock.engaged:
                self.operator_lock.guard(what, unlock_and_start)
                return
            self.notice.dismiss()
            self.controller.set_locked(False)
            start()
            self.focus_work_area()  # the tapped notice button is gone: not the URL field next in line

        self.notice.show_notice(f"ℹ Switch to Edit mode to {what}: this canvas is in Operate mode "
                                "(locked).", kind="info", actions=[("Switch to Edit mode", unlock_and_start)])

    def rank_widgets(self, type_name: str, role: Role) -> list[Candidate]:
        return rank_widgets(type_name, role, self.types, self.plugins)

    def targets_for(self, spec: WidgetSpec, role: Role) -> list[Target]:
        return targets_for(spec, role, self.catalog.get(f"{role.noun}s", []), self.types, self.plugins)

    def place_draft(self) -> None:
        draft = self.fleet_ui.bind(self.add_panel.take_draft())  # the panel closes
        if draft is not None:
            self._settle_layout()  # the free spot is looked for in the canvas as it is without the panel
            try:
                self.controller.add_draft(draft)
            except ValueError as exc:
                self.notice.show_notice(f"⚠ {exc}")
                return
            check_placed(self, draft)  # beyond the robot's safety envelope: kept only when the operator says

    def _settle_layout(self) -> None:
        """Apply pending layout changes now (the add panel just closed, the side panel may be back), so
        the canvas view has its new size."""
        for _ in range(3):
            QtWidgets.QApplication.sendPostedEvents(None, QtCore.QEvent.Type.LayoutRequest)

    def _dropped(self, _surface: Any, point: QtCore.QPoint) -> None:
        side_hidden = not self.side.isVisibleTo(self)
        draft = self.fleet_ui.bind(self.add_panel.take_draft())  # the panel closes
        if side_hidden and self.side.isVisibleTo(self):
            # the side panel gave its room to the add panel; coming back now it would push the canvas
            # (and the widget just dropped under the finger) sideways: it stays hidden until ▶ is tapped
            self.side_policy.keep_hidden()
        if draft is not None:
            self.controller.add_draft(draft, point)
            check_placed(self, draft)  # beyond the robot's safety envelope: kept only when the operator says

    def child_context(self, binding: Callable[[], Binding | None]) -> ChildContext:
        """What a settings form's children editor needs: types, widgets, the parent's binding, and a way to
        learn a type from the robot."""
        return ChildContext(self.types, self.plugins, binding, link_learner(self.link))

    def _confirm_closed(self) -> None:
        """After a confirm dialog (either answer) the keyboard is the window's again: Ctrl+Z, Ctrl+Q work."""
        self.activateWindow()
        if not has_focus_inside(self):
            self.focus_work_area()

    def focus_work_area(self) -> None:
        """Give the keyboard to what the operator works on: the add panel's page when it is open, else
        the canvas."""
        if self.add_panel.isVisible():
            page = self.add_panel.stack.currentWidget()
            focus_into(page if page is not None else self.add_panel)
        else:
            self.controller.surface.setFocus(QtCore.Qt.FocusReason.OtherFocusReason)

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
        self.connection.url.setCurrentText(url)
        self.connection.connect_clicked(remember=remember)

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
        if self.replay_stack is not None:
            self.replay_stack.close()  # a recording opened from the menu stops playing
        self.controller.shutdown()
        self.preview_live.stop()
        self.fleet_ui.shutdown()
        self.link.shutdown()
        self.config.release()

