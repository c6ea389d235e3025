"""RCON's rosbridge v2 client (asyncio + websockets).  No Qt.  See ``client.py`` for behaviour decisions."""

from .client import BridgeClient, ConnectionState
from .errors import (
    ActionError,
    ActionTimeoutError,
    BridgeError,
    ConnectionLostError,
    NotConnectedError,
    ProtocolError,
    ServiceError,
    ServiceTimeoutError,
)
from .nodes import ActionGoal, GoalStatus, Node, Publisher, ServiceServer, Subscription

__all__ = [
    "ActionError", "ActionGoal", "ActionTimeoutError", "BridgeClient", "BridgeError", "ConnectionLostError",
    "ConnectionState", "GoalStatus", "Node", "NotConnectedError", "ProtocolError", "Publisher", "ServiceError",
    "ServiceServer", "ServiceTimeoutError", "Subscription",
]
