"""The timeline of a recording played as the robot (``rcon --play FILE``, Canvas ▾ → Replay a recording…).

The recording is served by a bare sim with a ``Player`` (``rcon_core/sim/playback.py``) on its own thread,
and the window's first robot connects to it like to any robot: every widget works on it unchanged. The bar
under the connection bar: play/pause, the speed (0.25x to 8x), a slider to seek by dragging or tapping,
the current time and the length, and the words "REPLAY ... commands go nowhere".

Seeking sends each topic's latest message before that time (the player) and restarts the canvas's widgets,
so each shows the state at that time, not a trail from before (the map's track starts again there).

The bar only drives the player and says ``seeked``; :class:`~rcon_core.app.robot_recordings.RobotRecordings`
places it (``play_first``, ``open_dialog``) and the window restarts the widgets on ``seeked``.

Commands go nowhere, three times over: the recording's robot is view-only in the app
(``ReplayBar.reason`` is its view-only reason, ``view_only.reason``): its link refuses every command
(``bridge/guard.py``) and its control widgets show the sentence and send nothing; and the player absorbs
whatever reaches it anyway (``Player.absorbed``).
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

from qtpy import QtCore, QtWidgets

log = logging.getLogger(__name__)

__all__ = ["ReplayBar", "SPEEDS"]

SPEEDS = (0.25, 0.5, 1.0, 2.0, 4.0, 8.0)
STEPS = 1000  # slider resolution


def _time(seconds: float) -> str:
    m, s = divmod(max(0.0, seconds), 60)
    return f"{int(m)}:{s:04.1f}"


class ReplayBar(QtWidgets.QFrame):
    """Drives ``player`` (thread-safe calls) and shows where it is; ``poll`` from the frame clock."""

    #: the player went to another time (the widgets start again there)
    seeked = QtCore.Signal()

    def __init__(self, server: Any, player: Any, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.setObjectName("replayBar")
        self.server = server
        self.player = player
        self.url = server.url
        name = Path(player.recording.path).name
        #: the robot's view-only reason while it is a recording (fleet_ui reads it)
        self.reason = f"this robot is a recording ({name}): commands go nowhere"
        self.play_button = QtWidgets.QPushButton()
        self.play_button.setObjectName("replayPlay")
        self.play_button.setProperty("square", True)
        self.play_button.clicked.connect(self.toggle)
        self.speed = QtWidgets.QComboBox()
        self.speed.setObjectName("replaySpeed")
        for x in SPEEDS:
            self.speed.addItem(f"{x:g}×", x)
        self.speed.setCurrentIndex(SPEEDS.index(1.0) if player.rate not in SPEEDS else SPEEDS.index(player.rate))
        self.speed.currentIndexChanged.connect(lambda i: self.player.set_rate(SPEEDS[i]))
        self.slider = QtWidgets.QSlider(QtCore.Qt.Orientation.Horizontal)
        self.slider.setObjectName("replaySlider")
        self.slider.setRange(0, STEPS)
        self.slider.setMinimumWidth(160)
        self.slider.sliderMoved.connect(self._dragging)
        self.slider.sliderReleased.connect(lambda: self.seek(self._slider_seconds()))
        self.slider.valueChanged.connect(self._tapped)
        self.time_label = QtWidgets.QLabel()
        self.time_label.setObjectName("replayTime")
        self.words = QtWidgets.QLabel(f"REPLAY · {name} · commands go nowhere")
        self.words.setObjectName("replayWords")
        self.words.setProperty("role", "problem")
        self.words.setToolTip(f"{player.recording.path}: {player.recording.kind}, "
                              f"{'ROS 2' if server.ros2 else 'ROS 1'}, {len(player.recording.tracks)} topics, "
                              f"{player.recording.message_count} messages. Nothing the operator sends reaches "
                              "a robot.")
        row = QtWidgets.QHBoxLayout(self)
        row.setContentsMargins(10, 4, 10, 4)
        row.setSpacing(10)
        row.addWidget(self.play_button)
        row.addWidget(self.speed)
        row.addWidget(self.slider, 1)
        row.addWidget(self.time_label)
        row.addWidget(self.words)
        self.seeks = 0
        self.poll(0.0)

    # ------------------------------------------------------------------ control

    @property
    def duration(self) -> float:
        return float(self.player.duration)

    def toggle(self) -> None:
        if self.player.playing and not self.player.ended:
            self.player.pause()
        else:
            self.player.play()

    def set_speed(self, x: float) -> None:
        self.speed.setCurrentIndex(SPEEDS.index(x))

    def seek(self, seconds: float) -> None:
        """Go to ``seconds``: the player sends the state there and the widgets start again on it."""
        self.seeks += 1
        self.player.seek(seconds)
        self.seeked.emit()  # fresh widgets: the state at that time, not a trail from before

    def _slider_seconds(self) -> float:
        return self.slider.value() / STEPS * self.duration

    def _dragging(self, value: int) -> None:
        self.time_label.setText(f"{_time(value / STEPS * self.duration)} / {_time(self.duration)}")

    def _tapped(self, _value: int) -> None:
        if not self.slider.isSliderDown():  # a tap on the groove or a key, not our own update
            self.seek(self._slider_seconds())

    # ------------------------------------------------------------------ the frame clock

    def poll(self, _now: float) -> None:
        p = self.player
        playing = p.playing and not p.ended
        self.play_button.setText("||" if playing else "▶")
        self.play_button.setToolTip("Pause" if playing else "Play")
        if not self.slider.isSliderDown():
            value = int(round(p.position / self.duration * STEPS)) if self.duration > 0 else 0
            if value != self.slider.value():
                self.slider.blockSignals(True)
                self.slider.setValue(value)
                self.slider.blockSignals(False)
            self.time_label.setText(f"{_time(p.position)} / {_time(self.duration)}")
