"""Builds widget instances (model + view inside a frame) and paints them once per frame.

Models live on the bridge thread: they are started, stopped and fed there.  The GUI thread only reads
``model.state`` (a snapshot) and repaints a view when ``state.seq`` moved.  Each frame gets a time budget;
views are visited round-robin so a slow view delays the others by at most one frame, never more.
"""

from __future__ import annotations

import logging
import time
from typing import Any

from qtpy import QtWidgets

from rcon_core.app.layout import Instance
from rcon_core.app.link import Link
from rcon_core.app.widget_frame import WidgetFrame
from rcon_core.plugins import Binding, PluginManager, SettingsError, SpecError, UnknownWidget

log = logging.getLogger(__name__)

#: seconds of GUI work per frame spent refreshing views before the rest waits for the next frame
FRAME_BUDGET = 0.010


class Hosted:
    """One live widget: its frame, model and view."""

    __slots__ = ("instance", "frame", "model", "view", "painted_seq", "problems", "running")

    def __init__(self, instance: Instance, frame: WidgetFrame) -> None:
        self.instance = instance
        self.frame = frame
        self.model: Any = None
        self.view: Any = None
        self.painted_seq = -1
        self.problems: list[str] = []
        self.running = False


def make_view(view_cls: type, model: Any) -> QtWidgets.QWidget:
    """Views are built as ``View(model)``; a view may also accept ``View(model, parent)``."""
    return view_cls(model)


class WidgetHost:
    """Owns the models and views of the instances shown on canvases."""

    def __init__(self, plugins: PluginManager, link: Link, types: Any = None) -> None:
        self.plugins = plugins
        self.link = link
        self.types = types
        self.hosted: dict[str, Hosted] = {}
        self._order: list[str] = []
        self._cursor = 0
        self._link_up = False
        self.paint_hooks: list[Any] = []  # benchmark: fn(hosted, state) after each refresh

    # -------------------------------------------------------------------------------------- building
    def build(self, instance: Instance) -> WidgetFrame:
        """A frame for ``instance`` with its view, or a placeholder saying why there is none."""
        title = instance.title or instance.kind
        frame = WidgetFrame(instance.id, title)
        hosted = Hosted(instance, frame)
        self.hosted[instance.id] = hosted
        self._order.append(instance.id)
        self._populate(hosted)
        return frame

    def _populate(self, hosted: Hosted) -> None:
        instance, frame = hosted.instance, hosted.frame
        try:
            spec = self.plugins.widget(instance.kind)
        except UnknownWidget:
            frame.set_placeholder(f"Widget “{instance.kind}” is not installed.\nIts settings are kept.")
            hosted.problems = []
            return
        try:
            settings = spec.make_settings(instance.settings)
            model_cls = spec.load_model()
            hosted.model = self._new_model(model_cls, settings, instance.binding, instance.id, spec)
            view_cls = spec.load_view()
            hosted.view = make_view(view_cls, hosted.model)
            frame.set_view(hosted.view)
        except (SettingsError, SpecError, Exception) as exc:  # a broken plugin must not break the app
            log.warning("widget %s (%s) failed to build: %s", instance.id, instance.kind, exc)
            hosted.model = None if hosted.view is None else hosted.model
            frame.set_placeholder(f"{spec.title} could not be shown:\n{exc}")
            return
        hosted.problems = list(hosted.model.problems()) if hasattr(hosted.model, "problems") else []
        frame.problems.set_problems(hosted.problems)

    def _new_model(self, model_cls: type, settings: Any, binding: Binding, node_id: str, spec: Any) -> Any:
        client = self.link.client
        port = client.node(node_id) if client is not None else _OfflinePort()
        plugin_settings = None
        try:
            plugin_settings = spec.make_plugin_settings({})
        except Exception:
            plugin_settings = None
        return model_cls(
            settings, binding, port, types=self.types, plugin_settings=plugin_settings,
            dispatch=self.link.thread.call,
        )

    def rebuild(self, instance_id: str) -> None:
        """Re-create model and view of one instance (after its settings changed or the client did)."""
        hosted = self.hosted.get(instance_id)
        if hosted is None:
            return
        was_running = hosted.running
        self.stop([instance_id])
        self._close_port(hosted)
        hosted.model = hosted.view = None
        hosted.painted_seq = -1
        self._populate(hosted)
        if was_running:
            self.start([instance_id])

    def rebuild_all(self) -> None:
        for iid in list(self.hosted):
            self.rebuild(iid)

    def discard(self, instance_id: str) -> None:
        hosted = self.hosted.pop(instance_id, None)
        if hosted is None:
            return
        self._order.remove(instance_id)
        self._stop_hosted(hosted)
        self._close_port(hosted)

    # ------------------------------------------------------------------------------------ lifecycle
    def start(self, ids: list[str]) -> None:
        """Start these instances' models on the bridge thread (only when connected to a client)."""
        for iid in ids:
            hosted = self.hosted.get(iid)
            if hosted is None or hosted.model is None or hosted.running:
                continue
            if self.link.client is None:
                continue
            hosted.running = True
            model = hosted.model
            self.link.thread.call(_safe, model.start)
            self.link.thread.call(_safe, model.set_link, self._link_up)

    def stop(self, ids: list[str]) -> None:
        for iid in ids:
            hosted = self.hosted.get(iid)
            if hosted is not None:
                self._stop_hosted(hosted)

    def _stop_hosted(self, hosted: Hosted) -> None:
        if hosted.running and hosted.model is not None:
            self.link.thread.call(_safe, hosted.model.stop)
        hosted.running = False

    def _close_port(self, hosted: Hosted) -> None:
        port = getattr(hosted.model, "port", None)
        if port is not None and not isinstance(port, _OfflinePort):
            self.link.thread.call(_safe, port.close)

    def running_ids(self) -> list[str]:
        return [iid for iid, h in self.hosted.items() if h.running]

    def set_link_up(self, up: bool) -> None:
        self._link_up = up
        for hosted in self.hosted.values():
            if hosted.model is not None and hasattr(hosted.model, "set_link"):
                hosted.model.set_link(up)

    # ------------------------------------------------------------------------------------ per frame
    def tick(self, _now: float = 0.0) -> None:
        """Refresh the views whose model changed, within the frame budget, fairly."""
        order = [iid for iid in self._order if self.hosted[iid].running or self.hosted[iid].model is not None]
        n = len(order)
        if not n:
            return
        deadline = time.perf_counter() + FRAME_BUDGET
        start = self._cursor % n
        for k in range(n):
            hosted = self.hosted[order[(start + k) % n]]
            shown = hosted.view if hosted.view is not None else hosted.frame
            if not shown.isVisible():
                continue
            self._refresh(hosted)
            if time.perf_counter() > deadline:
                self._cursor = (start + k + 1) % n
                return
        self._cursor = 0

    def _refresh(self, hosted: Hosted) -> None:
        model = hosted.model
        if model is None:
            return
        state = model.state
        badge = hosted.frame.badge
        if state.link_down or not self._link_up:
            badge.show_status("down", "LINK DOWN")
        elif state.error:
            badge.show_status("problem", "ERROR")
            badge.setToolTip(state.error)
        elif state.stale:
            badge.show_status("stale", "STALE" if state.count else "NO DATA")
        else:
            badge.show_status("", "")
        if state.seq == hosted.painted_seq:
            return
        hosted.painted_seq = state.seq
        view = hosted.view
        refresh = getattr(view, "refresh", None)
        if refresh is not None:
            refresh(state)
        elif view is not None:
            view.update()
        for hook in self.paint_hooks:
            hook(hosted, state)

    def topic_counts(self) -> dict[str, int]:
        """Values received per subscribed topic (summed over widgets), for the topic list's rates."""
        out: dict[str, int] = {}
        for hosted in self.hosted.values():
            if hosted.running and hosted.model is not None and hosted.instance.binding.role.value == "subscribe":
                name = hosted.instance.binding.name
                out[name] = max(out.get(name, 0), hosted.model.state.count)
        return out


