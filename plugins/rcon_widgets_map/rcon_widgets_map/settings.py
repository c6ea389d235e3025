"""Settings of the GPS map widget (per instance) and of the map kind (shared). Pure Python, no Qt."""

from __future__ import annotations

import os
import re
from pathlib import Path

import attrs
import platformdirs

from .geo import HEADING_PATHS
from .http_tiles import template_problems

_TOPIC = re.compile(r"/?[A-Za-z][A-Za-z0-9_]*(/[A-Za-z0-9_]+)*")


def topic_problem(name: str, what: str) -> str | None:
    """A sentence if ``name`` is not a usable ROS topic name, else None."""
    if not _TOPIC.fullmatch(name):
        return f"{what} {name!r} is not a valid ROS topic name"
    return None


def parse_extra_topics(text: str) -> list[tuple[str, str]]:
    """``"/a/fix, boat2=/b/fix"`` -> ``[("/a/fix", "/a/fix"), ("boat2", "/b/fix")]`` (label, topic).

    Entries are separated by commas, semicolons or new lines; ``label=/topic`` names a marker.
    Raises ValueError naming the first bad entry.
    """
    out: list[tuple[str, str]] = []
    for raw in re.split(r"[,;\n]+", text or ""):
        item = raw.strip()
        if not item:
            continue
        label, sep, topic = item.partition("=")
        label, topic = (label.strip(), topic.strip()) if sep else (item, item)
        if not label:
            label = topic
        problem = topic_problem(topic, "extra topic")
        if problem:
            raise ValueError(problem)
        if any(t == topic for _, t in out):
            raise ValueError(f"extra topic {topic!r} is listed twice")
        out.append((label, topic))
    return out


def _positive(_inst: object, attribute: attrs.Attribute, value: float) -> None:
    if not value > 0:
        raise ValueError(f"{attribute.name} must be more than 0, got {value!r}")


