"""RCON's rosbridge v2 client (asyncio + websockets).  No Qt.  ``client.py`` says where each behaviour is decided
(the connection there, the protocol state in ``session.py``, the websockets adapter in ``wslink.py``...)."""

from .action_server import ActionServer, ServedGoal
from .client import BridgeClient, ConnectionState
from .errors import (
    ActionError,
    ActionNoAnswerError,
    ActionTimeoutError,
    AuthRefusedError,
    BridgeError,
    ConnectionLostError,
    LinkSettingsError,
    NotConnectedError,
    ProtocolError,
    RosapiRefusedError,
    ServiceError,
    ServiceTimeoutError,
)
from .guard import LinkGuard, ViewOnlyError
from .nodes import ActionGoal, GoalStatus, Node, Publisher, ServiceServer, Subscription
from .params import ParamNotFoundError, ParamRejectedError
from .rosinfo import RosInfo
from .stats import BridgeStats

__all__ = [
    "ActionError", "ActionGoal", "ActionNoAnswerError", "ActionServer", "ActionTimeoutError", "AuthRefusedError",
    "BridgeClient", "BridgeError", "BridgeStats", "ConnectionLostError", "ConnectionState", "GoalStatus", "LinkGuard",
    "LinkSettingsError", "Node", "NotConnectedError", "ParamNotFoundError", "ParamRejectedError", "ProtocolError",
    "Publisher", "RosInfo", "RosapiRefusedError", "ServedGoal", "ServiceError", "ServiceServer",
    "ServiceTimeoutError", "Subscription", "ViewOnlyError",
]
