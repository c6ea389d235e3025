"""Running a canvas: one model per widget instance, each with its own node of the bridge client.

::

    rt = CanvasRuntime(plugin_manager, client, types=type_registry, plugin_settings=ws.plugin_settings)
    rt = CanvasRuntime(plugin_manager, Fleet([(robot_a, client_a), (robot_b, client_b)]), ...)
    rt.start(canvas)            # builds and starts every widget's model
    rt.models[widget_id].state  # what the view paints
    rt.start(other_canvas)      # stops every widget of the old canvas (their subscriptions and
                                #   advertisements end on the server), starts the new one's
    rt.restart_widget(inst)     # after a reconfigure
    rt.focus_lost()             # the operator looked away: models' optional on_focus_lost() (teleop stops)
    rt.set_client(robot_id, c)  # that robot's link is another client now: only its widgets restart
    rt.stop()                   # focus_lost() first, then every model stops

Several robots (:mod:`rcon_core.canvas.fleet`): each widget runs on the client of the robot its binding
names (``binding.robot``, ``""`` = the first); each robot's link state reaches only its own widgets
(``model.set_link``), so losing one robot's link stops that robot's commands (teleop sends nothing, its
frames say LINK DOWN) while the others stay live. A model with ``on_fleet(robots)`` also gets a port on
every robot (the map of every robot's fix). A binding naming a robot the workspace does not have gets a
:class:`BrokenWidgetModel` saying so.

``on_activity(widget_id)`` (optional) is called on the loop thread right after a widget's model handled
an incoming message, service request or service response, so a front end can repaint at once instead of
polling on its next frame.

Every model gets a :class:`rcon_core.canvas.port.GuardedPort` onto its node, never the node itself.
``CanvasRuntime(..., view_only="reason")`` (every robot of this runtime is view-only), a robot marked
view-only in the fleet (``Fleet.view_only_reason(robot_id)``) or a canvas with ``view_only`` set makes
those ports refuse to publish, call or serve (``rt.view_only_reason(canvas, robot_id)``).

Call these on the bridge loop thread (from the GUI: ``bridge_thread.call(rt.start, canvas)``); pass
``dispatch=bridge_thread.call`` so the models' GUI-side actions reach the loop thread too.

The robot may not know a widget's type (a lab's own message whose package is not installed there), and
rosbridge 0.11 does not say so on the wire: for a type that is not standard the runtime asks the robot
(:class:`~rcon_core.bridge.typecheck.TypeChecker`) and, on a refusal, sets the model's error to "the robot
does not know lab_msgs/Winch (is its package installed there?)", so the frame shows ERROR rather than
NO DATA. A server that reports a failed subscribe/advertise with a ``status`` op sets the error too.

A widget whose plugin is missing gets a :class:`MissingWidgetModel` (shows why, talks to nobody); a
widget whose stored settings hold a value of the wrong type gets an :class:`UnconfiguredWidgetModel` (its
frame shows the "not configured" warning with one sentence per bad value); a widget whose model cannot
be built otherwise (an import error) gets a :class:`BrokenWidgetModel`; the other widgets run either way. The instance data is never touched, so it saves back unchanged.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Callable
from typing import Any

from rcon_core.bridge.client import ConnectionState
from rcon_core.bridge.safety import safe_text
from rcon_core.bridge.typecheck import TypeChecker, status_failure
from rcon_core.plugins.api import Binding, HostedModel, Port, RobotPort
from rcon_core.plugins.context import SharedResources, WidgetContext
from rcon_core.plugins.manager import PluginManager, UnknownWidget
from rcon_core.plugins.model_types import ModelTypes
from rcon_core.plugins.spec import SettingsError

from .fleet import BridgeNode, Fleet, RobotClient
from .placeholders import BrokenWidgetModel, MissingWidgetModel, UnconfiguredWidgetModel
from .port import GuardedPort
from .robots import UnknownRobot
from .workspace import Canvas, WidgetInstance

__all__ = ["CanvasRuntime", "MissingWidgetModel", "BrokenWidgetModel", "UnconfiguredWidgetModel"]

log = logging.getLogger(__name__)


_LOGGED: set[tuple[Any, ...]] = set()
_LOGGED_MAX = 1000


def _log_once(level: int, fmt: str, *args: Any) -> None:
    """Log a widget's standing problem once per process, not at every (re)start of its canvas."""
    key = (fmt, *map(str, args))
    if key in _LOGGED:
        return
    if len(_LOGGED) >= _LOGGED_MAX:
        _LOGGED.clear()
    _LOGGED.add(key)
    log.log(level, fmt, *args)


