"""The bridge clients of a workspace's robots, as the canvas runtime sees them. No Qt, no network.

::

    fleet = Fleet([(robot_a, client_a), (robot_b, client_b)])   # workspace order: the first is default
    fleet.client("")            # the first robot's client;  fleet.client("r-2") -> client_b
    fleet.robot("r-2")          # the Robot;  fleet.ids -> ["r-1", "r-2"]
    fleet.set_client("r-2", c)  # another client for that robot (the runtime restarts its widgets)
    fleet.view_only_reason("r-2")  # why it may not be commanded (Robot.view_only, or Fleet(view_only=...))
    rt = CanvasRuntime(plugin_manager, fleet, ...)               # a single client still works too

How a model gets its robot's port: the runtime makes each widget's node on the client of the robot its
binding names (``binding.robot``, ``""`` = the first) -- ``fleet.client(binding.robot).node(widget_id)``
-- so a model only ever sees that one robot, exactly as with one robot.

A widget that shows *every* robot (the GPS map) defines ``on_fleet(robots)`` on its model; the runtime
calls it before ``start()`` with one :class:`RobotPort` per robot of the workspace (its own robot's port
is the one the model was built with), and again when a robot's client changes. The model then subscribes
on each ``port``; the runtime closes those nodes when the widget stops. The model is told a robot's link
state through its optional ``on_robot_link(robot_id, up)``.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import Any, Protocol

from rcon_core.plugins.api import BridgePort, Publisher, RobotPort, Subscription

from .robots import Robot, UnknownRobot, resolve_robot, robot_colour

__all__ = ["Fleet", "RobotPort", "BridgeNode", "RobotClient"]


class BridgeNode(BridgePort, Protocol):
    """One widget's node of a robot's client, as the runtime wraps it in a ``GuardedPort``: a model's
    :class:`~rcon_core.plugins.model.BridgePort` plus ROS 2 action goals (``rcon_core.bridge.Node`` is one).

    The port passes a model's options on as they come; a node takes the options of its own kind (a
    ``Node``'s ``type``, ``throttle_rate``, ``latch``, ``timeout``...), which need not be any keywords at
    all: hence the open ``*args, **options`` here, which any such node fits."""

    def subscribe(self, topic: str, callback: Callable[[dict[str, Any]], Any],
                  *args: Any, **options: Any) -> Subscription: ...
    def advertise(self, topic: str, type: str, *args: Any, **options: Any) -> Publisher: ...
    def send_action_goal(self, action: str, action_type: str, *args: Any, **options: Any) -> Any: ...


class RobotClient(Protocol):
    """What the runtime needs of one robot's bridge client (``rcon_core.bridge.BridgeClient`` is one): a
    node per widget. Its link-state listeners (``add_state_listener``, ``add_status_listener``, ``state``)
    are optional: a client without them is taken to be connected."""

    def node(self, label: str) -> BridgeNode: ...


class Fleet:
    """Robot id -> bridge client, in the workspace's robot order."""

    def __init__(self, pairs: Iterable[tuple[Robot, RobotClient]], view_only: dict[str, str] | None = None) -> None:
        self._robots: list[Robot] = []
        self._clients: dict[str, RobotClient] = {}
        #: robot id -> why it may not be commanded, beyond its own ``view_only`` flag (the app's per-URL mark)
        self._view_only: dict[str, str] = dict(view_only or {})
        for robot, client in pairs:
            self._robots.append(robot)
            self._clients[robot.id] = client
        if not self._robots:
            raise ValueError("a fleet has at least one robot")

    @classmethod
    def single(cls, client: RobotClient, robot: Robot | None = None) -> Fleet:
        """One robot (the layouts and tests of before: a bare client)."""
        from .robots import default_robot

        return cls([(robot or default_robot(), client)])

    @property
    def robots(self) -> list[Robot]:
        return list(self._robots)

    @property
    def ids(self) -> list[str]:
        return [r.id for r in self._robots]

    def robot(self, robot_id: str) -> Robot:
        """The robot ``robot_id`` names (``""``: the first). Raises :class:`UnknownRobot`."""
        return resolve_robot(self._robots, robot_id)

    def resolve(self, robot_id: str) -> str:
        return self.robot(robot_id).id

    def client(self, robot_id: str = "") -> RobotClient:
        return self._clients[self.resolve(robot_id)]

    def colour(self, robot_id: str) -> str:
        return robot_colour(self._robots, robot_id)

    def set_client(self, robot_id: str, client: RobotClient) -> None:
        rid = self.resolve(robot_id)
        self._clients[rid] = client

    def set_view_only(self, robot_id: str, reason: str | None) -> None:
        rid = self.resolve(robot_id)
        if reason:
            self._view_only[rid] = reason
        else:
            self._view_only.pop(rid, None)

    def view_only_reason(self, robot_id: str = "") -> str | None:
        """Why ``robot_id`` may not be commanded (its ``view_only`` flag, or a mark given to the fleet)."""
        robot = self.robot(robot_id)
        if robot.id in self._view_only:
            return self._view_only[robot.id]
        return f"robot “{robot.label}” is view-only" if robot.view_only else None

    def items(self) -> list[tuple[Robot, Any]]:
        return [(r, self._clients[r.id]) for r in self._robots]

    def __contains__(self, robot_id: object) -> bool:
        if not isinstance(robot_id, str):
            return False
        try:
            self.resolve(robot_id)
        except UnknownRobot:
            return False
        return True
