"""The window's side of several robots: one link per robot, the chips, the side panel's robot, the robot
marks on widgets, and re-targeting a canvas.

:class:`FleetUi` is made by the main window right after its document (so it hears a change of robots
before the canvas controller does) and polled once per frame. It

- keeps a :class:`~rcon_core.app.fleet_links.FleetLinks` in step with the workspace's robots (the first
  robot's link is the window's own, driven by the connection bar), connects the other robots to their
  URLs, and gives the canvas runtime a :class:`~rcon_core.canvas.fleet.Fleet` of the current clients;
  a client change of one robot restarts only that robot's widgets;
- shows each robot's link on its chip (:mod:`rcon_core.app.robot_chips`) and on its own widgets (LINK
  DOWN on that robot's frames only);
- keeps the side panel's robot (:attr:`side_robot`): its topics, services and actions fill the lists, the
  Parameters tab shows its parameters, new widgets are bound to it, the add panel's preview runs on it;
- marks the widgets of a canvas that mixes robots (:mod:`rcon_core.app.robot_marks`);
- adds "Robots…" and "Duplicate for robot ▸" to the Canvas menu.

It is given the few parts it works with, typed (the document, the window's own link, the connection bar,
the widget host and runtime, the side panel's lists, the canvas bar, the notice bar, the app config, the
operator lock's guard and the window's question), and talks back through signals: ``fleet_changed`` (the
runtime's clients or marks changed), ``rerun`` (the current canvas's widgets start again),
``preview_stale``, ``side_robot_changed``, ``side_link_changed``/``side_client_changed`` (the Parameters
tab follows the side panel's robot) and ``link_up`` (a robot's link came up). The window places
:attr:`FleetUi.chips` under the connection bar and wires the signals.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from functools import partial
from pathlib import Path
from typing import Any

from qtpy import QtCore, QtGui, QtWidgets

from rcon_core.app import view_only
from rcon_core.app.canvas_bar import CanvasBar
from rcon_core.app.catalog_panel import CatalogList
from rcon_core.app.config import AppConfig
from rcon_core.app.connection_bar import LIVE_STATES, ConnectionBar
from rcon_core.app.fleet_links import FleetLinks
from rcon_core.app.link import EMPTY_CATALOG, OFFLINE, BadUrl, RobotConnection, as_state
from rcon_core.app.live import LiveCanvas
from rcon_core.app.notice_bar import NoticeBar
from rcon_core.app.operator_lock import Guard
from rcon_core.app.params_panel import Confirm
from rcon_core.app.robot_chips import RobotChips, RobotPicker
from rcon_core.app.robot_marks import apply_marks
from rcon_core.app.robot_recordings import RobotRecordings
from rcon_core.app.widget_host import WidgetHost
from rcon_core.bridge import ConnectionState
from rcon_core.canvas import Change, ChangeKind, Document, EditError
from rcon_core.canvas.fleet import Fleet
from rcon_core.canvas.retarget import plan_retarget, setting_names
from rcon_core.canvas.robots import Robot, robot_colour

log = logging.getLogger(__name__)

__all__ = ["FleetUi"]


class FleetUi(QtCore.QObject):
    """Several robots in the main window (see the module docstring)."""

    #: the side panel's robot (a robot id): its lists, parameters and new widgets
    side_robot_changed = QtCore.Signal(str)
    #: the runtime's clients or view-only marks changed (the canvas runtime takes :meth:`fleet`)
    fleet_changed = QtCore.Signal()
    #: the current canvas's widgets start again (another robot list or mark)
    rerun = QtCore.Signal()
    #: the add panel's preview starts again (on another robot or client)
    preview_stale = QtCore.Signal()
    #: the side panel's robot's link (the Parameters tab follows it)
    side_link_changed = QtCore.Signal(object)
    #: the side panel's robot got a new client (or None: disconnected)
    side_client_changed = QtCore.Signal(object)
    #: a robot's link (not the first's: the connection bar says that one) came up
    link_up = QtCore.Signal(str)

    def __init__(self, doc: Document, link: RobotConnection, connection: ConnectionBar, host: WidgetHost,
                 live: LiveCanvas, lists: Sequence[CatalogList], bar: CanvasBar, notice: NoticeBar, config: AppConfig,
                 guard: Guard, confirm: Confirm, parent: QtWidgets.QWidget) -> None:
        super().__init__(parent)
        self.doc, self.connection, self.host, self.live, self.bar = doc, connection, host, live, bar
        self.notice, self.config, self.guard, self.confirm, self.dialog_parent = notice, config, guard, confirm, parent
        self.links = FleetLinks(link, secret_for=connection.secrets.get, overrides=lambda: connection.overrides)
        # the bandwidth readout lists every robot's link (named when there are several)
        connection.bandwidth.sources = self._bandwidth_sources
        self.chips = RobotChips()  # right under the connection bar (the window puts it there)
        self.chips.picked.connect(self.pick_side_robot)
        self.pickers = []
        for lst in lists:
            picker = RobotPicker(lst.what)
            picker.picked.connect(self.pick_side_robot)
            col = lst.layout()
            if isinstance(col, QtWidgets.QBoxLayout):
                col.insertWidget(0, picker)
            self.pickers.append(picker)
        #: the robot whose topics and services the side panel shows (a robot id)
        self.side_robot = ""
        self.catalogs: dict[str, dict[str, list[tuple[str, str]]]] = {}
        self._catalog_dirty = True
        self._marks_dirty = True
        self._marked_models = -1  # the host's models_version the marks were last applied for
        self._states: dict[str, ConnectionState] = {}
        #: the plan of the last "Duplicate for robot" (names mapped and missing; tests)
        self.retarget_plan: Any = None
        #: robot id -> why its link is not up (words of rcon_core.bridge.reasons), for its chip
        self.why: dict[str, str] = {}
        #: the players of the robots whose source is a recording file (robot_recordings.py)
        self.recordings = RobotRecordings(self.links, notice, self.why, Path(config.dir) / "recordings", self)
        self._remove = doc.add_listener(self._doc_changed)
        self.links.on_client_changed(self._client_changed)
        self._sync_robots()
        self._add_menu()
        # the other robots connect once the window is built (the first one: the connection bar)
        QtCore.QTimer.singleShot(0, self.connect_saved)

    # ------------------------------------------------------------------------------------ reading
    @property
    def robots(self) -> list[Any]:
        return self.doc.workspace.robots

    @property
    def first_id(self) -> str:
        return self.robots[0].id

    def binding_robot(self, robot_id: str) -> str:
        """What a binding stores for ``robot_id``: ``""`` for the first robot (as one-robot layouts)."""
        return "" if not robot_id or robot_id == self.first_id else robot_id

    def fleet(self) -> Fleet:
        """The current clients, for the canvas runtime, with each robot's view-only mark: its own flag, or
        its URL marked view-only in the app config (Canvas ▾ → robot view-only)."""
        fleet = self.links.fleet(OFFLINE)
        for robot in fleet.robots:
            fleet.set_view_only(robot.id, self.config_view_only(robot.id))
        return fleet

    def robot_url(self, robot_id: str) -> str | None:
        """Where the robot is: the first robot's is the connection bar's (connected, else the field)."""
        if not robot_id or robot_id == self.first_id:
            return self.connection.robot_url() or None
        return self.links.url_of(robot_id)

    def config_view_only(self, robot_id: str, url: str | None = None) -> str | None:
        """Why the robot (at ``url``, default: where it is) may not be commanded, naming it (its URL's
        mark, its own flag, or a recording played as it; view_only.py)."""
        robot = view_only.find_robot(self.robots, robot_id)
        if robot is not None and url is None and not robot.recording:
            url = self.robot_url(robot.id)
        return view_only.reason(robot, url, self.config, self.recordings.replay)

    def apply_guards(self) -> None:
        """Each robot's link refuses, or stops refusing, to send anything that changes the robot
        (rcon_core.bridge.guard); each asks again for every new client (a new URL may carry another mark)."""
        for robot, link in self.links.items():
            link.guard_for = partial(self.config_view_only, robot.id)
            link.apply_guard()

    def side_target(self) -> tuple[Robot | None, str]:
        """The side panel's robot and its URL ("" when none yet): what the robot view-only action acts on."""
        robot = view_only.find_robot(self.robots, self.side_robot)
        return robot, (self.robot_url(robot.id) or "") if robot is not None else ""

    def side_fleet(self) -> Fleet:
        """The same, the side panel's robot first (a preview's binding names no robot or that one)."""
        fleet = self.fleet()
        pairs = fleet.items()
        pairs.sort(key=lambda p: p[0].id != self.side_robot)
        return Fleet(pairs, {r.id: why for r, _c in pairs if (why := fleet.view_only_reason(r.id))})

    def first_url(self) -> str:
        return self.robots[0].url

    # ------------------------------------------------------------------------------------ robots
    def _doc_changed(self, change: Change) -> None:
        if change.what in (ChangeKind.ROBOTS_CHANGED, ChangeKind.WORKSPACE_REPLACED):
            before = self._seen
            new = self._sync_robots()  # _seen is now the new robots
            if change.what is ChangeKind.ROBOTS_CHANGED:  # the controller restarts on workspace-replaced itself
                self._rerun(before)
            # once the runtime runs on the new robots (the controller hears this change after us)
            QtCore.QTimer.singleShot(0, lambda: self._connect(new))
        self._marks_dirty = True

    def _rerun(self, before: list[tuple[str, str, bool]]) -> None:
        """The robots were edited (Robots… OK, undo, redo): rebuild only the running widgets that change.
        Another robot list or view-only mark: every widget (its port, its robot); only names: the widgets
        that show every robot (their tracks carry the names); a new URL or connection setting: nothing here
        (that robot reconnects, and its own widgets are rebuilt on the new link, see _client_changed). OK
        with nothing changed keeps every form, trail and value as it was."""
        now = self._seen
        if [(rid, vo) for rid, _n, vo in before] != [(rid, vo) for rid, _n, vo in now]:
            self.rerun.emit()
        elif before != now:
            host, live = self.host, self.live
            for widget in self.doc.current.widgets:
                hosted = host.hosted.get(widget.id)
                if hosted is not None and hosted.model is not None and hosted.model.shows_every_robot:
                    live.restart(widget)

    def _sync_robots(self) -> list[str]:
        """Links, chips, pickers and menus for the workspace's robots; returns the robots to connect."""
        robots = self.robots
        #: what of the robots the running widgets depend on: id, name and view-only mark, in order
        self._seen: list[tuple[str, str, bool]] = [(r.id, r.label, bool(r.view_only)) for r in robots]
        new = self.links.sync(robots)
        self.recordings.sync(robots)  # a robot gone, or given another file: its player stops
        self.apply_guards()  # a robot's own view-only flag may have changed, a new link needs its mark
        self.host.first_robot = robots[0].id
        self.fleet_changed.emit()
        if self.side_robot not in [r.id for r in robots]:
            self.side_robot = robots[0].id
            self._catalog_dirty = True
            self._params_follow()
        shown = [(r.id, r.label, robot_colour(robots, r.id)) for r in robots]
        self.chips.set_robots(shown, self.side_robot)
        for picker in self.pickers:
            picker.set_robots(shown, self.side_robot)
        if hasattr(self, "retarget_menu"):
            self._fill_retarget_menu()
        for rid in list(self.catalogs):
            if rid not in {r.id for r in robots}:
                del self.catalogs[rid]
        return new

    def _connect(self, robot_ids: list[str]) -> None:
        """Connect robots that are new or reached differently now (a bad URL is logged, the others go on)."""
        first = self.first_id
        for rid in robot_ids:
            if rid not in self.links.ids:  # gone again before this ran (an undo)
                continue
            try:
                robot = self.links.robot(rid)
                if robot.recording:
                    self.recordings.play(robot, first=rid == first)
                elif rid != first:
                    self.links.connect_robot(rid)
                elif self.first_url():  # the first robot's URL was set: the connection bar goes there
                    self.connection.connect_to(self.first_url())
            except (BadUrl, KeyError) as exc:
                log.warning("robot %s: %s", rid, exc)

    def connect_saved(self) -> None:
        """Connect every robot but the first to its URL (the window connects the first one); play each
        robot whose source is a recording file."""
        self.links.connect_saved()
        for i, robot in enumerate(self.robots):
            if robot.recording:
                self.recordings.play(robot, first=i == 0)

    def connect_robot(self, robot_id: str, url: str | None = None) -> None:
        """Connect ``robot_id`` to ``url`` for this run (not saved: the demo's sims) or to its saved URL.
        The first robot goes through the connection bar (its URL field shows it)."""
        if not robot_id or robot_id == self.first_id:
            target = url or self.first_url()
            if target:
                self.connection.connect_to(target, remember=url is None)
            return
        self.links.connect_robot(robot_id, url)

    def _client_changed(self, robot_id: str, client: Any) -> None:
        """A new client for one robot: only its widgets are rebuilt on it. Disconnect (no client) keeps its
        running widgets and their last values, LINK DOWN then STALE, like a lost link."""
        self.fleet_changed.emit()
        live = self.live
        if not live.running:
            self.rerun.emit()
        elif client is None:
            live.set_client(robot_id, OFFLINE, keep=True)
        else:
            live.set_client(robot_id, client, view_only=self.config_view_only(robot_id))
        if robot_id == self.side_robot:
            self.catalogs.pop(robot_id, None)
            self._catalog_dirty = True
            self.side_client_changed.emit(client)
        self.preview_stale.emit()

    # ---------------------------------------------------------------------------------- side panel
    def bind(self, draft: Any) -> Any:
        """A draft being placed talks to the side panel's robot (whose topic or service it names)."""
        if draft is not None:
            draft.robot = self.binding_robot(self.side_robot)
        return draft

    def pick_side_robot(self, robot_id: str) -> None:
        """Show ``robot_id``'s topics and services in the side panel; new widgets are bound to it."""
        if robot_id not in [r.id for r in self.robots] or robot_id == self.side_robot:
            self.chips.set_current(self.side_robot)
            return
        self.side_robot = robot_id
        self.chips.set_current(robot_id)
        for picker in self.pickers:
            picker.set_current(robot_id)
        self._catalog_dirty = True
        self._params_follow()
        self.preview_stale.emit()
        self.side_robot_changed.emit(robot_id)  # the window's topic rates start afresh

    def _params_follow(self) -> None:
        """The Parameters tab shows the side panel's robot's parameters."""
        self.side_link_changed.emit(self.links.link(self.side_robot))

    def take_catalog(self) -> dict[str, list[tuple[str, str]]] | None:
        """Every robot's new catalogue is kept; the side robot's is returned when it changed (else None)."""
        for robot, link in self.links.items():
            ok, catalog = link.catalog_box.take()
            if ok:
                self.catalogs[robot.id] = catalog
                if robot.id == self.side_robot:
                    self._catalog_dirty = True
        if not self._catalog_dirty:
            return None
        self._catalog_dirty = False
        return self.catalogs.get(self.side_robot, EMPTY_CATALOG)

    def _bandwidth_sources(self) -> list[tuple[str, Any]]:
        """Each robot's link for the bandwidth readout, named when there are several."""
        pairs = self.links.items()
        return [(robot.label if len(pairs) > 1 else "", link) for robot, link in pairs]

    def catalog_state(self) -> str:
        """What the side robot's lists wait for (``RobotConnection.catalog_state``: "connecting",
        "listing", "lost"...)."""
        try:
            return str(self.links.link(self.side_robot).catalog_state)
        except KeyError:
            return "offline"

    # ------------------------------------------------------------------------------------- polling
    def poll(self, _now: float = 0.0) -> None:
        """Once per frame: each robot's link state on its chip and its widgets; the marks."""
        first = self.first_id
        for robot, link in self.links.items():
            if robot.id == first:
                state = self.connection.state  # the connection bar takes the first link's mailboxes
                failure = self.connection.failure
                self.why[first] = failure.text() if failure is not None else ""
            else:
                ok, taken = link.state_box.take()
                state = taken if ok else self._states.get(robot.id, ConnectionState.CLOSED)
                self._take_failure(robot.id, link)
                link.answered_box.take()
            state = as_state(state)
            if self._states.get(robot.id) != state:
                self._states[robot.id] = state
                self.host.set_link_up(state is ConnectionState.CONNECTED, robot.id)
                if state is ConnectionState.CONNECTED and robot.id != first:
                    self.link_up.emit(robot.id)
            latency = link.latency if state in LIVE_STATES else None
            mark = self.config_view_only(robot.id)  # its URL's mark or its own flag, naming it
            self.chips.show_state(robot.id, state, latency,
                                  None if state is ConnectionState.CONNECTED else self.why.get(robot.id) or None, mark)
        if self._marks_dirty or self.host.models_version != self._marked_models:
            self._marks_dirty = False
            self._marked_models = self.host.models_version
            apply_marks(self.host, self.doc.workspace)

    def _take_failure(self, robot_id: str, link: Any) -> None:
        """Why a robot's link is not up, in words (its chip's tooltip); a failure that retrying cannot fix
        (TLS, a refused secret) ends that robot's link, as the connection bar does for the first."""
        ok, failure = link.failure_box.take()
        if ok:
            if failure is None:
                self.why.pop(robot_id, None)
            else:
                self.why[robot_id] = failure.text()
                if failure.fatal:
                    link.disconnect()
                    self._states[robot_id] = ConnectionState.CLOSED
        ok, error = link.error_box.take()
        if ok and error:
            self.why[robot_id] = str(error)

    # ----------------------------------------------------------------------------------- canvas menu
    def _add_menu(self) -> None:
        menu = self.bar.menu
        before = self.bar.canvas_actions.get("delete")
        self.retarget_menu = QtWidgets.QMenu("Duplicate for robot", menu)
        self.retarget_menu.setObjectName("retargetMenu")
        self.retarget_menu.aboutToShow.connect(self._fill_retarget_menu)
        retarget = menu.insertMenu(before, self.retarget_menu) if before is not None else menu.addMenu(
            self.retarget_menu)
        retarget.setObjectName("canvas_retarget")
        self.bar.canvas_actions["retarget"] = retarget
        self._fill_retarget_menu()
        robots = QtGui.QAction("Robots…", menu)
        if before is not None:
            menu.insertAction(before, robots)
        else:
            menu.addAction(robots)
        robots.setObjectName("canvas_robots")
        robots.triggered.connect(lambda: self.guard("edit the robots", self.open_robots_dialog))
        self.bar.canvas_actions["robots"] = robots

    def _fill_retarget_menu(self) -> None:
        self.retarget_menu.clear()
        self.retarget_menu.setEnabled(len(self.robots) > 1)  # with one robot it would be a plain duplicate
        for robot in self.robots:
            action = self.retarget_menu.addAction(robot.label)
            action.setObjectName(f"retarget-{robot.id}")
            action.triggered.connect(lambda _c=False, rid=robot.id: self.retarget_current(rid))

    def retarget_current(self, robot_id: str) -> Any:
        """Duplicate the current canvas for ``robot_id`` and show the copy (one undo step). The names its
        widgets use are mapped into the robot's namespace and checked against the robot's topics, services
        and actions (``rcon_core.canvas.retarget``); when a name changes or the robot lacks one, the
        operator is told which before the copy is made (returns that question's dialog)."""
        canvas = self.doc.current
        label = next((r.label for r in self.robots if r.id == robot_id), robot_id)
        names = [n for w in canvas.widgets for n in (w.binding.name, *setting_names(w.settings))]
        catalog = self.catalogs.get(robot_id)
        known = None if catalog is None else {n for part in ("topics", "services", "actions")
                                              for n, _t in catalog.get(part, [])}
        plan = plan_retarget(names, known)
        self.retarget_plan = plan
        if plan.quiet or robot_id not in [r.id for r in self.robots]:
            return self._duplicate(canvas.id, robot_id, {})
        if not plan.renames and not plan.missing:  # not connected: nothing to check, said, copied as it is
            self._duplicate(canvas.id, robot_id, {})
            self.notice.show_notice(f"⚠ {plan.describe(label)}")
            return None
        return self.confirm(f"Duplicate “{canvas.name}” for {label}?", plan.describe(label), "Duplicate",
                                   lambda: self._duplicate(canvas.id, robot_id, plan.renames))

    def _duplicate(self, canvas_id: str, robot_id: str, renames: dict[str, str]) -> None:
        try:
            dup = self.doc.duplicate_for_robot(canvas_id, robot_id, renames=renames)
        except EditError as exc:
            self.notice.show_notice(f"⚠ {exc}")
            return
        self.doc.switch_canvas(dup.id)

    def open_robots_dialog(self) -> QtWidgets.QDialog:
        from rcon_core.app.robots_dialog import RobotsDialog

        dialog = RobotsDialog(self.robots, self.dialog_parent)
        dialog.accepted.connect(lambda: self._robots_edited(dialog))
        dialog.finished.connect(lambda _r: dialog.deleteLater())
        self.robots_dialog = dialog
        dialog.open()
        return dialog

    def _robots_edited(self, dialog: Any) -> None:
        try:
            self.doc.set_robots(dialog.robots())
        except EditError as exc:
            self.notice.show_notice(f"⚠ {exc}")

    def shutdown(self) -> None:
        self._remove()
        self.links.shutdown()
        self.recordings.shutdown()