def _is_up(state: ConnectionState | str) -> bool:
    """Whether a link state is usable: only CONNECTED (DEGRADED, a stalled link, counts as down). A test's
    fake client may report the state by its value (``"connected"``)."""
    return state is ConnectionState.CONNECTED or state == ConnectionState.CONNECTED.value


class CanvasRuntime:
    """Creates, starts and stops the models of one canvas at a time."""

    def __init__(
        self,
        plugin_manager: PluginManager,
        client: Fleet | RobotClient,
        *,
        types: ModelTypes | None = None,
        plugin_settings: dict[str, dict[str, Any]] | None = None,
        dispatch: Callable[[Callable[[], Any]], Any] | None = None,
        on_activity: Callable[[str], Any] | None = None,
        view_only: str | None = None,
    ) -> None:
        self.pm = plugin_manager
        #: every robot of this runtime is view-only: why (None: each robot's own mark decides); see
        #: :meth:`view_only_reason`
        self.view_only = view_only
        self.on_activity = on_activity
        #: robot id -> client; a bare client is a fleet of one robot
        self.fleet = client if isinstance(client, Fleet) else Fleet.single(client)
        #: the type registry every model gets (the runtime always passes one: the plugin manager's standard
        #: registry with every contributed type when none is given)
        self.types: ModelTypes = types if types is not None else plugin_manager.type_registry()
        self.plugin_settings = plugin_settings if plugin_settings is not None else {}
        self.dispatch = dispatch
        self.canvas: Canvas | None = None
        self.models: dict[str, HostedModel] = {}
        self._nodes: dict[str, list[Any]] = {}  # widget id -> its node, then its other robots' nodes
        self._robot_of: dict[str, str] = {}  # widget id -> robot id (resolved)
        self._fleet_wide: set[str] = set()  # widgets whose model has on_fleet
        self._remove: dict[str, list[Callable[[], None]]] = {}  # robot id -> listener removers
        self._link_up: dict[str, bool] = {}
        #: objects the widgets on one robot link share (``WidgetContext.shared``), by the port's ``link``
        self.shared = SharedResources()
        self._checkers: dict[str, TypeChecker] = {}
        self._checks: set[asyncio.Task[Any]] = set()
        #: hooks of the widgets' models that raised (logged once per widget and text; the others went on)
        self.hook_errors = 0

    @property
    def client(self) -> RobotClient:
        """The first robot's client (the only one in a one-robot workspace)."""
        return self.fleet.client("")

    @client.setter
    def client(self, client: RobotClient) -> None:
        """Widgets started from now on use ``client`` for the first robot; running ones keep theirs."""
        self.set_client("", client, restart=False)

    # -- lifecycle -----------------------------------------------------------------------------------
    def start(self, canvas: Canvas) -> None:
        """Build and start every widget of ``canvas`` (stopping the current canvas first, if any)."""
        if self.canvas is not None:
            self.stop()
        self.canvas = canvas
        for robot_id in self.fleet.ids:
            self._listen(robot_id)
        for inst in canvas.widgets:
            self._start_widget(inst)

    def stop(self) -> None:
        """Tell the models focus is lost, stop every one and close its node (ending what it forgot)."""
        self.focus_lost()
        for widget_id in list(self.models):
            self._stop_widget(widget_id)
        self.canvas = None
        for task in list(self._checks):
            task.cancel()
        for robot_id in list(self._remove):
            self._unlisten(robot_id)

    def restart_widget(self, inst: WidgetInstance) -> HostedModel:
        """Rebuild one widget's model (after its settings or binding changed)."""
        self._stop_widget(inst.id)
        return self._start_widget(inst)

    def set_client(self, robot_id: str, client: RobotClient, *, restart: bool = True,
                   view_only: str | None | bool = False) -> None:
        """``robot_id``'s link is ``client`` now. ``restart``: its running widgets (and every fleet-wide
        one) are rebuilt on it; else they keep the old client's nodes (a Disconnect: they show their last
        values with LINK DOWN) and only what starts from now on uses ``client``. ``view_only``: the
        robot's view-only mark for the new link (a reason or None; False: unchanged)."""
        rid = self.fleet.resolve(robot_id)
        if view_only is not False:
            self.fleet.set_view_only(rid, view_only if isinstance(view_only, str) and view_only else None)
        if self.fleet.client(rid) is client:
            return
        old = self.fleet.client(rid)
        self._unlisten(rid)
        self.fleet.set_client(rid, client)
        self._checkers.pop(rid, None)
        if self.canvas is None:
            return
        self._listen(rid)
        if not restart:  # the running widgets keep their nodes but hear the new link's state
            self._on_state(rid, ConnectionState.CONNECTED if self._link_up.get(rid) else ConnectionState.CLOSED)
            return
        for inst in list(self.canvas.widgets):
            if inst.id in self.models and (self._robot_of.get(inst.id) == rid or inst.id in self._fleet_wide):
                self.restart_widget(inst)
        self.shared.forget(id(old))  # nobody is on the old link any more

    def add_widget(self, inst: WidgetInstance) -> HostedModel:
        return self._start_widget(inst)

    def remove_widget(self, widget_id: str) -> None:
        self._stop_widget(widget_id)

    def focus_lost(self) -> None:
        """Call ``on_focus_lost()`` of every model and of its child widgets (the window lost focus, the
        canvas is being left): a teleop widget stops driving. A model that raises is logged, the others
        still run."""
        for widget_id, model in list(self.models.items()):
            for m in (model, *model.child_models()):
                try:
                    m.on_focus_lost()
                except Exception as exc:
                    log.warning("widget %s failed on focus loss: %s", widget_id, exc)

    # -- one widget ----------------------------------------------------------------------------------
    def build_model(self, inst: WidgetInstance, port: Port) -> HostedModel:
        """The model for one instance (a placeholder when the plugin is missing or the build fails)."""
        try:
            spec = self.pm.widget(inst.kind)
        except UnknownWidget as exc:
            return MissingWidgetModel(inst, str(exc))
        try:
            settings = spec.make_settings(inst.settings)
        except SettingsError as exc:
            _log_once(logging.INFO, "widget %s (%s) is not configured: %s", inst.id, inst.kind, exc)
            return UnconfiguredWidgetModel(inst, exc.problems)
        except Exception as exc:
            log.warning("widget %s (%s) could not be built: %s", inst.id, inst.kind, exc)
            return BrokenWidgetModel(inst, f"{inst.kind}: {exc}")
        try:
            model_cls = spec.load_model()
            shared = spec.make_plugin_settings(self.plugin_settings.get(inst.kind))
            binding = Binding(
                inst.binding.name, inst.binding.type, inst.binding.role, inst.binding.field_paths
            )
            if binding.role not in spec.roles:
                roles = ", ".join(sorted(r.value for r in spec.roles))
                raise ValueError(f"{spec.title} cannot {binding.role.value} (it can: {roles})")
            context = WidgetContext(self.pm, port.link, self.shared)
            kwargs: dict[str, Any] = {"types": self.types, "plugin_settings": shared, "context": context}
            if self.dispatch is not None:
                kwargs["dispatch"] = self.dispatch
            model: HostedModel = model_cls(settings, binding, port, **kwargs)
            return model
        except Exception as exc:
            log.warning("widget %s (%s) could not be built: %s", inst.id, inst.kind, exc)
            return BrokenWidgetModel(inst, f"{inst.kind}: {exc}")

    def view_only_reason(self, canvas: Canvas | None = None, robot_id: str = "") -> str | None:
        """Why the widgets of ``canvas`` (default: the running one) on ``robot_id`` (``""``: the first)
        may not send anything, or None."""
        if self.view_only:
            return self.view_only
        try:
            reason = self.fleet.view_only_reason(robot_id)
        except UnknownRobot:
            reason = None
        if reason:
            return reason
        canvas = canvas if canvas is not None else self.canvas
        if canvas is not None and canvas.view_only:
            return f"canvas “{canvas.name}” is view-only"
        return None

    def _port(self, node: BridgeNode, widget_id: str, robot_id: str, built: list[HostedModel]) -> GuardedPort:
        """The model's only way to the robot (view-only enforced there, see canvas.port)."""
        notify = None
        if self.on_activity is not None:
            on_activity = self.on_activity

            def notify() -> None:
                on_activity(widget_id)

        def refused(text: str) -> None:
            for m in built:
                m.set_error(text)

        return GuardedPort(node, notify=notify, view_only=self.view_only_reason(robot_id=robot_id),
                           on_refused=refused, link=id(self.fleet.client(robot_id)), widget_id=widget_id)

    def _start_widget(self, inst: WidgetInstance) -> HostedModel:
        try:
            rid = self.fleet.resolve(inst.binding.robot)
        except UnknownRobot as exc:
            model: HostedModel = BrokenWidgetModel(inst, str(exc))
            self.models[inst.id] = model
            model.start()
            return model
        node = self.fleet.client(rid).node(inst.id)
        built: list[HostedModel] = []
        port = self._port(node, inst.id, rid, built)
        model = self.build_model(inst, port)
        built.append(model)
        self._nodes[inst.id] = [node]
        self._robot_of[inst.id] = rid
        self.models[inst.id] = model
        self._hook(inst.id, "set_link", model.set_link, self._link_up.get(rid, True))
        try:  # the widget boundary: every hook of a plugin's model may raise (see _hook)
            self._give_fleet(inst.id, model, rid, port, built)
            model.start()
        except Exception as exc:
            log.warning("widget %s (%s) failed to start: %s", inst.id, inst.kind, safe_text(exc))
            self._hook(inst.id, "set_error", model.set_error, f"could not start: {safe_text(exc)}")
            return model
        self._hook(inst.id, "the type check", self._check_type, inst.id, model)
        return model

    def _hook(self, widget_id: str, what: str, fn: Callable[..., Any], *args: Any) -> None:
        """Call one hook of one widget's model; what it raises is logged (bounded) and counted in
        ``hook_errors``, and the caller goes on with the other widgets."""
        try:
            fn(*args)
        except Exception as exc:
            self.hook_errors += 1
            _log_once(logging.WARNING, "widget %s failed in %s: %s", widget_id, what, safe_text(exc))

    def _give_fleet(self, widget_id: str, model: HostedModel, own: str, own_port: Port,
                    built: list[HostedModel]) -> None:
        """A fleet-wide model (it overrides ``on_fleet``) gets a port on every robot, and each robot's link
        state."""
        if not model.fleet_wide:
            return
        self._fleet_wide.add(widget_id)
        ports = []
        for robot, client in self.fleet.items():
            port: Port
            if robot.id == own:
                port = own_port
            else:
                node = client.node(widget_id)
                self._nodes[widget_id].append(node)
                port = self._port(node, widget_id, robot.id, built)
            ports.append(RobotPort(robot.id, robot.label, self.fleet.colour(robot.id), port))
        model.on_fleet(ports)
        self._tell_robot_link(model, None)

    # -- does the robot know the type? ---------------------------------------------------------------
    def _check_type(self, widget_id: str, model: HostedModel) -> None:
        """Ask the robot (once per type and connection) whether it knows a non-standard bound type."""
        b = model.binding
        if isinstance(model, MissingWidgetModel) or b.problems() or model.dry_run:
            return
        rid = self._robot_of.get(widget_id, "")
        client = self.fleet.client(rid)
        if getattr(client, "rosapi", None) is None:
            return
        try:
            loop = asyncio.get_running_loop()
        except RuntimeError:  # not on the bridge loop (a test building models by hand)
            return
        checker = self._checkers.get(rid)
        if checker is None or checker.client is not client:
            checker = self._checkers[rid] = TypeChecker(client)

        async def check() -> None:
            problem = await checker.problem(b.type, service=b.role.is_service)
            if problem and self.models.get(widget_id) is model:
                model.set_error(problem)
                self._notify(widget_id)

        task = loop.create_task(check())
        self._checks.add(task)
        task.add_done_callback(self._check_done)

    def _check_done(self, task: asyncio.Task[Any]) -> None:
        self._checks.discard(task)
        if not task.cancelled() and task.exception() is not None:
            log.warning("checking a widget's type failed: %s", task.exception())

    def _on_status(self, robot_id: str, frame: dict[str, Any]) -> None:
        """A ``status`` op of level error naming one of our subscribe/advertise ops (newer servers)."""
        failure = status_failure(frame)
        if failure is None:
            return
        topic, text = failure
        for widget_id, model in list(self.models.items()):
            if self._robot_of.get(widget_id) != robot_id:
                continue
            b = model.binding
            if b.name == topic and not b.role.is_service:
                self._hook(widget_id, "set_error", model.set_error, f"the robot refused {topic}: {text}")
                self._notify(widget_id)

    def _notify(self, widget_id: str) -> None:
        if self.on_activity is not None:
            try:
                self.on_activity(widget_id)
            except Exception:
                log.exception("activity listener failed")

    def _stop_widget(self, widget_id: str) -> None:
        model = self.models.pop(widget_id, None)
        nodes = self._nodes.pop(widget_id, [])
        self._robot_of.pop(widget_id, None)
        self._fleet_wide.discard(widget_id)
        if model is not None:
            try:
                model.stop()
            except Exception as exc:
                log.warning("widget %s failed to stop cleanly: %s", widget_id, exc)
        for node in nodes:
            try:
                node.close()
            except Exception as exc:
                log.warning("node of widget %s failed to close: %s", widget_id, exc)

    # -- link state ----------------------------------------------------------------------------------
    def link_up(self, robot_id: str = "") -> bool:
        """Whether ``robot_id``'s link is usable, as the runtime last heard."""
        return self._link_up.get(self.fleet.resolve(robot_id), True)

    def _listen(self, robot_id: str) -> None:
        if robot_id in self._remove:
            return
        client = self.fleet.client(robot_id)
        removers = []
        if hasattr(client, "add_state_listener"):
            removers.append(client.add_state_listener(lambda state: self._on_state(robot_id, state)))
        if hasattr(client, "add_status_listener"):
            removers.append(client.add_status_listener(lambda frame: self._on_status(robot_id, frame)))
        self._remove[robot_id] = [r for r in removers if callable(r)]
        self._link_up[robot_id] = _is_up(getattr(client, "state", ConnectionState.CONNECTED))

    def _unlisten(self, robot_id: str) -> None:
        for remove in self._remove.pop(robot_id, []):
            try:
                remove()
            except Exception:
                log.debug("removing a link listener failed", exc_info=True)

    def _on_state(self, robot_id: str, state: ConnectionState) -> None:
        """One robot's link state: only its own widgets hear it (and the fleet-wide ones, per robot)."""
        up = _is_up(state)
        if robot_id not in self._remove:  # an old client's late callback
            return
        self._link_up[robot_id] = up
        for widget_id, model in list(self.models.items()):
            if self._robot_of.get(widget_id) == robot_id:
                for m in (model, *model.child_models()):
                    self._hook(widget_id, "set_link", m.set_link, up)
            if widget_id in self._fleet_wide:
                self._tell_robot_link(model, robot_id)

    def _tell_robot_link(self, model: HostedModel, robot_id: str | None) -> None:
        for rid in [robot_id] if robot_id is not None else self.fleet.ids:
            try:
                model.on_robot_link(rid, self._link_up.get(rid, True))
            except Exception as exc:
                log.warning("a widget failed on robot %s's link state: %s", rid, exc)
