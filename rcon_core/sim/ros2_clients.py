"""``/connected_clients``: who is connected, as rosbridge 2.x publishes it (ROS 2 mode only).

rosbridge_server publishes ``rosbridge_msgs/msg/ConnectedClients`` beside ``/client_count`` whenever a
client connects or leaves (with a close handshake or without), latched: one entry per WebSocket client,
``ip_address`` and ``connection_time`` (``{sec, nanosec}``) in the order they connected
(``tests/recordings/rosbridge-ros2-2.1.0/publish_json.jsonl:21``, ``reconnect.jsonl:8-9, :15-16, :27-28``).
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING, Any

from .graph import BRIDGE_NODE

if TYPE_CHECKING:
    from .server import SimServer

TOPIC = "/connected_clients"


def advertise(server: SimServer) -> None:
    if server.ros2:
        server.advertise_internal(TOPIC, server.flavour.msg("rosbridge_msgs", "ConnectedClients"), BRIDGE_NODE,
                                  latched=True)
        server.publish(TOPIC, {"clients": []}, BRIDGE_NODE)


def publish(server: SimServer) -> None:
    """Publish the current clients (call after a client came or went)."""
    if not server.ros2 or TOPIC not in server.topics:
        return
    clients: list[dict[str, Any]] = []
    for conn in sorted(server.connections, key=lambda c: getattr(c, "connected_at", 0.0)):
        if not hasattr(conn, "connected_at"):
            conn.connected_at = time.time()
        address = getattr(conn.ws, "remote_address", None) or ("", 0)
        clients.append({"ip_address": str(address[0]), "connection_time": server.flavour.time(conn.connected_at)})
    server.publish(TOPIC, {"clients": clients}, BRIDGE_NODE)
