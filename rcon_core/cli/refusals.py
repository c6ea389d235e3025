"""What the robot refused, for ``rcon pub`` and ``rcon echo``: a type it cannot load, a failed op.

rosbridge 0.11 refuses a type only in its log, so a type that is not standard is asked about first
(:class:`rcon_core.bridge.typecheck.TypeChecker`); newer servers send a ``status`` frame naming the op,
which :class:`StatusErrors` collects.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from typing import Any

from rcon_core.bridge.typecheck import TypeChecker, status_failure


async def type_refusal(client: Any, type_name: str | None, timeout: float = 10.0) -> str | None:
    """The sentence to print when the robot does not know ``type_name``; None when it does (or cannot
    tell, or the type is standard)."""
    if not type_name:
        return None
    try:
        return await asyncio.wait_for(TypeChecker(client).problem(type_name), timeout)
    except TimeoutError:
        return None


class StatusErrors:
    """Error ``status`` frames about one topic's subscribe/advertise ops (servers that send them)."""

    def __init__(self, client: Any, topic: str) -> None:
        self.topic = topic
        self.errors: list[str] = []
        self.event = asyncio.Event()
        add = getattr(client, "add_status_listener", None)
        self._remove: Callable[[], None] | None = add(self._on_status) if add is not None else None

    def _on_status(self, frame: dict[str, Any]) -> None:
        failure = status_failure(frame)
        if failure is not None and failure[0] == self.topic:
            self.errors.append(failure[1])
            self.event.set()

    def sentence(self) -> str:
        return f"the robot refused {self.topic}: {self.errors[0]}" if self.errors else ""

    def close(self) -> None:
        if self._remove is not None:
            self._remove()
            self._remove = None


async def silent_for(seconds: float, last_seen: Callable[[], float]) -> None:
    """Return once ``seconds`` have passed since ``last_seen()`` (loop time) without a newer value."""
    loop = asyncio.get_running_loop()
    while True:
        remaining = last_seen() + seconds - loop.time()
        if remaining <= 0:
            return
        await asyncio.sleep(remaining)
