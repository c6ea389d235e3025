"""RCON's rosbridge v2 client (asyncio + websockets).  No Qt.  See ``client.py`` for behaviour decisions."""

from .client import BridgeClient, ConnectionState
from .errors import (
    ActionError,
    BridgeError,
    ConnectionLostError,
    NotConnectedError,
    ProtocolError,
    ServiceError,
    ServiceTimeoutError,
)
from .nodes import ActionGoal, Node, Publisher, ServiceServer, Subscription

__all__ = [
    "ActionError", "ActionGoal", "BridgeClient", "BridgeError", "ConnectionLostError", "ConnectionState",
    "Node", "NotConnectedError", "ProtocolError", "Publisher", "ServiceError", "ServiceServer",
    "ServiceTimeoutError", "Subscription",
]
