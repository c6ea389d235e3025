"""Running a canvas: one model per widget instance, each with its own node of the bridge client.

::

    rt = CanvasRuntime(plugin_manager, client, types=type_registry, plugin_settings=ws.plugin_settings)
    rt.start(canvas)            # builds and starts every widget's model
    rt.models[widget_id].state  # what the view paints
    rt.switch(other_canvas)     # stops every widget of the old canvas (their subscriptions and
                                #   advertisements end on the server), starts the new one's
    rt.restart_widget(inst)     # after a reconfigure
    rt.focus_lost()             # the operator looked away: models' optional on_focus_lost() (teleop stops)
    rt.stop()                   # focus_lost() first, then every model stops

``on_activity(widget_id)`` (optional) is called on the loop thread right after a widget's model handled
an incoming message, service request or service response, so a front end can repaint at once instead of
polling on its next frame.

Call these on the bridge loop thread (from the GUI: ``bridge_thread.call(rt.switch, canvas)``); pass
``dispatch=bridge_thread.call`` so the models' GUI-side actions reach the loop thread too.

A widget whose plugin is missing gets a :class:`MissingWidgetModel` (shows why, talks to nobody); a
widget whose model cannot be built (bad settings, import error) gets a :class:`BrokenWidgetModel`; the
other widgets run either way. The instance data is never touched, so it saves back unchanged.
"""

from __future__ import annotations

import asyncio
import inspect
import logging
from collections.abc import Callable
from typing import Any

from rcon_core.plugins.manager import UnknownWidget
from rcon_core.plugins.model import Binding, WidgetModel

from .model import Canvas, WidgetInstance

__all__ = ["CanvasRuntime", "MissingWidgetModel", "BrokenWidgetModel"]

log = logging.getLogger(__name__)


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


class _WatchedPort:
    """A widget's node that reports activity after each incoming message, request or response."""

    def __init__(self, node: Any, notify: Callable[[], None]) -> None:
        self._node = node
        self._notify = notify

    def _ping(self) -> None:
        try:
            self._notify()
        except Exception:
            log.exception("activity listener failed")

    def subscribe(self, topic: str, callback: Callable[[Any], Any], **options: Any) -> Any:
        def watched(msg: Any) -> Any:
            try:
                return callback(msg)
            finally:
                self._ping()

        return self._node.subscribe(topic, watched, **options)

    def advertise_service(self, name: str, type: str, handler: Callable[[Any], Any]) -> Any:
        def watched(request: Any) -> Any:
            result = handler(request)
            if inspect.isawaitable(result):
                async def finish() -> Any:
                    try:
                        return await result
                    finally:
                        self._ping()

                return finish()
            self._ping()
            return result

        return self._node.advertise_service(name, type, watched)

    async def call_service(self, name: str, args: Any = None, timeout: float | None = None) -> Any:
        try:
            return await self._node.call_service(name, args, timeout=timeout)
        finally:
            # after the caller's on_response, which runs in the same task step as this return
            asyncio.get_running_loop().call_soon(self._ping)

    def send_action_goal(self, action: str, action_type: str, args: Any = None,
                         feedback: Callable[[Any], Any] | None = None, **options: Any) -> Any:
        watched = None
        if feedback is not None:
            def watched(values: Any) -> Any:
                try:
                    return feedback(values)
                finally:
                    self._ping()

        return self._node.send_action_goal(action, action_type, args, feedback=watched, **options)

    def __getattr__(self, name: str) -> Any:  # advertise, close, ...
        return getattr(self._node, name)


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
    ) -> None:
        self.pm = plugin_manager
        self.on_activity = on_activity
        self.client = client
        self.types = types
        self.plugin_settings = plugin_settings if plugin_settings is not None else {}
        self.dispatch = dispatch
        self.canvas: Canvas | None = None
        self.models: dict[str, WidgetModel] = {}
        self._nodes: dict[str, Any] = {}
        self._remove_listener: Callable[[], None] | None = None
        self._link_up = True

    # -- lifecycle -----------------------------------------------------------------------------------
    def start(self, canvas: Canvas) -> None:
        """Build and start every widget of ``canvas`` (stopping the current canvas first, if any)."""
        if self.canvas is not None:
            self.stop()
        self.canvas = canvas
        if self._remove_listener is None and hasattr(self.client, "add_state_listener"):
            self._remove_listener = self.client.add_state_listener(self._on_state)
        self._link_up = self._client_up()
        for inst in canvas.widgets:
            self._start_widget(inst)

    def stop(self) -> None:
        """Tell the models focus is lost, stop every one and close its node (ending what it forgot)."""
        self.focus_lost()
        for widget_id in list(self.models):
            self._stop_widget(widget_id)
        self.canvas = None
        if self._remove_listener is not None:
            self._remove_listener()
            self._remove_listener = None

    def switch(self, canvas: Canvas) -> None:
        """Stop the current canvas's widgets and start ``canvas``'s."""
        self.start(canvas)

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
            model_cls = spec.load_model()
            settings = spec.make_settings(inst.settings)
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

    def _start_widget(self, inst: WidgetInstance) -> WidgetModel:
        node = self.client.node(inst.id)
        port = node
        if self.on_activity is not None:
            notify, widget_id = self.on_activity, inst.id
            port = _WatchedPort(node, lambda: notify(widget_id))
        model = self.build_model(inst, port)
        self._nodes[inst.id] = node
        self.models[inst.id] = model
        model.set_link(self._link_up)
        try:
            model.start()
        except Exception as exc:
            log.warning("widget %s (%s) failed to start: %s", inst.id, inst.kind, exc)
            model.set_error(f"could not start: {exc}")
        return model

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
