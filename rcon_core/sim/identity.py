"""Who a simulated vessel is: its name, the namespace of its topics, where it starts and how it looks.

A sim without a name is the one robot it always was: node ``/kingfisher``, topics at the root
(``/cmd_vel``, ``/gps/fix``), GPS origin in Toronto's Inner Harbour, the plain camera scene.

A named sim (``rcon sim --name boat2``, ``SimServer(name="boat2")``) is one vessel of a fleet, laid out
the way a real fleet namespaces its robots (one ``ns`` per robot in the launch files):

* **namespaced** (``/boat2/...``): everything the vessel itself publishes, subscribes and serves -- its
  sensors (``/boat2/odom``, ``/boat2/gps/fix``, ``/boat2/camera/front/image_raw``...), its command topics
  (``/boat2/cmd_vel``, ``/boat2/speed_limit``), its services (``/boat2/dock``, ``/boat2/lights/set``,
  ``/boat2/reset_pose``), its ROS 2 action (``/boat2/navigate_to_fix``) and its node
  (``/boat2/kingfisher``, so ``/rosout`` lines, rosapi's node list and the logger services follow);
* **global** (unchanged): the ROS infrastructure the rosbridge server brings (``/rosout``,
  ``/rosout_agg``, ``/client_count``, ``/rosapi/*``, the bridge's own logger services, the ROS 2
  tutorial action ``/fibonacci``) and ``/map``,
  the harbour's chart, which a fleet shares from one map server;
* **frame ids stay as they are** (``base_link``, ``odom``...): each sim is its own TF tree.

That is the layout of robots that share one ROS graph. Robots that each run their own rosbridge (RCON's
fleet model: one link per robot, a canvas re-targeted to another boat keeps its topic names, the map
shows the same fix topic of every robot) usually keep the plain names: ``namespaced=False``
(``rcon sim --name boat2 --no-namespace``; the fleet demo's vessels) keeps every name as the unnamed
sim has it and changes only the start position and the camera scene.

Distinct vessels differ where an operator sees it: the **index** (the name's trailing number, ``boat2``
-> 2, or a stable hash of a name without one; 0 without a name) picks the GPS origin, on a spiral
a few hundred metres apart (each vessel starts at its own harbour's origin, so ``/odom`` starts at 0,0
as on a real robot), and the camera scene: the sky's tint, and the bow in the hull's colour with the
name painted on it at the bottom of the front camera.
"""

from __future__ import annotations

import math
import re
import zlib
from dataclasses import dataclass

from .vessel import EARTH_RADIUS_M

#: the unnamed sim's GPS origin (Toronto Inner Harbour)
BASE_LAT, BASE_LON = 43.6385, -79.3790
#: distance between neighbouring vessels' start positions (metres, spiral spacing)
SPACING_M = 300.0
_GOLDEN_ANGLE = math.radians(137.50776)
_NAME_RE = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")

#: per index (cycled from 1): (hull RGB, sky top RGB, sky horizon RGB); index 0 is the unnamed sim's sky
_SKIES: tuple[tuple[tuple[int, int, int], tuple[int, int, int], tuple[int, int, int]], ...] = (
    ((200, 40, 40), (150, 120, 200), (225, 205, 240)),   # red hull, violet dusk
    ((240, 200, 30), (230, 140, 80), (250, 215, 170)),   # yellow hull, orange sunset
    ((40, 160, 70), (90, 150, 120), (190, 225, 205)),    # green hull, sea-green haze
    ((30, 80, 200), (70, 90, 140), (170, 180, 205)),     # blue hull, overcast slate
    ((240, 240, 240), (200, 110, 150), (245, 200, 215)),  # white hull, pink dawn
    ((250, 120, 20), (60, 70, 110), (130, 140, 180)),    # orange hull, evening
)
DEFAULT_SKY = ((120, 170, 225), (200, 225, 245))


def check_name(name: str) -> str:
    """``name`` when it can be a ROS namespace (a letter, then letters, digits, ``_``), else ValueError."""
    if not isinstance(name, str) or not _NAME_RE.match(name):
        raise ValueError(f"robot name {name!r} must start with a letter and hold only letters, digits and _ "
                         "(it becomes the namespace of the robot's topics, /NAME/cmd_vel)")
    return name


def index_of(name: str | None) -> int:
    """0 without a name; the trailing number of ``boat2`` (2); else a stable number from 1 to 97."""
    if name is None:
        return 0
    digits = re.search(r"(\d+)$", name)
    if digits:
        return int(digits.group(1)) % 100_000
    return zlib.crc32(name.encode()) % 97 + 1


@dataclass(frozen=True)
class Identity:
    """A vessel's name, namespace, start position and looks (see the module docstring)."""

    name: str | None = None
    index: int = 0
    namespaced: bool = True

    @classmethod
    def of(cls, name: str | None = None, index: int | None = None, namespaced: bool = True) -> Identity:
        if name is not None:
            check_name(name)
        if index is not None and (isinstance(index, bool) or not isinstance(index, int) or index < 0):
            raise ValueError(f"robot index must be a non-negative integer, got {index!r}")
        return cls(name, index_of(name) if index is None else index, bool(namespaced))

    @property
    def namespace(self) -> str:
        """``/boat2`` for a named, namespaced vessel, else ``""``."""
        return f"/{self.name}" if self.name and self.namespaced else ""

    @property
    def node(self) -> str:
        return f"{self.namespace}/kingfisher"

    def topic(self, name: str) -> str:
        """The graph name of one of the vessel's own topics, services or actions (``/cmd_vel``...)."""
        return self.namespace + name

    @property
    def origin(self) -> tuple[float, float]:
        """The GPS origin (lat, lon) of this vessel's harbour: on a spiral, ``SPACING_M`` apart."""
        if self.index == 0:
            return BASE_LAT, BASE_LON
        radius = SPACING_M * math.sqrt(self.index)
        angle = self.index * _GOLDEN_ANGLE
        north, east = radius * math.sin(angle), radius * math.cos(angle)
        lat = BASE_LAT + math.degrees(north / EARTH_RADIUS_M)
        lon = BASE_LON + math.degrees(east / (EARTH_RADIUS_M * math.cos(math.radians(BASE_LAT))))
        return lat, lon

    @property
    def sky(self) -> tuple[tuple[int, int, int], tuple[int, int, int]]:
        """The camera's sky gradient (top, horizon)."""
        if self.index == 0:
            return DEFAULT_SKY
        _, top, horizon = _SKIES[(self.index - 1) % len(_SKIES)]
        return top, horizon

    @property
    def hull(self) -> tuple[int, int, int] | None:
        """The hull's colour (painted on the bow in the front camera); None for the unnamed sim."""
        if self.index == 0 and self.name is None:
            return None
        return _SKIES[(self.index - 1) % len(_SKIES)][0]

    @property
    def label(self) -> str:
        """What is painted on the bow: the name (upper case), else the index."""
        return (self.name or str(self.index)).upper()
