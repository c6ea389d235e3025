"""Running a canvas: one model per widget instance, each with its own node of the bridge client.

::

    rt = CanvasRuntime(plugin_manager, client, types=type_registry, plugin_settings=ws.plugin_settings)
    rt.start(canvas)            # builds and starts every widget's model
    rt.models[widget_id].state  # what the view paints
    rt.start(other_canvas)      # stops every widget of the old canvas (their subscriptions and
                                #   advertisements end on the server), starts the new one's
    rt.restart_widget(inst)     # after a reconfigure
    rt.focus_lost()             # the operator looked away: models' optional on_focus_lost() (teleop stops)
    rt.stop()                   # focus_lost() first, then every model stops

``on_activity(widget_id)`` (optional) is called on the loop thread right after a widget's model handled
an incoming message, service request or service response, so a front end can repaint at once instead of
polling on its next frame.

Every model gets a :class:`rcon_core.canvas.port.GuardedPort` onto its node, never the node itself.
``CanvasRuntime(..., view_only="reason")`` (the robot connection is view-only) or a canvas with
``view_only`` set makes those ports refuse to publish, call or serve (``rt.view_only_reason(canvas)``).

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

from rcon_core.bridge.typecheck import TypeChecker, status_failure
from rcon_core.plugins.manager import UnknownWidget
from rcon_core.plugins.model import Binding, WidgetModel
from rcon_core.plugins.spec import SettingsError

from .model import Canvas, WidgetInstance
from .port import GuardedPort

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


class _NoPort:
    """The port of a placeholder: refuses every use."""

    def __getattr__(self, name: str) -> Any:
        raise RuntimeError("a placeholder widget has no bridge port")


class MissingWidgetModel(WidgetModel):
    """Stands in for a widget whose plugin is not installed (or disabled). Never subscribes."""

    stale_after = None

    def __init__(self, instance: WidgetInstance, reason: str) -> None:
        super().__init__(None, instance.binding, _NoPort())
        self.kind = instance.kind
        self.reason = reason
        self.set_error(reason)

    def start(self) -> None:
        with self._lock:
            self._running = True
            self._seq += 1

    def stop(self) -> None:
        with self._lock:
            self._running = False
            self._seq += 1

    def problems(self) -> list[str]:
        return [self.reason]


class BrokenWidgetModel(MissingWidgetModel):
    """Stands in for a widget whose model could not be built; ``reason`` says why."""


class UnconfiguredWidgetModel(MissingWidgetModel):
    """Stands in for a widget whose stored settings cannot be read (a value of the wrong type): not an
    error but the "not configured" warning, one sentence per bad value (``problems()``)."""

    def __init__(self, instance: WidgetInstance, problems: list[str]) -> None:
        WidgetModel.__init__(self, None, instance.binding, _NoPort())
        self.kind = instance.kind
        self.reason = "; ".join(problems)
        self._problems = list(problems)

    def problems(self) -> list[str]:
        return list(self._problems)


class CanvasRuntime:
    """Creates, starts and stops the models of one canvas at a time."""

    def __init__(
        self,
        plugin_manager: Any,
        client: Any,
        *,
        types: Any = None,
        plugin_settings: dict[str, dict[str, Any]] | None = None,
        dispatch: Callable[[Callable[[], Any]], Any] | None = None,
        on_activity: Callable[[str], Any] | None = None,
        view_only: str | None = None,
    ) -> None:
        self.pm = plugin_manager
        #: the robot connection is view-only: why (None: it may be commanded); see :meth:`view_only_reason`
        self.view_only = view_only
        self.on_activity = on_activity
        self.client = client
        self.types = types
        self.plugin_settings = plugin_settings if plugin_settings is not None else {}
        self.dispatch = dispatch
        self.canvas: Canvas | None = None
        self.models: dict[str, WidgetModel] = {}
        self._nodes: dict[str, Any] = {}
        self._remove_listener: Callable[[], None] | None = None
        self._remove_status_listener: Callable[[], None] | None = None
        self._link_up = True
        self._checker: TypeChecker | None = None
        self._checks: set[asyncio.Task[Any]] = set()

    # -- lifecycle -----------------------------------------------------------------------------------
    def start(self, canvas: Canvas) -> None:
        """Build and start every widget of ``canvas`` (stopping the current canvas first, if any)."""
        if self.canvas is not None:
            self.stop()
        self.canvas = canvas
        if self._remove_listener is None and hasattr(self.client, "add_state_listener"):
            self._remove_listener = self.client.add_state_listener(self._on_state)
        if self._remove_status_listener is None and hasattr(self.client, "add_status_listener"):
            self._remove_status_listener = self.client.add_status_listener(self._on_status)
        self._link_up = self._client_up()
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
        if self._remove_listener is not None:
            self._remove_listener()
            self._remove_listener = None
        if self._remove_status_listener is not None:
            self._remove_status_listener()
            self._remove_status_listener = None

    def restart_widget(self, inst: WidgetInstance) -> WidgetModel:
        """Rebuild one widget's model (after its settings or binding changed)."""
        self._stop_widget(inst.id)
        return self._start_widget(inst)

    def add_widget(self, inst: WidgetInstance) -> WidgetModel:
        return self._start_widget(inst)

    def remove_widget(self, widget_id: str) -> None:
        self._stop_widget(widget_id)

    def focus_lost(self) -> None:
        """Call the optional ``on_focus_lost()`` of every model (the window lost focus, the canvas is
        being left): a teleop widget stops driving. A model that raises is logged, the others still run."""
        for widget_id, model in list(self.models.items()):
            hook = getattr(model, "on_focus_lost", None)
            if callable(hook):
                try:
                    hook()
                except Exception as exc:
                    log.warning("widget %s failed on focus loss: %s", widget_id, exc)

    # -- one widget ----------------------------------------------------------------------------------
    def build_model(self, inst: WidgetInstance, port: Any) -> WidgetModel:
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
            kwargs: dict[str, Any] = {"types": self.types, "plugin_settings": shared}
            if self.dispatch is not None:
                kwargs["dispatch"] = self.dispatch
            return model_cls(settings, binding, port, **kwargs)
        except Exception as exc:
            log.warning("widget %s (%s) could not be built: %s", inst.id, inst.kind, exc)
            return BrokenWidgetModel(inst, f"{inst.kind}: {exc}")

    def view_only_reason(self, canvas: Canvas | None = None) -> str | None:
        """Why the widgets of ``canvas`` (default: the running one) may not send anything, or None."""
        if self.view_only:
            return self.view_only
        canvas = canvas if canvas is not None else self.canvas
        if canvas is not None and canvas.view_only:
            return f"canvas “{canvas.name}” is view-only"
        return None

    def _start_widget(self, inst: WidgetInstance) -> WidgetModel:
        node = self.client.node(inst.id)
        built: list[WidgetModel] = []
        notify = None
        if self.on_activity is not None:
            on_activity, widget_id = self.on_activity, inst.id

            def notify() -> None:
                on_activity(widget_id)

        def refused(text: str) -> None:
            for m in built:
                m.set_error(text)

        # the model never gets the node itself: only this port (view-only enforced here, see canvas.port)
        port = GuardedPort(node, notify=notify, view_only=self.view_only_reason(), on_refused=refused,
                           link=id(self.client), widget_id=inst.id)
        model = self.build_model(inst, port)
        built.append(model)
        self._nodes[inst.id] = node
        self.models[inst.id] = model
        model.set_link(self._link_up)
        try:
            model.start()
        except Exception as exc:
            log.warning("widget %s (%s) failed to start: %s", inst.id, inst.kind, exc)
            model.set_error(f"could not start: {exc}")
            return model
        self._check_type(inst.id, model)
        return model

    # -- does the robot know the type? ---------------------------------------------------------------
    def _check_type(self, widget_id: str, model: WidgetModel) -> None:
        """Ask the robot (once per type and connection) whether it knows a non-standard bound type."""
        b = model.binding
        if isinstance(model, MissingWidgetModel) or b.problems() or getattr(model, "dry_run", False):
            return
        if getattr(self.client, "rosapi", None) is None:
            return
        try:
            loop = asyncio.get_running_loop()
        except RuntimeError:  # not on the bridge loop (a test building models by hand)
            return
        if self._checker is None or self._checker.client is not self.client:
            self._checker = TypeChecker(self.client)
        checker = self._checker

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

    def _on_status(self, frame: dict[str, Any]) -> None:
        """A ``status`` op of level error naming one of our subscribe/advertise ops (newer servers)."""
        failure = status_failure(frame)
        if failure is None:
            return
        topic, text = failure
        for widget_id, model in list(self.models.items()):
            if model.binding.name == topic and not model.binding.role.is_service:
                model.set_error(f"the robot refused {topic}: {text}")
                self._notify(widget_id)

    def _notify(self, widget_id: str) -> None:
        if self.on_activity is not None:
            try:
                self.on_activity(widget_id)
            except Exception:
                log.exception("activity listener failed")

    def _stop_widget(self, widget_id: str) -> None:
        model = self.models.pop(widget_id, None)
        node = self._nodes.pop(widget_id, None)
        if model is not None:
            try:
                model.stop()
            except Exception as exc:
                log.warning("widget %s failed to stop cleanly: %s", widget_id, exc)
        if node is not None:
            try:
                node.close()
            except Exception as exc:
                log.warning("node of widget %s failed to close: %s", widget_id, exc)

    # -- link state ----------------------------------------------------------------------------------
    def _client_up(self) -> bool:
        state = getattr(self.client, "state", None)
        return getattr(state, "value", "connected") == "connected"

    def _on_state(self, state: Any) -> None:
        up = getattr(state, "value", state) == "connected"
        self._link_up = up
        for model in self.models.values():
            model.set_link(up)
