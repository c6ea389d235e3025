"""What the parts of the bridge need of the client, as small protocols.

``BridgeClient`` (``client.py``) satisfies all of them; the modules that take a client (``nodes.py``,
``rosapi.py``, ``rosinfo.py``, ``params.py``) are typed against these instead of importing ``client.py``,
which imports them: the bridge has no import cycle even counting annotations (``tools/import_cycles.py
--typing``).  The session's own needs are ``session.Host``.
"""

from __future__ import annotations

from typing import Any, Protocol


class ServiceCaller(Protocol):
    """Calls services on the server (``rosapi.py``)."""

    call_timeout: float

    async def call_service(self, name: str, args: dict[str, Any] | list | None = None,
                           timeout: float | None = None) -> Any: ...


class RosClient(ServiceCaller, Protocol):
    """Also knows which ROS the server runs (``rosinfo.py``, ``params.py``)."""

    async def detect_ros(self, refresh: bool = False) -> Any: ...


class NodeClient(ServiceCaller, Protocol):
    """What a ``Node`` holds: the client's session (``session.Session``) and its service calls."""

    session: Any
