"""A widget that tries to command the robot whatever the app says (publish, call, serve), and to reach the
raw bridge client through its port. Used by the view-only tests; no Qt here (the app test adds a view)."""

from __future__ import annotations

import asyncio
from typing import Any

from rcon_core.bridge import BridgeClient
from rcon_core.bridge.nodes import Node
from rcon_core.plugins import Accepts, WidgetModel, WidgetSpec, hookimpl

CMD = {"linear": {"x": 1.5, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.0}}


def find_raw(obj: Any, depth: int = 4, seen: set[int] | None = None) -> list[str]:
    """Paths of attributes (not dunder) under ``obj`` that lead to a bridge Node or BridgeClient."""
    seen = set() if seen is None else seen
    if id(obj) in seen or depth < 0:
        return []
    seen.add(id(obj))
    if isinstance(obj, (Node, BridgeClient)):
        return [type(obj).__name__]
    found: list[str] = []
    if isinstance(obj, dict):
        children = list(obj.items())
    elif isinstance(obj, (list, tuple, set, frozenset)):
        children = list(enumerate(obj))
    elif isinstance(obj, (str, bytes, int, float, bool, type(None))):
        return []
    else:
        children = []
        for name in dir(obj):
            if name.startswith("__"):
                continue
            try:
                children.append((name, getattr(obj, name)))
            except Exception:
                continue
    for key, value in children:
        found += [f"{key}.{p}" for p in find_raw(value, depth - 1, seen)]
    return found


class RogueModel(WidgetModel):
    """On start: advertises and publishes on /cmd_vel, serves /rogue/serve, calls /lights/set, and looks
    for the raw client behind its port. ``attempts`` says what each try gave."""

    def on_start(self) -> None:
        self.attempts: dict[str, str] = {}
        self.raw_paths = find_raw(self.port)
        port = self.port
        pub = port.advertise("/cmd_vel", "geometry_msgs/Twist")
        for what, fn in (
            ("publish", lambda: pub.publish(CMD)),
            ("serve", lambda: port.advertise_service("/rogue/serve", "std_srvs/Trigger",
                                                     lambda _req: {"success": True, "message": "rogue"})),
        ):
            try:
                fn()
                self.attempts[what] = "sent"
            except Exception as exc:
                self.attempts[what] = f"{type(exc).__name__}: {exc}"
        self.publish(CMD)  # through the base class too (role publish on /cmd_vel)
        self._call_task = asyncio.ensure_future(self._call())

    async def _call(self) -> None:
        try:
            await self.port.call_service("/lights/set", {"data": True}, timeout=5.0)
            self.attempts["call"] = "sent"
        except Exception as exc:
            self.attempts["call"] = f"{type(exc).__name__}: {exc}"


class RoguePlugin:
    """Registers ``test.rogue`` (model only; ``view`` may be given for the app test)."""

    def __init__(self, view: Any = None) -> None:
        self.view = view

    @hookimpl
    def rcon_register_widgets(self, registry: Any) -> None:
        registry.add(WidgetSpec(kind="test.rogue", title="Rogue", model=RogueModel, view=self.view,
                                roles=["publish"], accepts=Accepts(messages=["twist"]), default_size=(200, 120)))
