"""What the sans-I/O :class:`~rcon_core.bridge.session.Session` hands its shell, as data: a frame to write
(:class:`Outgoing`), a publish that was not written (:class:`Dropped`, or :data:`KEPT` for a latched value held
for the restore), and a service call waiting for its answer (:class:`Call`).  No I/O, no asyncio.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from .safety import bounded_repr

#: ``done(values, error)``: how a call's answer (``error`` None) or failure reaches its caller
Done = Callable[[Any, "BaseException | None"], None]


class Outgoing:
    """One frame to write: its bytes and, for a command, the monotonic time after which it must not be
    written (``deadline``, None: none) and the publisher it counts against (``pub``)."""

    __slots__ = ("data", "deadline", "pub")

    def __init__(self, data: bytes, deadline: float | None = None, pub: Any = None) -> None:
        self.data = data
        self.deadline = deadline
        self.pub = pub

    def __repr__(self) -> str:
        return f"Outgoing({bounded_repr(self.data, 60)}, deadline={self.deadline})"


class Dropped:
    """A publish that was not written, and why (counted where it was decided)."""

    __slots__ = ("reason",)

    def __init__(self, reason: str) -> None:
        self.reason = reason

    def __repr__(self) -> str:
        return f"Dropped({self.reason!r})"


class Kept:
    """A latched value published while down: held, sent right after the advertisement is restored."""

    __slots__ = ()

    def __repr__(self) -> str:
        return "KEPT"


#: the publish was made while the link was down (or before its advertisement was accepted)
DOWN = Dropped("link down")
KEPT = Kept()


class Call:
    """One service call: its id, service, frame, and where its answer goes (``done``)."""

    __slots__ = ("id", "name", "op", "done")

    def __init__(self, cid: str, name: str, op: dict[str, Any], done: Done | None) -> None:
        self.id = cid
        self.name = name
        self.op = op
        self.done = done

    def settle(self, values: Any, error: BaseException | None) -> None:
        done, self.done = self.done, None  # once
        if done is not None:
            done(values, error)
