"""RCON's rosbridge v2 client (asyncio + websockets).  No Qt.  See ``client.py`` for behaviour decisions."""

from .client import BridgeClient, ConnectionState
from .errors import (
    ActionError,
    ActionTimeoutError,
    AuthRefusedError,
    BridgeError,
    ConnectionLostError,
    LinkSettingsError,
    NotConnectedError,
    ProtocolError,
    ServiceError,
    ServiceTimeoutError,
)
from .nodes import ActionGoal, GoalStatus, Node, Publisher, ServiceServer, Subscription

__all__ = [
    "ActionError", "ActionGoal", "ActionTimeoutError", "AuthRefusedError", "BridgeClient", "BridgeError", "ConnectionLostError",
    "ConnectionState", "GoalStatus", "LinkSettingsError", "Node", "NotConnectedError", "ProtocolError", "Publisher", "ServiceError",
    "ServiceServer", "ServiceTimeoutError", "Subscription",
]
