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
        self._consumers: list[Callable[[float], object]] = []
        self._timer = QtCore.QTimer(self)
        self._timer.setTimerType(QtCore.Qt.TimerType.PreciseTimer)
        self._timer.setInterval(max(1, round(1000 / hz)))
        self._timer.timeout.connect(self._tick)
        self.last_tick = time.monotonic()
        #: durations (s) of the last ticks' work, and the gaps between ticks
        self.work_times: deque[float] = deque(maxlen=4096)
        self.gaps: deque[float] = deque(maxlen=4096)
        self.ticks = 0

    def add(self, consumer: Callable[[float], object]) -> None:
        """Register ``consumer(now)`` to be called every frame."""
        if consumer not in self._consumers:
            self._consumers.append(consumer)

    def remove(self, consumer: Callable[[float], object]) -> None:
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


#: the event type a :class:`Waker` posts to itself
WAKE_EVENT = QtCore.QEvent.Type(QtCore.QEvent.registerEventType())


class Waker(QtCore.QObject):
    """Wakes the GUI thread from any thread as soon as something arrived, without flooding it.

    ``poke(key)`` (thread-safe) collects ``key`` (a widget id, or None for "something") and posts one event
    to the GUI thread unless one is already pending; the handler then gets every key collected so far.
    Two handler runs are at least ``min_gap`` seconds apart, so a burst of messages costs one GUI pass,
    and a value waits at most ``min_gap`` instead of a whole frame for the next clock tick.
    """

    def __init__(self, handler: Callable[[set[str]], None], parent: QtCore.QObject | None = None,
                 min_gap: float = 0.004) -> None:
        super().__init__(parent)
        import threading

        self.handler = handler
        self.min_gap = min_gap
        self._lock = threading.Lock()
        self._keys: set[str] = set()
        self._pending = False
        self._last = 0.0
        self._later = QtCore.QTimer(self)
        self._later.setSingleShot(True)
        self._later.setTimerType(QtCore.Qt.TimerType.PreciseTimer)
        self._later.timeout.connect(self._fire)
        self.wakes = 0
        self.enabled = True

    def poke(self, key: str | None = None) -> None:
        with self._lock:
            if key is not None:
                self._keys.add(key)
            if self._pending or not self.enabled:
                return
            self._pending = True
        QtCore.QCoreApplication.postEvent(self, QtCore.QEvent(WAKE_EVENT))

    def event(self, event: QtCore.QEvent) -> bool:
        if event.type() == WAKE_EVENT:
            wait = self._last + self.min_gap - time.monotonic()
            if wait > 0:
                self._later.start(max(1, round(wait * 1000)))
            else:
                self._fire()
            return True
        return super().event(event)

    def _fire(self) -> None:
        with self._lock:
            keys, self._keys = self._keys, set()
            self._pending = False
        self._last = time.monotonic()
        self.wakes += 1
        try:
            self.handler(keys)
        except Exception:
            import logging

            logging.getLogger(__name__).exception("wake handler failed")

    def stop(self) -> None:
        with self._lock:
            self.enabled = False
        self._later.stop()
