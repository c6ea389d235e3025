"""The live preview on the add panel's settings page: the draft run as a one-widget canvas.

The preview's model is built and started by its own canvas runtime (a :class:`LiveCanvas`) on the
bridge thread, like any placed widget, and shown by the same :class:`WidgetHost`; releasing the preview
stops it there. Only a widget that *shows* (subscribe) runs on the robot, and then on a view-only port
(it subscribes, it never advertises, publishes or calls: a map's preview does not announce its goal
topic): a preview that would publish, call or serve runs offline, so touching a teleop pad or a button in
the add panel never moves the robot (its frame says PREVIEW ONLY).
"""

from __future__ import annotations

from typing import Any

from rcon_core.app.link import OFFLINE
from rcon_core.app.live import LiveCanvas
from rcon_core.app.widget_frame import WidgetFrame
from rcon_core.app.widget_host import WidgetHost
from rcon_core.canvas import Canvas, Geometry, WidgetInstance, new_id
from rcon_core.plugins import Role

#: why a preview on the robot sends nothing (its port's view-only reason)
PREVIEW_LISTENS = "a preview sends nothing until the widget is placed"


class PreviewHost:
    """Runs the draft being configured; ``client()`` gives the current bridge client (or the offline one)."""

    def __init__(self, host: WidgetHost, live: LiveCanvas, client: Any) -> None:
        self.host = host
        self.live = live
        self.client = client
        self.widget: WidgetInstance | None = None
        #: the robot connection is view-only (why), set by the window: the preview's port refuses too
        self.view_only: str | None = None

    def build(self, draft: Any, frame: WidgetFrame) -> None:
        """Show ``draft`` in ``frame``: its view appears when the runtime has built the model."""
        self.release()
        w, h = draft.size()
        widget = WidgetInstance(
            new_id("preview"), draft.spec.kind, draft.binding, Geometry(0, 0, w, h), draft.settings_dict(),
            draft.title,
        )
        self.widget = widget
        frame.instance_id = widget.id
        self.host.build_frame(widget, frame)
        if not self.live_on_robot:
            self.host.dry_run.add(widget.id)
        self.restart()

    @property
    def live_on_robot(self) -> bool:
        """Whether the preview talks to the robot: only widgets that just show what arrives."""
        return self.widget is not None and self.widget.binding.role is Role.SUBSCRIBE

    def release(self) -> None:
        if self.widget is not None:
            self.host.discard(self.widget.id)
            self.host.dry_run.discard(self.widget.id)
            self.live.stop()
            self.widget = None

    def restart(self) -> None:
        """Run the preview again on the current client (after the link changed)."""
        if self.widget is not None:
            client = self.client() if self.live_on_robot else OFFLINE
            # a preview on the robot only listens: its port sends nothing, not even an advertise (a map's
            # preview told the robot it would publish goals on /goal/fix)
            view_only = self.view_only or (PREVIEW_LISTENS if self.live_on_robot else None)
            self.live.start(client, Canvas("preview", "Preview", [self.widget]), view_only=view_only)
