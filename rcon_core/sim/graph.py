"""The simulated ROS graph: topics with their publishers/subscribers, services, nodes."""

from __future__ import annotations

import collections
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .connection import Connection

#: an in-process subscriber callback (the robot's own subscriptions)
InternalCallback = Callable[[dict[str, Any]], None]
#: a service handler run inside the sim: args (already converted) -> values
ServiceHandler = Callable[[dict[str, Any]], Awaitable[dict[str, Any]] | dict[str, Any]]

BRIDGE_NODE = "/rosbridge_websocket"
ROSAPI_NODE = "/rosapi"
ROSOUT_NODE = "/rosout"


class ServiceFailure(Exception):
    """A service handler failed; the text reaches the caller as ``values`` with ``result: false``."""


@dataclass
class Topic:
    """One topic of the simulated graph."""

    name: str
    type: str
    latched: bool = False
    publishers: collections.Counter[str] = field(default_factory=collections.Counter)
    internal_subscribers: dict[str, list[InternalCallback]] = field(default_factory=dict)
    client_subscribers: set[Connection] = field(default_factory=set)
    #: latched messages, one per publishing node (as /rosout is latched per node in ROS 1)
    latched_msgs: dict[str, dict[str, Any]] = field(default_factory=dict)
    seq: int = 0

    def has_subscribers(self) -> bool:
        return bool(self.client_subscribers) or any(self.internal_subscribers.values())

    def is_alive(self) -> bool:
        """Listed in rosapi while someone publishes or subscribes."""
        return bool(+self.publishers) or self.has_subscribers()

    def subscriber_nodes(self) -> list[str]:
        nodes = [n for n, cbs in self.internal_subscribers.items() if cbs]
        if self.client_subscribers:
            nodes.append(BRIDGE_NODE)
        return nodes


@dataclass
class Service:
    """A service the sim answers itself (robot or rosapi) or routes to the client that advertised it."""

    name: str
    type: str
    node: str
    handler: ServiceHandler | None = None
    provider: Connection | None = None
    counter: int = 0
    pending: dict[str, Any] = field(default_factory=dict)  # request id -> asyncio.Future
