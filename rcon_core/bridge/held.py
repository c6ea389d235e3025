"""Commands held behind an unanswered service call, seen from the client. No Qt, no I/O.

Decision: why
    rosbridge 2.1.0 (the stock Jazzy release; every Humble 1.x release too, unless launched with
    ``call_services_in_new_thread``) handles one connection's frames one at a time, and a ``call_service``
    waits for its answer inside that handling. While a call is unanswered every later frame on the same
    connection -- teleop publishes included -- waits in the server and is delivered late, all at once,
    when the call returns (``tests/recordings/rosbridge-ros2-2.1.0/services.jsonl:20-25``). The client
    cannot stop what it already wrote, and its stall watch sees nothing: WebSocket pings are still
    answered. So the client watches its own calls: a call written on a link and not answered for more than
    :data:`HOLD_AFTER` (0.5 s) means the robot's bridge may be holding every command sent since.

Decision: which servers
    ``may_hold()`` (the session asks the host's ``ros_version``) is False for ROS 1: rosbridge 0.11 runs
    each call in a thread of its own (``rosbridge-ros1/services.jsonl:19-22``: a fast call answered while
    a slow one runs). Every ROS 2 server may hold (2.2.0 and later run calls in threads by default, but
    that is a launch option the wire does not show), and so may a server whose ROS is not known yet.

Decision: until when
    A call counts until its ``service_response`` arrives, whatever the client did meanwhile: a call that
    timed out on the client, or whose caller gave up, still occupies 2.1.0's one worker (it has no
    timeout of its own). A dropped link ends it (the server forgot the connection). At most ``limit``
    calls are kept (the oldest forgotten first).

::

    watch = HeldWatch(may_hold=lambda: client.ros_version != 1, schedule=loop.call_later)
    watch.started(call_id, "/dock")     # the call_service frame was written
    watch.answered(call_id)             # its service_response arrived (late ones too)
    watch.reset()                       # the link dropped
    watch.current                       # Held("/dock", since) once told, else None
    watch.add_listener(fn)              # fn(Held | None) when that changes (on the loop thread)

The session (``session.py``) feeds it; the canvas runtime tells each model of the robot
(``WidgetModel.on_commands_held``: the teleop pad stops and says why) and the app's link shows
:meth:`Held.sentence` on the connection bar.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

__all__ = ["Held", "HeldWatch", "HOLD_AFTER"]

log = logging.getLogger(__name__)

#: seconds a call may go unanswered before the link reports that commands may be held behind it
HOLD_AFTER = 0.5


@dataclass(frozen=True)
class Held:
    """The oldest call still unanswered past the threshold: ``service`` and when it was written."""

    service: str
    since: float

    def sentence(self) -> str:
        return f"commands held: the robot's bridge is still busy with {self.service}"


class HeldWatch:
    """Service calls written on one link and not answered yet (see the module docstring)."""

    def __init__(self, *, threshold: float = HOLD_AFTER, clock: Callable[[], float] = time.monotonic,
                 may_hold: Callable[[], bool] = lambda: True,
                 schedule: Callable[[float, Callable[[], Any]], Any] | None = None, limit: int = 64) -> None:
        """``schedule(delay, fn)`` arranges a later :meth:`check` (the session's shell passes the running
        loop's timer, ``shell.later``; None: only the next call, answer or reset checks)."""
        self.threshold = threshold
        self.clock = clock
        self.may_hold = may_hold
        self.schedule = schedule
        self.limit = limit
        self._calls: dict[Any, tuple[str, float]] = {}  # call id -> (service, written at), oldest first
        self._listeners: list[Callable[[Held | None], None]] = []
        #: what the listeners were last told (None: nothing held)
        self.current: Held | None = None

    # ------------------------------------------------------------------ events
    def started(self, call_id: Any, service: str) -> None:
        """A call_service frame was written."""
        self._calls[call_id] = (service, self.clock())
        while len(self._calls) > self.limit:
            old = next(iter(self._calls))
            log.debug("held watch: forgetting the oldest unanswered call %r", old)
            del self._calls[old]
        self._later(self.threshold)

    def answered(self, call_id: Any) -> None:
        """A service_response with this id arrived (on time, late, or a failure)."""
        if self._calls.pop(call_id, None) is not None:
            self.check()

    def reset(self) -> None:
        """The link dropped: the server forgot every call of the connection."""
        self._calls.clear()
        self.check()

    # ------------------------------------------------------------------ reading
    def held(self) -> Held | None:
        """The oldest call unanswered for more than the threshold, if this server may hold frames."""
        if not self._calls:
            return None
        service, since = next(iter(self._calls.values()))
        if self.clock() - since <= self.threshold or not self._may_hold():
            return None
        return Held(service, since)

    def check(self) -> Held | None:
        """Tell the listeners when what is held changed; returns it. Arranges the next check while a call
        is unanswered but not yet past the threshold."""
        now = self.held()
        if now is None and self._calls:
            _service, since = next(iter(self._calls.values()))
            left = since + self.threshold - self.clock()
            if left > 0:  # not yet past the threshold; past it and not held (ROS 1): nothing to wait for
                self._later(left)
        if now != self.current:
            self.current = now
            for fn in list(self._listeners):
                try:
                    fn(now)
                except Exception:  # noqa: BLE001 - one listener never keeps the others from hearing it
                    log.exception("a commands-held listener failed")
        return now

    def add_listener(self, fn: Callable[[Held | None], None]) -> Callable[[], None]:
        """``fn(held)`` on every change (None: nothing held any more); returns the remover."""
        self._listeners.append(fn)

        def remove() -> None:
            if fn in self._listeners:
                self._listeners.remove(fn)

        return remove

    # ------------------------------------------------------------------ inside
    def _may_hold(self) -> bool:
        try:
            return bool(self.may_hold())
        except Exception:  # noqa: BLE001 - not knowing the server: it may hold
            return True

    def _later(self, delay: float) -> None:
        schedule = self.schedule
        if schedule is not None:
            schedule(delay + 0.01, self.check)  # just past the threshold
