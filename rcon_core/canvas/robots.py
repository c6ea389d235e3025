"""The robots of a workspace: who the widgets talk to. Plain data and lookups, no behaviour, no Qt.

A workspace holds a list of :class:`Robot` (at least one; the first is the default). A widget's
:class:`~rcon_core.plugins.model.Binding` names its robot by id in ``binding.robot``; ``""`` means the
first robot, so a layout made with one robot (and every plugin, which never sets it) needs no change.

A robot's ``url`` ``""`` means "the URL of the app's connection bar" (``--url``, the URL history): what a
layout of format version 1, which stored no URL, migrates to. Its connection settings are the ones the
app keeps per URL (CA file, client certificate and key, whether it uses rosauth; the secret itself lives
in the OS credential store, never here) and ``view_only`` (the operator may watch but not command it).
``envelope`` is the robot's safety envelope (:class:`~rcon_core.bridge.envelope.Envelope`: its maximum
linear and angular speed; None: no limit), which every motion command sent to it is held to.
``colour`` ``""`` takes the colour of its position in :data:`PALETTE`. ``recording``: a recording file
played as the robot (Robots… → Recording file…): the app serves it on a player of its own at run time
(so no URL is kept for it) and the robot is view-only.
"""

from __future__ import annotations

from typing import Any

import attrs

from rcon_core.bridge.envelope import Envelope

__all__ = ["Robot", "PALETTE", "DEFAULT_ROBOT_ID", "default_robot", "robot_colour", "resolve_robot",
           "UnknownRobot", "robot_label", "mixes_robots"]

#: the id a migrated (version 1) or new workspace gives its one robot
DEFAULT_ROBOT_ID = "r-1"

#: robot colours, by position: Okabe-Ito's colour-blind-safe set, darkened where white text must read on it
PALETTE = ("#0072b2", "#d55e00", "#009e73", "#cc79a7", "#8f6200", "#3b7ea1", "#6a3d9a", "#000000")


@attrs.define
class Robot:
    """One robot of the workspace and how to reach it."""

    id: str
    name: str = ""
    url: str = ""  #: "" = the connection bar's URL
    ca_file: str = ""
    client_cert: str = ""
    client_key: str = ""
    auth: bool = False  #: sign an ``auth`` op with the secret kept for this URL
    view_only: bool = False  #: commands are refused: the operator only watches this robot
    colour: str = ""  #: "#rrggbb"; "" = PALETTE by position
    envelope: Envelope | None = None  #: the safety envelope its motion commands are held to (None: none)
    #: a recording file (.mcap, .bag, a rosbag2 folder) played as this robot, view-only; its URL is the
    #: player's, made at run time ("" = a live robot)
    recording: str = ""
    extra: dict[str, Any] = attrs.field(factory=dict)

    @property
    def label(self) -> str:
        return self.name or self.id

    def connection_settings(self) -> dict[str, Any]:
        """The app's per-URL connection settings (``AppConfig.robot_settings`` shape)."""
        return {"ca_file": self.ca_file, "client_cert": self.client_cert, "client_key": self.client_key,
                "auth": self.auth}


class UnknownRobot(KeyError):
    """A binding names a robot the workspace does not have."""

    def __str__(self) -> str:
        return f"robot {self.args[0]!r} is not in this workspace"


def default_robot() -> Robot:
    return Robot(DEFAULT_ROBOT_ID, "Robot")


def resolve_robot(robots: list[Robot], robot_id: str) -> Robot:
    """The robot a binding's ``robot`` names (``""``: the first). Raises :class:`UnknownRobot`."""
    if not robots:
        raise UnknownRobot(robot_id)
    if not robot_id:
        return robots[0]
    for r in robots:
        if r.id == robot_id:
            return r
    raise UnknownRobot(robot_id)


def robot_colour(robots: list[Robot], robot_id: str) -> str:
    """The robot's colour ("#rrggbb"): its own, else the palette's by position; black when unknown."""
    try:
        robot = resolve_robot(robots, robot_id)
    except UnknownRobot:
        return "#000000"
    return robot.colour or PALETTE[robots.index(robot) % len(PALETTE)]


def robot_label(robots: list[Robot], robot_id: str) -> str:
    try:
        return resolve_robot(robots, robot_id).label
    except UnknownRobot:
        return robot_id


def mixes_robots(robots: list[Robot], bindings: list[Any]) -> bool:
    """Whether these bindings (a canvas's widgets') talk to more than one robot."""
    ids = set()
    for b in bindings:
        try:
            ids.add(resolve_robot(robots, b.robot).id)
        except UnknownRobot:
            ids.add(b.robot)
    return len(ids) > 1
