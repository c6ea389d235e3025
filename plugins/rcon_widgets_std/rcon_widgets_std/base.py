"""The standard widgets' common model base: learns unknown types from the robot, runs small tasks."""

from __future__ import annotations

import asyncio
from collections.abc import Coroutine
from typing import Any

from rcon_core.plugins import WidgetModel

from .common import learn_type

__all__ = ["StdModel"]


class StdModel(WidgetModel):
    """A :class:`WidgetModel` that makes sure its type is known.

    When the registry it was given lacks the bound type (a lab's own message, a type never seen), the
    model asks the robot for its typedefs (``/rosapi/message_details`` or the service details) when it
    starts, then calls :meth:`on_types_ready`.
    """

    #: False for models that never need the definition (a Label only reads what arrives)
    needs_types = True

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self._types_ready = False

    # -- types ---------------------------------------------------------------------------------------
    @property
    def types_ready(self) -> bool:
        """True once the bound type's definition is in the registry."""
        return self._types_ready or self.type_known()

    def type_known(self) -> bool:
        t = self.binding.type
        if not t:
            return False
        return bool(self.types.has_service(t) if self.binding.role.is_service else self.types.has(t))

    def on_start(self) -> None:
        if self.binding.problems() or not self.needs_types:
            return
        if self.type_known():
            self._types_ready = True
            self.on_types_ready()
            return
        self.spawn(self._learn())

    async def _learn(self) -> None:
        try:
            ok = await learn_type(self.port, self.types, self.binding.type, self.binding.role.is_service)
        except Exception as exc:
            self.set_error(f"cannot learn type {self.binding.type} from the robot: {exc}")
            return
        if not ok:
            self.set_error(f"the robot does not know the type {self.binding.type}")
            return
        self._types_ready = True
        self.on_types_ready()

    def on_types_ready(self) -> None:
        """Hook: the bound type is known (at start, or once learned from the robot). Loop thread."""

    # -- tasks ---------------------------------------------------------------------------------------
    def spawn(self, coro: Coroutine[Any, Any, Any]) -> asyncio.Task[Any] | None:
        """Run ``coro`` on the running (bridge) loop; cancelled by :meth:`stop`. Call on the loop thread."""
        try:
            loop = asyncio.get_running_loop()
        except RuntimeError:
            coro.close()
            self.set_error("this widget needs the bridge loop: pass dispatch=BridgeThread.call")
            return None
        task = loop.create_task(coro)
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)
        return task
