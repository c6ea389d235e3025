"""What a started sim holds besides the bridge itself: rosapi, the ROS 2 action hub, the robot and its action.

:func:`furnish` is called by ``SimServer.start()`` once the server's own topics (``/rosout``,
``/client_count``) exist and before the socket is bound. It is kept apart from ``server.py`` so that the
server knows nothing of the robot or of rosapi (they use the server's public graph API: ``publish``,
``add_service``, ``advertise_internal``...), and none of them imports the server back.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from . import ros2_rosapi, rosapi
from .actions import NavigateActionServer
from .robot_node import RobotNode
from .ros2_actions import ActionHub, FibonacciServer

if TYPE_CHECKING:
    from .server import SimServer


def furnish(server: SimServer) -> None:
    """Install rosapi (ROS 1 or 2 flavour), the action hub with its demo action (ROS 2), and, unless the
    server was made with ``robot=False``, the robot's node (started) and its navigate action (ROS 2)."""
    if server.ros2:
        server.action_hub = ActionHub(server)
        server.action_hub.add(FibonacciServer(server.action_hub))
        ros2_rosapi.install(server)
    else:
        rosapi.install(server)
    if not server.with_robot:
        return
    server.robot_node = RobotNode(server, identity=server.identity)
    server.robot = server.robot_node.vessel
    server.robot_node.start()
    if server.ros2:
        server.navigate_action = NavigateActionServer(server, server.robot_node)
        server.action_hub.add(server.navigate_action)
