"""RCON's Foxglove WebSocket protocol link (``foxglove.sdk.v1``, ``foxglove.websocket.v1``).  No Qt.

``client.py`` is the async shell (connect, reconnect, stall watch), ``session.py`` the protocol state
machine (frames in, effects out), ``wire.py`` the frames, ``codecs.py`` the message encodings,
``catalog.py`` topics/services/graph/parameters, ``guard.py`` the view-only guard, ``ws.py`` the seam to the
WebSocket library.
"""

from .client import FoxgloveClient, NotFoxgloveError
from .session import CANNOT
from .wire import SUBPROTOCOLS

__all__ = ["CANNOT", "FoxgloveClient", "NotFoxgloveError", "SUBPROTOCOLS"]
