"""The GUI's handle on the canvas runtime, which lives on the bridge thread.

:class:`rcon_core.canvas.runtime.CanvasRuntime` builds, starts and stops the widget models of one canvas.
It must run on the bridge loop thread, so every request the GUI makes here (show a canvas, add, remove or
restart a widget, focus lost) is handed to that thread in order, with snapshots of the instances (the
GUI keeps editing its own copies). The models the runtime builds come back through :meth:`take_updates`,
and ``notify`` is called (on the bridge thread) whenever there is something new for the GUI: a batch of
models, or a widget whose model just took a message. The GUI thread never waits on the bridge thread.
"""

from __future__ import annotations

import copy
import logging
from collections import deque
from collections.abc import Callable
from typing import Any

import attrs

from rcon_core.canvas import Canvas, WidgetInstance
from rcon_core.canvas.runtime import CanvasRuntime
from rcon_core.plugins.api import HostedModel

log = logging.getLogger(__name__)

@attrs.frozen
class Reset:
    """A whole canvas (re)started: every widget's model (None for the widgets that stopped)."""

    models: dict[str, HostedModel | None]


@attrs.frozen
class One:
    """One widget was added, rebuilt or removed (``model`` None)."""

    widget_id: str
    model: HostedModel | None


#: an update for the GUI
Update = Reset | One


class LiveCanvas:
    """Runs one canvas at a time through a :class:`CanvasRuntime` on the bridge thread."""

    def __init__(
        self,
        plugins: Any,
        thread: Any,
        *,
        types: Any = None,
        notify: Callable[[str | None], Any] | None = None,
    ) -> None:
        self.plugins = plugins
        self.thread = thread
        self.types = types
        self.notify = notify or (lambda _widget_id: None)
        self._updates: deque[Update] = deque()  # appended on the bridge thread, drained by the GUI
        self._rt: CanvasRuntime | None = None  # touched on the bridge thread only
        self.running = False

    # ---------------------------------------------------------------------------------- GUI thread
    def start(self, client: Any, canvas: Canvas, plugin_settings: dict[str, Any] | None = None, *,
              view_only: str | None = None) -> None:
        """(Re)build the runtime on ``client`` and start ``canvas`` (replacing whatever ran before);
        ``view_only``: why the robot connection may not be commanded (see ``rcon_core.canvas.port``)."""
        self.running = True
        snap, shared = copy.deepcopy(canvas), copy.deepcopy(plugin_settings or {})
        self._send(self._loop_start, client, snap, shared, view_only)

    def switch(self, canvas: Canvas) -> None:
        """Stop the running canvas's widgets (after telling them focus is lost), start ``canvas``'s."""
        self._send(self._loop_switch, copy.deepcopy(canvas))

    def add(self, widget: WidgetInstance) -> None:
        self._send(self._loop_add, copy.deepcopy(widget), False)

    def restart(self, widget: WidgetInstance) -> None:
        self._send(self._loop_add, copy.deepcopy(widget), True)

    def remove(self, widget_id: str) -> None:
        self._send(self._loop_remove, widget_id)

    def focus_lost(self) -> None:
        """Tell the running models the operator's attention left (their optional ``on_focus_lost``)."""
        self._send(self._loop_focus_lost)

    def keep_running_offline(self, client: Any) -> None:
        """The link was closed on purpose (Disconnect): the running widgets keep their models and views, so
        they show their last values with LINK DOWN, then STALE, as after a lost link; whatever starts from
        now on (another canvas, an added or reconfigured widget) is built on ``client`` (offline)."""
        self._send(self._loop_offline, client)

    def set_client(self, robot_id: str, client: Any, *, keep: bool = False,
                   view_only: str | None | bool = False) -> None:
        """``robot_id``'s link is ``client`` now: only that robot's widgets (and fleet-wide ones such as
        the map of every robot) are rebuilt on it. ``keep``: they keep their models and last values (a
        Disconnect: LINK DOWN, then STALE) and only what starts from now on uses ``client``.
        ``view_only``: the robot's view-only mark on the new link (a reason or None; False: unchanged)."""
        self._send(self._loop_set_client, robot_id, client, keep, view_only)

    def stop(self) -> None:
        """Stop every widget (returns at once; the stop runs on the bridge thread)."""
        self.running = False
        self._send(self._loop_stop)

    def _send(self, fn: Callable[..., Any], *args: Any) -> None:
        try:
            self.thread.call(self._safe, fn, *args)
        except RuntimeError:  # the bridge thread has stopped (the window is closing): nothing runs
            log.debug("bridge thread stopped; %s dropped", getattr(fn, "__name__", fn))

    def take_updates(self) -> list[Update]:
        out = []
        while self._updates:
            out.append(self._updates.popleft())
        return out

    # ------------------------------------------------------------------------------- bridge thread
    def _safe(self, fn: Callable[..., Any], *args: Any) -> None:
        try:
            fn(*args)
        except Exception:
            log.exception("canvas runtime request failed")

    def _post(self, update: Update) -> None:
        self._updates.append(update)
        self.notify(None)

    def _post_reset(self, before: set[str]) -> None:
        models: dict[str, HostedModel | None] = dict.fromkeys(before)
        if self._rt is not None:
            models.update(self._rt.models)
        self._post(Reset(models))

    def _dispatch(self, fn: Callable[[], Any]) -> Any:
        """A model's GUI-side action (a finger lifted, a tap) to the loop thread. Once the app has stopped
        the thread (quitting), every model has stopped and sent its stop: a view hidden or unfocused after
        it (a finger still on the pad) has nothing to send, and raising here would escape a Qt handler."""
        if not self.thread.running:
            log.debug("a widget's action after the bridge thread stopped: dropped")
            return None
        return self.thread.call(fn)

    def _running_ids(self) -> set[str]:
        return set(self._rt.models) if self._rt is not None else set()

    def _loop_start(self, client: Any, canvas: Canvas, shared: dict[str, Any], view_only: str | None) -> None:
        before = self._running_ids()
        if self._rt is not None:
            self._rt.stop()
        self._rt = CanvasRuntime(
            self.plugins, client, types=self.types, plugin_settings=shared, dispatch=self._dispatch,
            on_activity=self.notify, view_only=view_only,
        )
        self._rt.start(canvas)
        self._post_reset(before)

    def _loop_switch(self, canvas: Canvas) -> None:
        if self._rt is None:
            return
        before = self._running_ids()
        self._rt.start(canvas)
        self._post_reset(before)

    def _loop_add(self, widget: WidgetInstance, restart: bool) -> None:
        if self._rt is None or self._rt.canvas is None:
            return
        model = self._rt.restart_widget(widget) if restart else self._rt.add_widget(widget)
        self._post(One(widget.id, model))

    def _loop_remove(self, widget_id: str) -> None:
        if self._rt is None:
            return
        self._rt.remove_widget(widget_id)
        self._post(One(widget_id, None))

    def _loop_focus_lost(self) -> None:
        if self._rt is not None:
            self._rt.focus_lost()

    def _loop_offline(self, client: Any) -> None:
        if self._rt is not None:
            self._rt.client = client

    def _loop_set_client(self, robot_id: str, client: Any, keep: bool, view_only: str | None | bool) -> None:
        if self._rt is None or robot_id not in self._rt.fleet:  # a robot the next start brings in
            return
        before = self._running_ids()
        self._rt.set_client(robot_id, client, restart=not keep, view_only=view_only)
        if not keep:
            self._post_reset(before)

    def _loop_stop(self) -> None:
        before = self._running_ids()
        if self._rt is not None:
            self._rt.stop()
            self._rt = None
        self._post_reset(before)