def _safe(fn: Any, *args: Any) -> None:
    try:
        fn(*args)
    except Exception:
        log.exception("widget lifecycle call failed")


class _OfflinePort:
    """The port a model gets while there is no client: every request says so."""

    def subscribe(self, *_a: Any, **_k: Any) -> Any:
        raise RuntimeError("not connected to a robot")

    advertise = advertise_service = subscribe

    async def call_service(self, *_a: Any, **_k: Any) -> Any:
        raise RuntimeError("not connected to a robot")

    def close(self) -> None:
        pass


class RateMeter:
    """Turns growing per-topic counters into messages per second (sampled about once a second)."""

    def __init__(self) -> None:
        self._last: dict[str, tuple[float, int]] = {}
        self.rates: dict[str, float] = {}

    def sample(self, counts: dict[str, int], now: float | None = None) -> dict[str, float]:
        now = time.monotonic() if now is None else now
        rates: dict[str, float] = {}
        for topic, count in counts.items():
            prev = self._last.get(topic)
            if prev is not None and now > prev[0] and count >= prev[1]:
                rates[topic] = (count - prev[1]) / (now - prev[0])
            self._last[topic] = (now, count)
        for topic in list(self._last):
            if topic not in counts:
                del self._last[topic]
        self.rates = rates
        return rates



class PreviewHost:
    """The live preview of a draft in the add panel: one model + view, started when it can be."""

    def __init__(self, host: WidgetHost) -> None:
        self.host = host
        self.hosted: Hosted | None = None

    def build(self, draft: Any) -> QtWidgets.QWidget:
        self.release()
        instance = Instance(
            kind=draft.spec.kind, binding=draft.binding, settings=draft.settings_dict(), title=draft.title,
            id=f"preview-{draft.spec.kind}",
        )
        frame_holder = WidgetFrame(instance.id, instance.title)  # only used for its badge/overlay logic
        hosted = Hosted(instance, frame_holder)
        self.hosted = hosted
        self.host.hosted[instance.id] = hosted
        self.host._order.append(instance.id)
        self.host._populate(hosted)
        view = frame_holder.view
        if view is not None:
            frame_holder.body_layout.removeWidget(view)
            view.setParent(None)
        if not draft.problems():
            self.host.start([instance.id])
        return view if view is not None else QtWidgets.QLabel("no preview")

    def release(self) -> None:
        if self.hosted is not None:
            iid = self.hosted.instance.id
            self.hosted.frame.deleteLater()
            self.host.discard(iid)
            self.hosted = None
