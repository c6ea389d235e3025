"""The robot's side of "a stale command is dropped": an age limit on stamped velocity commands.

What the operator's device can promise stops at the network. RCON never *writes* a command older than its
freshness limit, and cuts a stalled link so what waits in its own send buffer is discarded; but a command
that already left (in flight, or in the robot's receive buffer) when the link stalls is still delivered
when the link comes back, the stall's length late: TCP cannot unsend it. Only the robot can refuse it, and
only if the command says when it was made.

So the sim takes ``geometry_msgs/TwistStamped`` on ``/cmd_vel_stamped`` (``/NAME/cmd_vel_stamped`` for a
named vessel) besides ``Twist`` on ``/cmd_vel``, and :meth:`StampedCommands.judge`:

* drops a command whose ``header.stamp`` is more than ``max_age`` seconds old (the robot's parameter
  ``cmd_max_age``; its default is the thrusters' watchdog, 0.5 s: a command the watchdog would already have
  stopped is never acted on), and one stamped more than ``max_age`` in the future (the two clocks are not
  in sync: an age cannot be judged); a zero stamp is "made in 1970", so it is dropped too;
* counts what it dropped (``dropped_stale``, ``dropped_future``) and says so on ``/rosout``, at most once
  every :data:`LOG_EVERY_S` seconds;
* for a command it takes, gives the time it was made on the robot's monotonic clock, so the watchdog runs
  from the stamp, not from the arrival: a command that arrived 0.4 s late drives for the 0.1 s left.

This needs the device's and the robot's clocks in sync (NTP/chrony), as any stamped-command timeout does.
The same recipe on a real robot (``twist_mux``, ``diff_drive_controller``'s ``cmd_vel_timeout``) is in
``docs/security.md``.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

__all__ = ["StampedCommands", "stamp_seconds", "LOG_EVERY_S"]

#: at most one /rosout line about dropped commands this often (seconds)
LOG_EVERY_S = 2.0


def stamp_seconds(header: Any) -> float | None:
    """A header's stamp in seconds (ROS 1 ``secs/nsecs`` or ROS 2 ``sec/nanosec``), None if it has none."""
    stamp = header.get("stamp") if isinstance(header, dict) else None
    if not isinstance(stamp, dict):
        return None
    secs = stamp.get("secs", stamp.get("sec"))
    nsecs = stamp.get("nsecs", stamp.get("nanosec", 0))
    if not isinstance(secs, int | float) or not isinstance(nsecs, int | float):
        return None
    return float(secs) + float(nsecs) * 1e-9


class StampedCommands:
    """The age check of stamped commands (see the module docstring). ``wall`` and ``mono`` are the clocks
    (injectable); ``say(text)`` puts a warning on /rosout."""

    def __init__(self, max_age: float, say: Callable[[str], None], wall: Callable[[], float] = time.time,
                 mono: Callable[[], float] = time.monotonic) -> None:
        self.max_age = max_age
        self.say = say
        self.wall, self.mono = wall, mono
        self.taken = 0
        self.dropped_stale = 0
        self.dropped_future = 0
        self.oldest_dropped_s = 0.0
        self._said_at = float("-inf")

    def judge(self, msg: dict[str, Any], topic: str) -> float | None:
        """The monotonic time the command was made, or None when it is dropped."""
        stamp = stamp_seconds(msg.get("header"))
        age = self.wall() - stamp if stamp is not None else float("inf")
        if age > self.max_age:
            self.dropped_stale += 1
            self.oldest_dropped_s = max(self.oldest_dropped_s, age)
            shown = "it has no stamp" if stamp is None or stamp == 0 else f"it is {age:.2f} s old"
            self._tell(f"Dropped a {topic} command: {shown} (limit {self.max_age:.2f} s, cmd_max_age)")
            return None
        if age < -self.max_age:
            self.dropped_future += 1
            self._tell(f"Dropped a {topic} command stamped {-age:.2f} s in the future: the clocks of the "
                       "operator's device and the robot are not in sync")
            return None
        self.taken += 1
        return self.mono() - max(0.0, age)

    def _tell(self, text: str) -> None:
        now = self.mono()
        if now - self._said_at >= LOG_EVERY_S:
            self._said_at = now
            self.say(text)
