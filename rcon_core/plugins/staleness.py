"""When a widget's value is stale, and when a topic is static: the rules, in one small object (no Qt).

A subscriber is *stale* when no value came for ``stale_after`` seconds, except on a *static* topic, which
delivers once and then stays quiet by design (a latched ``/map``, a robot description):

- a topic that delivered exactly one message since subscribing, that one within :data:`NO_DATA_AFTER`
  seconds (or ``stale_after`` when longer; what a latched topic does: it sends its message on subscribe, a
  big map over a slow link taking a few seconds), counts as static until a second message arrives.
  rosbridge does not say whether a topic is latched; this is what it looks like from the client. A stream
  that dies right after its first message looks the same: the value's age still shows how old it is.
- the operator can say so: ``stale_after = 0`` means "static: never stale once a value came" (the widget
  still shows NO DATA when nothing came for :data:`NO_DATA_AFTER` seconds).
- ``stale_after = None``: never stale.

After the link comes back the subscription is made again and a latched topic delivers again, so the count
of deliveries starts over (:meth:`Staleness.resubscribed`).

:class:`Staleness` holds what the rules need (when the model started and subscribed, the deliveries since)
and judges a value's age; ``WidgetModel`` keeps one under its lock and feeds it the times. It reads no
clock itself, so the rules are tested with plain numbers.
"""

from __future__ import annotations

__all__ = ["NO_DATA_AFTER", "Staleness"]

#: with ``stale_after = 0`` (a static topic), how long nothing at all may come before NO DATA; also how
#: long a latched topic's one message may take to arrive after subscribing (at least)
NO_DATA_AFTER = 5.0


class Staleness:
    """The staleness rules of one subscriber (see the module docstring). Not locked: its owner locks."""

    __slots__ = ("started_at", "subscribed_at", "deliveries", "first_delivery")

    def __init__(self) -> None:
        self.started_at: float | None = None
        self.subscribed_at: float | None = None  # when the subscription was (re)made
        self.deliveries = 0  # messages since then
        self.first_delivery: float | None = None  # seconds from subscribing to the first of them

    def started(self, now: float) -> None:
        """The model started (and subscribed) at ``now``."""
        self.started_at = now
        self.resubscribed(now)

    def resubscribed(self, now: float) -> None:
        """The subscription was made again at ``now`` (the link came back): deliveries count afresh."""
        self.subscribed_at = now
        self.deliveries, self.first_delivery = 0, None

    def delivered(self, now: float) -> None:
        """A message arrived at ``now``."""
        self.deliveries += 1
        if self.deliveries == 1 and self.subscribed_at is not None:
            self.first_delivery = now - self.subscribed_at

    def static(self, has_value: bool, stale_after: float | None) -> bool:
        """Whether the value came from a static topic: the settings say so (``stale_after = 0``), or it
        looks latched (one delivery, right after subscribing). False before any value."""
        if not has_value:
            return False
        if stale_after == 0:
            return True
        window = max(NO_DATA_AFTER, stale_after or 0.0)
        return self.deliveries == 1 and self.first_delivery is not None and self.first_delivery <= window

    def judge(self, now: float, age: float | None, stale_after: float | None,
              watching: bool) -> tuple[bool, bool]:
        """``(stale, static)`` of a value ``age`` seconds old (None: no value yet) at ``now``; ``watching``:
        the model runs and subscribes (nothing else is ever stale)."""
        static = self.static(age is not None, stale_after)
        stale = False
        if stale_after is not None and watching:
            if age is None:  # nothing yet: NO DATA
                stale = now - (self.started_at if self.started_at is not None else now) > (
                    stale_after or NO_DATA_AFTER)
            elif not static:
                stale = age > stale_after
        return stale, static
