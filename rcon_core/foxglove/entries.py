"""What the Foxglove session keeps of the server and of this client, and what the protocol cannot do.

:class:`Channel` (a server channel: topic, encoding, schema, RCON's type name), :class:`Service` (an advertised
service with its request and response schemas), :class:`ClientChannel` (a topic this client publishes,
shared by every node's Publisher), and the stand-ins for what a rosbridge session offers and this protocol
lacks (providing services, actions), which raise the sentences of :data:`CANNOT`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from rcon_core.bridge.errors import ActionError, BridgeError

from . import wire
from .codecs import Encode, type_name

if TYPE_CHECKING:
    from rcon_core.bridge.nodes import Publisher


#: what this protocol cannot do, in the operator's words (the link, the docs and the app say the same)
CANNOT = {
    "actions": "the Foxglove WebSocket protocol has no actions: this robot's actions cannot be listed, sent "
               "goals or cancelled over it (connect to its rosbridge server for actions)",
    "rosauth": "the Foxglove WebSocket protocol has no rosauth: the robot's secret is not used on this link "
               "(use wss:// with a client certificate to protect it)",
    "provide_service": "the Foxglove WebSocket protocol lets a client call services, not provide them",
    "delete_param": "the Foxglove WebSocket protocol cannot delete a parameter",
}
STATUS_LEVELS = {0: "info", 1: "warning", 2: "error"}


class Channel:
    __slots__ = ("id", "topic", "encoding", "schema_name", "schema_encoding", "schema", "type")

    def __init__(self, c: dict[str, Any]) -> None:
        self.id: int = c["id"]
        self.topic: str = c["topic"]
        self.encoding: str = c["encoding"]
        self.schema_name: str = c["schemaName"]
        self.schema_encoding: str = c["schemaEncoding"]
        self.schema: str = c["schema"]
        self.type = type_name(self.schema_name, self.schema_encoding)


class Service:
    __slots__ = ("id", "name", "type", "request", "response")

    def __init__(self, sid: int, name: str, type_: str, schemas: dict[str, Any]) -> None:
        self.id, self.name, self.type = sid, name, type_
        self.request, self.response = schemas["request"], schemas["response"]


class ClientChannel:
    """One client advertisement (a topic this client publishes), shared by every node's Publisher."""

    __slots__ = ("id", "topic", "type", "pubs", "latch", "active", "pending", "dropped", "head", "encode",
                 "encoding")

    def __init__(self, cid: int, topic: str, type_: str) -> None:
        self.id, self.topic, self.type = cid, topic, type_
        self.pubs: list[Publisher] = []
        self.latch = False
        self.active = False
        self.pending: Any = None
        self.dropped = 0
        self.head = wire.message_head(cid)
        self.encode: Encode | None = None
        self.encoding = ""


class _NoServices:
    """``session.services`` of the rosbridge session: here a client cannot provide services."""

    def add(self, srv: Any) -> None:
        raise BridgeError(CANNOT["provide_service"])

    def remove(self, srv: Any) -> None:
        pass


class _NoActions:
    def send(self, *args: Any, **kwargs: Any) -> Any:
        raise ActionError(CANNOT["actions"])

    def create(self, *args: Any, **kwargs: Any) -> Any:
        raise ActionError(CANNOT["actions"])

    def cancel(self, goal: Any) -> None:
        pass

    def disconnected(self) -> None:
        pass
