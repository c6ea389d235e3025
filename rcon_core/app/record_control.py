"""The Record control on the connection bar: record every robot of the workspace and what the operator did.

A button ("● Rec"; also Canvas ▾ → Record every robot) and, while recording, an indicator:
``REC 01:23 · 45.6 MB`` (red), the time and the size on disk of every file, updated once a second from the
frame clock. On a screen narrower than 1100 px (a 1024x600 tablet) the bar has no room for more: the button is left
out (the menu starts and stops), and the indicator, ``REC 01:23`` (the size in its tooltip), takes the round-trip
time's place while recording; where even that has no room beside the URL field (200 % text), it is a red ●. Each robot gets its own MCAP file
in the recordings folder (``AppConfig.dir / "recordings"`` unless ``RecordControl.directory`` is
set): the topics every canvas's widgets show, and on ``/rcon/operator/...`` every publish, call and
answer, action goal, feedback, result and cancel, and parameter set that left the app for it, with the
widget and the robot (``rcon_core/record/session.py``, tapped below every widget: ``bridge/tap.py``).

The disk budget (``budget``, 4 GB by default) is shared by the files; at 90 % the notice bar says so,
and when it is used up the files are closed properly and the notice says that. Any other problem (a full
disk, a type without definition) is said on the notice bar too. A robot that is connected again while
recording is recorded from its new link into the same file; a dropped link shows as a gap (and on
``/rcon/link``).

Installed by :func:`install_record_control` from the window's composition root, given the few parts it
works with (the bridge thread, the document, the fleet's clients, the notice bar, the connection bar, the
canvas bar, the frame clock); no other module of the app knows it.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from pathlib import Path
from typing import Any

from qtpy import QtCore, QtGui, QtWidgets

from rcon_core.app.canvas_bar import CanvasBar
from rcon_core.app.connection_bar import ConnectionBar
from rcon_core.app.frame_clock import FrameClock
from rcon_core.app.notice_bar import NoticeBar
from rcon_core.app.theme import repolish
from rcon_core.bridge.threaded import BridgeThread
from rcon_core.canvas import Document
from rcon_core.canvas.fleet import Fleet
from rcon_core.record.session import DEFAULT_BUDGET, AppRecording, topics_of

log = logging.getLogger(__name__)

__all__ = ["RecordControl", "install_record_control", "COMPACT_BELOW"]

#: a screen narrower than this gets the compact control (a 1024x600 tablet has room for the button)
COMPACT_BELOW = 1100  # as the side panel's: at 1024 px the button left the URL field "ws:…971"


class RecIndicator(QtWidgets.QLabel):
    """The recording's reading (``REC 01:23``) where the bar gives it the room (its maximum width, set by the
    bar: ``ConnectionBar.givers``), a red ● where not (at 200 % text on a 1024 px tablet the URL field comes
    first); the reading is in its accessible name either way, the details in its tooltip."""

    SHORT = "●"

    def __init__(self) -> None:
        super().__init__("")
        self.reading = ""

    def set_reading(self, text: str) -> None:
        if text != self.reading:
            self.reading = text
            self.setAccessibleName(f"recording: {text}")
            self.updateGeometry()
            self._fit()

    def _width(self, text: str) -> int:
        shown = super().text()
        chrome = super().sizeHint().width() - (self.fontMetrics().horizontalAdvance(shown) if shown else 0)
        return chrome + self.fontMetrics().horizontalAdvance(text)

    def full_width(self) -> int:
        return self._width(self.reading) if self.reading else 0

    def set_room(self, px: int) -> None:
        if px != self.maximumWidth():
            self.setMaximumWidth(px)

    def sizeHint(self) -> QtCore.QSize:  # noqa: N802 - Qt's name
        return QtCore.QSize(self.full_width(), super().sizeHint().height())

    def minimumSizeHint(self) -> QtCore.QSize:  # noqa: N802 - Qt's name
        return QtCore.QSize(self._width(self.SHORT), super().minimumSizeHint().height())

    def resizeEvent(self, event: QtGui.QResizeEvent) -> None:  # noqa: N802 - Qt's name
        super().resizeEvent(event)
        self._fit()

    def _fit(self) -> None:
        text = self.reading if self.width() >= self.full_width() else self.SHORT if self.reading else ""
        if text != super().text():
            self.setText(text)


def _clock(seconds: float) -> str:
    s = int(seconds)
    return f"{s // 3600}:{s % 3600 // 60:02d}:{s % 60:02d}" if s >= 3600 else f"{s // 60:02d}:{s % 60:02d}"


class RecordControl(QtWidgets.QWidget):
    """The button and the indicator (see the module docstring)."""

    def __init__(self, thread: BridgeThread, directory: Path, doc: Document, fleet: Callable[[], Fleet],
                 notice: NoticeBar, yield_latency: Callable[[bool], None],
                 parent: QtWidgets.QWidget | None = None, *, compact: bool = False) -> None:
        super().__init__(parent)
        #: a small screen: no button on the bar (Canvas ▾ → Record every robot), and while recording a
        #: short indicator in the place of the round-trip time, so the bar is no wider than without it
        self.compact = compact
        self.action: QtGui.QAction | None = None
        self.bridge_thread, self.doc, self.fleet, self.notice = thread, doc, fleet, notice
        #: ``yield_latency(True)``: the compact indicator takes the round-trip time's place on the connection
        #: bar while recording (the bar alone shows or hides the round trip: ``ConnectionBar.yield_latency``)
        self.yield_latency = yield_latency
        self.directory = directory
        self.budget: int | None = DEFAULT_BUDGET
        self.recording: AppRecording | None = None
        self._said: set[str] = set()
        self._last = -1.0
        self.button = QtWidgets.QPushButton("● Rec")
        self.button.setObjectName("recordButton")
        self.button.setCheckable(True)
        self.button.setToolTip("Record every robot's topics and what the operator sends, to MCAP files "
                               "(Foxglove, Lichtblick, rosbags, rcon sim --play)")
        self.button.clicked.connect(self.toggle)
        self.indicator = RecIndicator()
        self.indicator.setObjectName("recordIndicator")
        self.indicator.setProperty("role", "problem")
        self.indicator.hide()
        row = QtWidgets.QHBoxLayout(self)
        row.setContentsMargins(0, 0, 0, 0)
        row.setSpacing(6)
        row.addWidget(self.button)
        row.addWidget(self.indicator)
        self.button.setVisible(not compact)
        self._fit_visibility()

    def _fit_visibility(self) -> None:
        """Shown while it shows something: an empty control would still cost the bar a spacing (at 200 %
        text on a 1024 px tablet the URL field needs every pixel)."""
        self.setVisible(not self.button.isHidden() or not self.indicator.isHidden())

    def set_compact(self, compact: bool) -> None:
        """Leave the button out (or put it back). Decided once, from the screen, by the installer: a
        control that came and went with the window's width would change the bar's minimum width, which
        stays the same in every state (``connection_bar.py``)."""
        if compact == self.compact:
            return
        self.compact = compact
        self.button.setVisible(not compact)
        recording = self.recording is not None and self.recording.active
        self.yield_latency(compact and recording)
        self._fit_visibility()
        self._show()

    # ------------------------------------------------------------------ start and stop

    def robots(self) -> list[tuple[str, str, Any, dict[str, str]]]:
        ws = self.doc.workspace
        first = ws.robots[0].id
        out = []
        for robot, client in self.fleet().items():
            live = client if hasattr(client, "session") else None
            out.append((robot.id, robot.label if hasattr(robot, "label") else robot.name, live,
                        topics_of(ws, robot.id, first)))
        return out

    def toggle(self) -> None:
        if self.recording is not None and self.recording.active:
            self.stop()
        else:
            self.start()

    def start(self) -> None:
        rec = AppRecording(self.bridge_thread, self.directory, budget=self.budget)
        try:
            rec.start(self.robots())
        except Exception as exc:  # noqa: BLE001 - said, never raised into Qt
            rec.stop()
            self.button.setChecked(False)
            self.notice.show_notice(f"Cannot record: {exc}")
            return
        self.recording = rec
        self._said.clear()
        self.button.setChecked(True)
        self.button.setText("■ Stop")
        if self.action is not None:
            self.action.setText("■ Stop recording")
        if self.compact:
            self.yield_latency(True)
        self.indicator.show()
        self._fit_visibility()
        self._show(force=True)

    def stop(self) -> None:
        rec = self.recording
        if rec is None:
            return
        rec.stop()
        status = rec.status()
        self.button.setChecked(False)
        self.button.setText("● Rec")
        if self.action is not None:
            self.action.setText("● Record every robot")
        self.indicator.hide()
        self._fit_visibility()
        self.yield_latency(False)
        files = ", ".join(Path(f).name for f in status.files)
        self.notice.show_notice(f"ℹ Recorded {_clock(status.seconds)}, {status.size / 1e6:.1f} MB: {files} "
                                       f"in {self.directory}", kind="info")

    # ------------------------------------------------------------------ the frame clock

    def close_files(self) -> None:
        """The app is closing: every file is closed properly (summary and index) before the links go."""
        if self.recording is not None and self.recording.active:
            self.recording.stop()

    def poll(self, now: float) -> None:
        rec = self.recording
        if rec is None or not rec.active or now - self._last < 1.0:
            return
        self._last = now
        for robot_id, _name, client, topics in self.robots():
            rec.swap_client(robot_id, client)
            rec.add_topics(robot_id, topics)
        self._show()

    def _show(self, force: bool = False) -> None:
        rec = self.recording
        if rec is None:
            return
        st = rec.status()
        self.indicator.set_reading(f"REC {_clock(st.seconds)}" if self.compact else
                                   f"REC {_clock(st.seconds)} · {st.size / 1e6:.1f} MB")
        self.indicator.setToolTip(f"{st.size / 1e6:.1f} MB, {st.messages} messages, {st.events} operator events"
                                  + (f", {st.dropped} dropped" if st.dropped else "") + " · " + ", ".join(st.files))
        self.indicator.setProperty("role", "problem" if st.recording else "muted")
        repolish(self.indicator)
        for text in (st.warning, st.problem):
            if text and text not in self._said:
                self._said.add(text)
                self.notice.show_notice(f"Recording: {text}")
        if not st.recording and rec.active:
            self.stop()


def install_record_control(thread: BridgeThread, directory: Path, doc: Document, fleet: Callable[[], Fleet],
                           notice: NoticeBar, connection: ConnectionBar, bar: CanvasBar, clock: FrameClock,
                           replay_dialog: Callable[[], object], *, compact: bool) -> RecordControl:
    """Put the Record control on the connection bar, before the link state, and on the frame clock; and
    Canvas ▾ → Record every robot / Replay a recording… (``replay_dialog``). ``compact``: a small screen."""
    control = RecordControl(thread, directory, doc, fleet, notice, connection.yield_latency, compact=compact)
    row = connection.layout()
    if isinstance(row, QtWidgets.QBoxLayout):
        row.insertWidget(max(0, row.indexOf(connection.state_label)), control)
    connection.givers.insert(0, control.indicator)  # the bar's room, after the URL field's host, to it first
    clock.add(control.poll)
    menu = bar.menu
    record = QtGui.QAction("● Record every robot", menu)
    record.setObjectName("record")
    record.triggered.connect(control.toggle)
    control.action = record
    action = QtGui.QAction("Replay a recording…", menu)
    action.setObjectName("replay_recording")
    export = bar.canvas_actions.get("export")
    for a in (record, action):
        if export is not None:  # beside the other file actions, before Export / Import
            menu.insertAction(export, a)
        else:
            menu.addAction(a)
    action.triggered.connect(lambda: replay_dialog())
    return control


def small_screen(widget: QtWidgets.QWidget) -> bool:
    """``widget``'s screen is narrower than :data:`COMPACT_BELOW` (the compact control)."""
    screen = widget.screen() or QtGui.QGuiApplication.primaryScreen()
    return screen is not None and screen.availableGeometry().width() < COMPACT_BELOW
