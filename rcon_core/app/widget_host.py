"""The Qt side of the widgets: a frame per instance, a view per running model, painting.

Models are built, started and stopped by the canvas runtime on the bridge thread (see
:mod:`rcon_core.app.live`); they arrive here through :meth:`WidgetHost.attach`, and the host builds their
views (``View(model)``). Per pass it reads ``model.state`` (a snapshot) and calls ``view.refresh(state)``
only when ``state.seq`` moved, and for each widget at most once per frame interval (latest value wins:
a widget that changed too soon is refreshed when its interval is over). All decoding happens in the
models, on the bridge thread; the host never does more than ``view.refresh(state)``.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Iterable
from typing import Any

from rcon_core.app.accessibility import name_parts
from rcon_core.app.live import Reset, Update
from rcon_core.app.widget_frame import WidgetFrame
from rcon_core.bridge.safety import safe_text
from rcon_core.canvas import WidgetInstance
from rcon_core.canvas.runtime import BrokenWidgetModel, MissingWidgetModel, UnconfiguredWidgetModel
from rcon_core.plugins import PluginManager, Role, UnknownWidget
from rcon_core.plugins.api import HostedModel, WidgetView

log = logging.getLogger(__name__)

#: seconds of GUI work per pass spent refreshing views before the rest waits for the next pass
FRAME_BUDGET = 0.010
#: a view is refreshed at most once per this many seconds (one display frame)
FRAME_INTERVAL = 1 / 60


class Hosted:
    """One widget instance on a canvas: its frame, and its model and view while its canvas runs."""

    __slots__ = ("widget", "frame", "model", "view", "refreshes", "painted_seq", "painted_at", "view_error",
                 "hook_error")

    def __init__(self, widget: WidgetInstance, frame: WidgetFrame) -> None:
        self.widget = widget
        self.frame = frame
        self.model: HostedModel | None = None
        self.view: Any = None
        #: the view has ``refresh(state)`` (the ``WidgetView`` protocol); else the host calls its ``update()``
        self.refreshes = False
        self.painted_seq = -1
        self.painted_at = 0.0
        #: why the view failed to show the last state (its ``refresh`` raised), until one succeeds
        self.view_error: str | None = None
        #: why another hook of the widget raised (``problems()``, ``view_only``...), until it is attached again
        self.hook_error: str | None = None


class WidgetHost:
    """Owns the frames of every instance and the views of the running ones."""

    def __init__(self, plugins: PluginManager) -> None:
        self.plugins = plugins
        self.hosted: dict[str, Hosted] = {}
        #: moves whenever a widget's model is attached, replaced or dropped (what depends on the models,
        #: e.g. the robot marks, looks again)
        self.models_version = 0
        #: views whose ``refresh`` raised (each counted, logged, shown on its badge; the others go on)
        self.view_errors = 0
        #: other hooks of a widget that raised (``problems()``, ``view_only``, attaching it...), counted the same
        self.hook_errors = 0
        self._view_error_counts: dict[str, int] = {}
        self._cursor = 0
        self._link_up = False
        #: several robots: each robot's link, by robot id; a widget's robot is its binding's (``""``:
        #: :attr:`first_robot`). A robot not listed follows the one-robot flag (set_link_up(up)).
        self.links_up: dict[str, bool] = {}
        self.first_robot = ""
        #: widget id -> (robot name, colour) on a canvas that mixes robots (see robot_marks.py)
        self.robot_marks: dict[str, tuple[str, str]] = {}
        self._due: set[str] = set()  # changed, but refreshed less than a frame ago
        self.paint_hooks: list[Any] = []  # benchmark: fn(hosted, state) after each refresh
        #: widgets run offline on purpose (previews of controls): no LINK DOWN, a PREVIEW ONLY badge
        self.dry_run: set[str] = set()

    # -------------------------------------------------------------------------------------- frames
    def build_frame(self, widget: WidgetInstance, frame: WidgetFrame | None = None) -> WidgetFrame:
        """The frame for ``widget`` (empty until its model arrives); an existing frame may be given."""
        frame = frame or WidgetFrame(widget.id, self.title_of(widget))
        self.hosted[widget.id] = Hosted(widget, frame)
        if not self.plugins.has_widget(widget.kind):
            frame.set_placeholder(_not_installed(widget.kind))
        return frame

    def update_widget(self, widget: WidgetInstance) -> None:
        """The instance changed (title, geometry, settings): keep the host's copy in step."""
        hosted = self.hosted.get(widget.id)
        if hosted is not None:
            hosted.widget = widget
            hosted.frame.set_title(self.title_of(widget))

    def title_of(self, widget: WidgetInstance) -> str:
        """The frame's title: the widget's, after its robot's name when its canvas mixes robots."""
        title = widget.title or widget.kind
        mark = self.robot_marks.get(widget.id)
        return f"{mark[0]} · {title}" if mark else title

    def discard(self, widget_id: str) -> None:
        """Forget a widget (its frame is removed by its surface)."""
        self.hosted.pop(widget_id, None)
        self._due.discard(widget_id)

    # -------------------------------------------------------------------------------------- models
    def apply(self, updates: Iterable[Update]) -> None:
        """Take the runtime's updates (see :class:`rcon_core.app.live.LiveCanvas`), in order."""
        for update in updates:
            pairs = update.models.items() if isinstance(update, Reset) else [(update.widget_id, update.model)]
            for widget_id, model in pairs:
                try:  # the widget boundary: one widget that cannot be attached leaves the others alone
                    self.attach(widget_id, model)
                except Exception as exc:
                    hosted = self.hosted.get(widget_id)
                    if hosted is not None:
                        self.hook_failed(hosted, "being shown", exc)

    def attach(self, widget_id: str, model: HostedModel | None) -> None:
        """Show ``model`` in its widget's frame (None: the widget stopped)."""
        hosted = self.hosted.get(widget_id)
        if hosted is None or model is hosted.model:
            return
        hosted.model, hosted.view, hosted.refreshes, hosted.painted_seq = model, None, False, -1
        hosted.hook_error = None
        self.models_version += 1
        frame = hosted.frame
        if model is None:
            frame.set_placeholder("")
            frame.problems.set_problems([])
            return
        if isinstance(model, UnconfiguredWidgetModel):  # settings it cannot read: the warning, no view
            frame.set_placeholder("")
            frame.problems.set_problems(self.problems_of(hosted))
            return
        if isinstance(model, MissingWidgetModel):
            if isinstance(model, BrokenWidgetModel):
                frame.set_placeholder(f"{hosted.widget.title or hosted.widget.kind} could not be shown:\n"
                                      f"{model.reason}")
            else:
                frame.set_placeholder(_not_installed(hosted.widget.kind))
            frame.problems.set_problems([])
            return
        try:
            view_cls = self.plugins.widget(hosted.widget.kind).load_view()
            if widget_id in self.dry_run:
                for m in (model, *model.child_models()):  # a preview: offline on purpose (the view contract)
                    try:
                        m.dry_run = True
                    except AttributeError:  # a model with __slots__ may refuse; the badge still says it
                        pass
            hosted.view = view_cls(model)
            hosted.refreshes = isinstance(hosted.view, WidgetView)
        except (UnknownWidget, Exception) as exc:  # a broken view must not break the app
            log.warning("view of %s (%s) failed: %s", widget_id, hosted.widget.kind, exc)
            frame.set_placeholder(f"{hosted.widget.title or hosted.widget.kind} could not be shown:\n{exc}")
            return
        frame.set_view(hosted.view)
        try:  # what the view leaves nameless is named after the widget (accessibility.py)
            name_parts(hosted.view, hosted.widget.title or self.plugins.widget(hosted.widget.kind).title)
        except Exception as exc:  # noqa: BLE001 - a view that fails here still shows
            log.warning("naming the parts of %s failed: %s", widget_id, exc)
        frame.problems.set_problems(self.problems_of(hosted))
        reason = view_only_control(hosted.widget, model)
        if reason:  # the port refuses anyway (rcon_core.canvas.port); the controls say so
            hosted.view.setEnabled(False)
            hosted.view.setToolTip(f"View only: {reason}. Nothing is sent to the robot.")
            # the badge with it, not at the next pass: a disabled control never shows without its reason
            hosted.frame.badge.show_status("view-only", "VIEW ONLY", f"{reason}: nothing is sent to the robot")

    def set_link_up(self, up: bool, robot_id: str | None = None) -> None:
        """One robot's link (``robot_id``), or, without it, every robot's (a one-robot window)."""
        if robot_id is None:
            self._link_up = up
            self.links_up.clear()
        else:
            self.links_up[robot_id] = up

    def link_up_for(self, widget: WidgetInstance) -> bool:
        robot = widget.binding.robot or self.first_robot
        return self.links_up.get(robot, self._link_up)

    # ------------------------------------------------------------------------------------ painting
    @property
    def waiting(self) -> bool:
        """Whether some widget changed but waits for its frame interval (or the frame budget)."""
        return bool(self._due)

    def refresh(self, ids: Iterable[str] | None = None, now: float | None = None) -> float | None:
        """Refresh the views whose model changed (all, or only ``ids`` and those waiting for their
        interval), within the frame budget, fairly. Returns seconds until a waiting widget is due."""
        now = time.monotonic() if now is None else now
        if ids is None:
            order = [w for w, h in self.hosted.items() if h.model is not None]
            start = self._cursor % len(order) if order else 0
            order = order[start:] + order[:start]
        else:
            order = [w for w in {*ids, *self._due} if w in self.hosted]
        deadline = time.perf_counter() + FRAME_BUDGET
        for k, widget_id in enumerate(order):
            hosted = self.hosted[widget_id]
            try:  # the widget boundary: one view that fails does not keep the others from repainting
                self._refresh(hosted, now)
            except Exception as exc:
                self._view_failed(hosted, exc)
            if time.perf_counter() > deadline:
                self._due.update(order[k + 1:])
                if ids is None:
                    self._cursor = (self._cursor + k + 1) % max(1, len(self.hosted))
                break
        else:
            if ids is None:
                self._cursor = 0
        if not self._due:
            return None
        soonest = min((self.hosted[w].painted_at for w in self._due if w in self.hosted), default=now)
        return max(0.0, soonest + FRAME_INTERVAL - now)

    def _refresh(self, hosted: Hosted, now: float) -> None:
        model = hosted.model
        if model is None or not hosted.frame.isVisible():
            self._due.discard(hosted.widget.id)
            return
        state = model.state
        badge = hosted.frame.badge
        view_only = view_only_control(hosted.widget, model)
        if hosted.widget.id in self.dry_run:
            badge.show_status("ok", "PREVIEW ONLY", "not sent to the robot until the widget is placed")
        elif view_only:
            badge.show_status("view-only", "VIEW ONLY", f"{view_only}: nothing is sent to the robot")
        elif state.link_down or not self.link_up_for(hosted.widget):
            badge.show_status("down", "LINK DOWN", "the link to this widget's robot is down: nothing arrives, "
                                                   "nothing is sent")
        elif state.error or hosted.view_error or hosted.hook_error:
            badge.show_status("problem", "ERROR", state.error or hosted.view_error or hosted.hook_error or "")
        elif state.stale:
            badge.show_status("stale", "STALE" if state.count else "NO DATA",
                              "no new value for a while" if state.count else "nothing has arrived yet")
        else:
            badge.show_status("", "")
        if state.seq == hosted.painted_seq:
            self._due.discard(hosted.widget.id)
            return
        if now - hosted.painted_at < FRAME_INTERVAL:
            self._due.add(hosted.widget.id)  # at most one repaint per frame; the latest value wins later
            return
        self._due.discard(hosted.widget.id)
        hosted.painted_seq, hosted.painted_at = state.seq, now
        view = hosted.view
        if hosted.refreshes:
            view.refresh(state)
        elif view is not None:
            view.update()
        if hosted.view_error is not None:  # it shows again: the next pass clears the badge
            hosted.view_error = None
        for hook in self.paint_hooks:
            hook(hosted, state)

    def problems_of(self, hosted: Hosted) -> list[str]:
        """The model's ``problems()``; one that raises is itself the problem shown (and counted)."""
        if hosted.model is None:
            return []
        try:
            return [str(p) for p in hosted.model.problems()]
        except Exception as exc:
            self.hook_failed(hosted, "problems()", exc)
            return [f"the widget could not check its settings: {safe_text(exc)}"]

    def hook_failed(self, hosted: Hosted, hook: str, exc: Exception) -> None:
        """A widget's hook other than ``refresh`` raised: counted, logged with a bounded text (the first 20,
        then every 1000th), shown on that widget's badge until it is attached again; the others go on."""
        self.hook_errors += 1
        hosted.hook_error = f"the widget failed in {hook}: {safe_text(exc)}"
        self._log_failure(hosted, hosted.hook_error)
        try:
            hosted.frame.badge.show_status("problem", "ERROR", hosted.hook_error)
        except Exception:  # noqa: BLE001 - the frame itself is broken: the count and the log say it
            pass

    def _log_failure(self, hosted: Hosted, text: str) -> None:
        n = self._view_error_counts[hosted.widget.id] = self._view_error_counts.get(hosted.widget.id, 0) + 1
        if n <= 20 or n % 1000 == 0:
            log.error("widget %s (%s): %s (%d so far)", hosted.widget.id, hosted.widget.kind, text, n)

    def _view_failed(self, hosted: Hosted, exc: Exception) -> None:
        """A view's ``refresh`` (or the widget's badge) raised: counted, logged with a bounded text (the
        first 20, then every 1000th), shown on the widget's badge; the pass goes on with the others."""
        self.view_errors += 1
        hosted.view_error = f"the view could not show the value: {safe_text(exc)}"
        self._log_failure(hosted, hosted.view_error)
        try:
            hosted.frame.badge.show_status("problem", "ERROR", hosted.view_error)
        except Exception:  # noqa: BLE001 - the frame itself is broken: the count and the log say it
            pass

    def topic_counts(self, robot_id: str | None = None) -> dict[str, int]:
        """Values received per subscribed topic (the largest over its widgets), for the topic rates; with
        ``robot_id``, of that robot's widgets only (the side panel lists one robot's topics)."""
        out: dict[str, int] = {}
        for hosted in self.hosted.values():
            binding = hosted.widget.binding
            if robot_id is not None and (binding.robot or self.first_robot) != robot_id:
                continue
            if hosted.model is not None and binding.role is Role.SUBSCRIBE and binding.name:
                try:
                    count = int(hosted.model.state.count)
                except Exception as exc:  # the widget boundary: its count is left out, the others kept
                    self.hook_failed(hosted, "state", exc)
                    continue
                out[binding.name] = max(out.get(binding.name, 0), count)
        return out


def view_only_control(widget: WidgetInstance, model: HostedModel) -> str | None:
    """Why ``widget`` (a publishing, calling or serving one) runs view-only, or None. A model whose
    ``view_only`` raises cannot say: its controls are shown disabled (its port refuses anyway when the
    robot is view-only, see ``rcon_core.canvas.port``)."""
    if widget.binding.role.value == "subscribe":
        return None
    try:
        reason = model.view_only
    except Exception as exc:
        return f"the widget could not say whether it may send ({safe_text(exc, 80)})"
    return str(reason) if reason else None


def _not_installed(kind: str) -> str:
    return f"Widget “{kind}” is not installed.\nIts settings are kept."


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
