"""One timer at display rate that drives everything the GUI takes from the bridge thread.

The GUI thread never waits on the network: the bridge thread leaves values in mailboxes, and on each tick
the clock's consumers take the newest values and ask Qt to repaint what changed.  Qt coalesces repaints,
so a widget paints at most once per frame whatever its topic's rate.
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable

from qtpy import QtCore

FRAME_HZ = 60


class FrameClock(QtCore.QObject):
    """Calls its consumers once per frame (~60 Hz) on the GUI thread and keeps timing figures."""

    def __init__(self, parent: QtCore.QObject | None = None, hz: int = FRAME_HZ) -> None:
        super().__init__(parent)
        self._consumers: list[Callable[[float], None]] = []
        self._timer = QtCore.QTimer(self)
        self._timer.setTimerType(QtCore.Qt.TimerType.PreciseTimer)
        self._timer.setInterval(max(1, round(1000 / hz)))
        self._timer.timeout.connect(self._tick)
        self.last_tick = time.monotonic()
        #: durations (s) of the last ticks' work, and the gaps between ticks
        self.work_times: deque[float] = deque(maxlen=4096)
        self.gaps: deque[float] = deque(maxlen=4096)
        self.ticks = 0

    def add(self, consumer: Callable[[float], None]) -> None:
        """Register ``consumer(now)`` to be called every frame."""
        if consumer not in self._consumers:
            self._consumers.append(consumer)

    def remove(self, consumer: Callable[[float], None]) -> None:
        if consumer in self._consumers:
            self._consumers.remove(consumer)

    def start(self) -> None:
        self.last_tick = time.monotonic()
        self._timer.start()

    def stop(self) -> None:
        self._timer.stop()

    @property
    def running(self) -> bool:
        return self._timer.isActive()

    def _tick(self) -> None:
        now = time.monotonic()
        self.gaps.append(now - self.last_tick)
        self.last_tick = now
        self.ticks += 1
        for consumer in list(self._consumers):
            try:
                consumer(now)
            except Exception:  # one broken consumer must not stop the others' frames
                import logging

                logging.getLogger(__name__).exception("frame consumer %r failed", consumer)
        self.work_times.append(time.monotonic() - now)