@attrs.define
class MapSettings:
    """Per-instance settings of ``map.gps``."""

    goal_topic: str = attrs.field(
        default="/goal/fix", validator=attrs.validators.instance_of(str),
        metadata={"label": "Goal topic",
                  "help": "Tap the map, confirm, and a sensor_msgs/NavSatFix is published here. Empty: no goals."},
    )
    navigate_action: str = attrs.field(
        default="", validator=attrs.validators.instance_of(str),
        metadata={"label": "Navigate action",
                  "help": "A ROS 2 action (e.g. /navigate_to_fix): long-press the map, tap 'Navigate here', and "
                          "a goal to that point is sent; Stop cancels it. Empty: no navigation"},
    )
    navigate_type: str = attrs.field(
        default="rcon_sim/action/NavigateToFix", validator=attrs.validators.instance_of(str),
        metadata={"label": "Its action type",
                  "help": "The action's type; the point goes into the first message of its goal with a "
                          "latitude and a longitude"},
    )
    extra_topics: str = attrs.field(
        default="", validator=attrs.validators.instance_of(str),
        metadata={"label": "More fixes",
                  "help": "Other NavSatFix topics to show, each with its own colour and trail, separated by "
                          "commas; 'name=/topic' labels one, e.g. 'operator=/phone/fix, /boat2/gps/fix'"},
    )
    every_robot: bool = attrs.field(
        default=False,
        metadata={"label": "Every robot",
                  "help": "Show the bound topic's fix of every robot of the workspace, each with its name and "
                          "colour (several robots in one workspace)"},
    )
    heading_topic: str = attrs.field(
        default="", validator=attrs.validators.instance_of(str),
        metadata={"label": "Heading topic",
                  "help": "Optional Imu/Odometry/PoseStamped topic giving the robot's heading; "
                          "otherwise the heading comes from successive fixes"},
    )
    heading_type: str = attrs.field(
        default="sensor_msgs/Imu", validator=attrs.validators.in_(tuple(HEADING_PATHS)),
        metadata={"label": "Heading type", "choices": list(HEADING_PATHS)},
    )
    mbtiles_path: str = attrs.field(
        default="", validator=attrs.validators.instance_of(str),
        metadata={"label": "Offline map (.mbtiles)", "help": "An MBTiles file on this device, used first"},
    )
    tile_url: str = attrs.field(
        default="", validator=attrs.validators.instance_of(str),
        metadata={"label": "Online tiles URL",
                  "help": "XYZ template, e.g. https://tile.openstreetmap.org/{z}/{x}/{y}.png; tiles are "
                          "cached on disk for offline use. Empty: offline only"},
    )
    follow: bool = attrs.field(default=True, metadata={"label": "Follow the robot"})
    fit_all: bool = attrs.field(
        default=False,
        metadata={"label": "Show every marker",
                  "help": "Open centred and zoomed on every marker (every robot, the extra fixes), and again "
                          "when one is out of view, until you pan or zoom; the Fit button brings it back. "
                          "Takes the place of following the robot"},
    )
    zoom: float = attrs.field(
        default=18.0, converter=float, validator=attrs.validators.and_(attrs.validators.ge(1.0),
                                                                       attrs.validators.le(21.0)),
        metadata={"label": "Zoom", "min": 1, "max": 21, "step": 1, "decimals": 1},
    )
    trail_length: int = attrs.field(
        default=600, validator=attrs.validators.and_(attrs.validators.instance_of(int),
                                                     attrs.validators.ge(0),
                                                     attrs.validators.le(100_000)),
        metadata={"label": "Trail points", "min": 0, "max": 100000,
                  "help": "How many recent positions each trail keeps (0: no trail)"},
    )
    trail_spacing_m: float = attrs.field(
        default=0.5, converter=float, validator=attrs.validators.ge(0.0),
        metadata={"label": "Trail spacing (m)", "min": 0, "max": 1000, "step": 0.5,
                  "help": "A fix closer than this to the last trail point is not added"},
    )
    stale_after: float = attrs.field(
        default=5.0, converter=float, validator=_positive,
        metadata={"label": "Stale after (s)", "min": 0.1, "max": 3600, "step": 1},
    )

    def problems(self) -> list[str]:
        out: list[str] = []
        if self.goal_topic.strip():
            p = topic_problem(self.goal_topic.strip(), "goal topic")
            if p:
                out.append(p)
        action = self.navigate_action.strip()
        if action:
            p = topic_problem(action, "navigate action")
            if p:
                out.append(p)
            if "/" not in self.navigate_type.strip():
                out.append("the navigate action needs its type, like rcon_sim/action/NavigateToFix")
        try:
            parse_extra_topics(self.extra_topics)
        except ValueError as exc:
            out.append(str(exc))
        if self.heading_topic.strip():
            p = topic_problem(self.heading_topic.strip(), "heading topic")
            if p:
                out.append(p)
        path = self.mbtiles_path.strip()
        if path and not Path(os.path.expanduser(path)).is_file():
            out.append(f"offline map file {path!r} does not exist")
        out += template_problems(self.tile_url.strip())
        return out


def default_cache_dir() -> str:
    """Where online tiles are kept: the user's cache directory (``~/.cache/rcon/tiles`` on Linux)."""
    return os.path.join(platformdirs.user_cache_dir("rcon"), "tiles")


@attrs.define
class MapPluginSettings:
    """Settings shared by every map: the tile cache."""

    cache_dir: str = attrs.field(
        default="", validator=attrs.validators.instance_of(str),
        metadata={"label": "Tile cache folder", "help": "Empty: the user's cache directory"},
    )
    memory_tiles: int = attrs.field(
        default=256, validator=attrs.validators.and_(attrs.validators.instance_of(int), attrs.validators.ge(16)),
        metadata={"label": "Tiles kept in memory", "min": 16, "max": 4096},
    )
    timeout_s: float = attrs.field(
        default=6.0, converter=float, validator=_positive,
        metadata={"label": "Tile download timeout (s)", "min": 0.5, "max": 60},
    )

    def resolved_cache_dir(self) -> str:
        return os.path.expanduser(self.cache_dir) if self.cache_dir.strip() else default_cache_dir()

    def problems(self) -> list[str]:
        return []
