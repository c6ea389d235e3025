"""The fleet demo (``rcon --demo --robots N``): N embedded vessels, one workspace, one canvas for them all.

Each vessel is its own :class:`~rcon_core.sim.SimServer` (named ``boat1`` ... ``boatN``: it starts a few
hundred metres from the others and its camera has its own sky and its name on the bow; see
``rcon_core/sim/identity.py``) on its own free loopback port, in its own thread. Like boats that each run
their own rosbridge, the vessels keep the plain topic names (``/cmd_vel`` on every one; ``namespace=False``):
which vessel a widget talks to is its binding's robot, so a canvas re-targeted to another boat works
as it is and the map shows the same fix topic of every robot. The workspace has one robot per vessel
(``r-1`` ... ``r-N``, named after the vessel) and:

- canvas **Fleet**: a tile per vessel with its front camera beside its teleop pad (each pad is bound to
  its own vessel and publishes only there) and one GPS map with every vessel's fix (``every_robot``) that
  opens showing them all (``fit_all``). :func:`fleet_layout` lays them out to fill the screen the app
  starts on (measured by :func:`fit_fleet` on the first start; a 1024x600 tablet's room otherwise): each
  pad's disc at least 160 px across, every tap target at least 48 px, the map beside the tiles or in the
  free slot of the last row. What does not fit in the height continues below (the canvas scrolls down,
  never sideways): at 1280x800 with the side panel open two or three vessels fit on one screen, at
  1024x600 one row of two vessels (and the map, for two);
- canvas **Drive · boatK** per vessel: the single-robot demo's Drive canvas, bound to that vessel.

Every vessel has the single-robot demo's safety envelope (``DEMO_ENVELOPE``).

No Qt at import: the window wires the links (``rcon_core/app/main.py``); :func:`fleet_room` measures a
window.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from typing import TYPE_CHECKING, Any, Protocol

import attrs

from rcon_core.canvas import Canvas, Geometry, WidgetInstance, Workspace, new_id
from rcon_core.canvas.robots import Robot
from rcon_core.plugins import Binding, PluginManager, Role

from .demo import DEMO_ENVELOPE, DRIVE, pick_kind

if TYPE_CHECKING:  # the window's side (Qt) only where there is a window
    from .canvas_controller import CanvasController
    from .fleet_ui import FleetUi


class FleetWindow(Protocol):
    """What the helpers below use of a window: its canvases and its robots."""

    @property
    def controller(self) -> CanvasController: ...

    @property
    def fleet_ui(self) -> FleetUi: ...

MAX_ROBOTS = 6  #: the sim has six distinct camera scenes
GAP = 16  #: between tiles and from the canvas's edge (the canvas grid: every rect below stays on it)
#: the smallest frames of a vessel's tile, in canvas units at 48 px touch targets and the standard text
#: size: the camera (its title "boat1 · Camera" whole; ``widget_frame.frame_min_size`` is 144 x 112) and
#: the teleop pad, whose disc is then at least 160 px across (its frame holds the title bar, the axis
#: labels and the status line besides)
CAMERA_MIN = (160, 112)
PAD_MIN = (208, 256)
#: the pad's frame is this much narrower than tall when its disc fills it both ways (title, labels)
PAD_ASPECT_PX = 55
#: the map: room for its 2x2 block of touch-sized buttons in a corner and for the markers beside them
MAP_MIN = (192, 256)
TILE_MIN_W = CAMERA_MIN[0] + GAP + PAD_MIN[0]
#: the Fleet canvas's view on a 1024x600 tablet in Operate mode (below the bars, no side panel): what the
#: layout fills when no window is there to measure (``rcon --demo --robots N`` measures its own)
DEFAULT_ROOM = (1024, 392)
#: the width a vertical scroll bar takes from the view when the layout is taller than it
DEFAULT_BAR = 32


@attrs.frozen
class FleetLayout:
    """Where the Fleet canvas's widgets go (canvas units): each vessel's camera and pad, and the map."""

    tiles: tuple[tuple[tuple[int, int, int, int], tuple[int, int, int, int]], ...]
    map: tuple[int, int, int, int]
    rows: int = 1  #: rows of slots (a vessel's tile, or the map, in each)
    shown: int = 1  #: of which the first screenful shows this many

    @property
    def hidden_rows(self) -> int:
        """Rows below the first screenful (0: everything in sight without scrolling)."""
        return self.rows - self.shown

    @property
    def map_in_sight(self) -> bool:
        """Whether the map starts on the first screenful."""
        slot_h = self.tiles[0][0][3] if self.tiles else self.map[3]
        return self.map[1] < GAP + self.shown * (slot_h + GAP)

    def pad_diameter(self) -> int:
        """The teleop pads' disc (the smallest), as the pad view draws it in such a frame."""
        return min(min(w - 36, h - 91) for _cam, (_x, _y, w, h) in self.tiles) if self.tiles else 0


def _down(value: float) -> int:
    return int(value // GAP * GAP)


def _up(value: float) -> int:
    return int(-(-value // GAP) * GAP)


def fleet_layout(n: int, room: tuple[int, int] = DEFAULT_ROOM, bar: int = DEFAULT_BAR) -> FleetLayout:
    """Lay ``n`` vessel tiles (camera beside pad) and the map out to fill ``room`` (the canvas view's width
    and height): every pad at least :data:`PAD_MIN` (a disc of 160 px), every camera at least
    :data:`CAMERA_MIN`, the map at least :data:`MAP_MIN`, all on the grid. Of the arrangements (1..n tile
    columns; the map as a column right of the tiles, or in the free slots of the last row) the best is
    the one that hides the fewest rows below the screen, then keeps the map in sight, then has the largest
    pads, then the most even camera and map. What does not fit in the room's height continues below (the
    canvas scrolls down, never sideways: ``bar`` is the width the scroll bar then takes)."""
    best: tuple[tuple[float, ...], FleetLayout] | None = None
    for cols in range(1, max(1, n) + 1):
        for map_beside in (True, False):
            for scrolled in (False, True):
                width = room[0] - (bar if scrolled else 0)
                layout = _arrange(n, cols, map_beside, width, room[1])
                if layout is None or (layout.hidden_rows > 0) != scrolled:
                    continue
                score = _score(layout)
                if best is None or score < best[0]:
                    best = (score, layout)
    if best is None:  # a room narrower than one tile: one column, as narrow as a tile gets
        layout = _arrange(n, 1, False, max(room[0], TILE_MIN_W + 2 * GAP) - bar, room[1], force=True)
        assert layout is not None
        return layout
    return best[1]


def _arrange(n: int, cols: int, map_beside: bool, width: int, height: int,
             force: bool = False) -> FleetLayout | None:
    right = width - GAP  # nothing may end past this (the canvas keeps a GAP of margin)
    tiles_end = right - (MAP_MIN[0] + GAP if map_beside else 0)  # where the last column ends
    slot_w = _down((tiles_end - GAP - (cols - 1) * GAP) / cols)
    if slot_w < TILE_MIN_W and not force:
        return None
    slot_w = max(slot_w, TILE_MIN_W)
    slots = n if map_beside else n + 1
    rows = -(-slots // cols)
    shown = max(1, min(rows, (height - GAP) // (PAD_MIN[1] + GAP)))
    slot_h = max(PAD_MIN[1], _down((height - GAP) / shown - GAP))
    # the pad as wide as its disc needs for the slot's height, at most half the tile (the camera gets the rest)
    pad_w = min(max(PAD_MIN[0], _up(slot_h - PAD_ASPECT_PX)), slot_w - GAP - CAMERA_MIN[0],
                max(PAD_MIN[0], _down((slot_w - GAP) / 2)))
    cam_w = slot_w - GAP - pad_w
    tiles = []
    for k in range(n):
        x, y = GAP + (k % cols) * (slot_w + GAP), GAP + (k // cols) * (slot_h + GAP)
        tiles.append(((x, y, cam_w, slot_h), (x + cam_w + GAP, y, pad_w, slot_h)))
    if map_beside:
        x = GAP + cols * (slot_w + GAP)
        map_rect = (x, GAP, right - x, shown * (slot_h + GAP) - GAP)
    else:
        x, y = GAP + (n % cols) * (slot_w + GAP), GAP + (n // cols) * (slot_h + GAP)
        map_rect = (x, y, right - x, slot_h)
    if map_rect[2] < MAP_MIN[0] and not force:
        return None
    return FleetLayout(tuple(tiles), map_rect, rows, shown)


def _score(layout: FleetLayout) -> tuple[float, ...]:
    """Smaller is better: rows out of sight, the map out of sight, small pads, an uneven camera and map."""
    _x, _y, w, h = layout.map
    camera = layout.tiles[0][0] if layout.tiles else (0, 0, 0, 0)
    return (layout.hidden_rows, float(not layout.map_in_sight), -layout.pad_diameter(),
            -min(camera[2] * camera[3], w * h))


def vessel_name(k: int) -> str:
    """The k-th vessel's name (1-based): ``boat1``..."""
    return f"boat{k}"


def robot_id(k: int) -> str:
    return f"r-{k}"


def check_count(n: Any) -> int:
    if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= MAX_ROBOTS:
        raise ValueError(f"--robots must be a whole number from 1 to {MAX_ROBOTS}, got {n!r}")
    return n


def _widget(plugins: PluginManager, kinds: dict[str, dict[str, Any]], binding: Binding,
            rect: tuple[int, int, int, int], title: str) -> WidgetInstance:
    kind = pick_kind(plugins, list(kinds))
    settings = dict(kinds[kind])
    if plugins.has_widget(kind):
        spec = plugins.widget(kind)
        try:  # the stored form of the settings object: every field, defaults filled in
            settings = spec.settings_to_dict(spec.make_settings(settings))
        except Exception:
            pass  # kept as written; the widget shows what is wrong with it
    return WidgetInstance(new_id("w"), kind, binding, Geometry(*rect), settings, title)


def _map_settings(plugins: PluginManager) -> dict[str, Any]:
    """The map's settings: every robot's fix, all of them in view, as far as this map knows how
    (``every_robot``, then ``fit_all``)."""
    out: dict[str, Any] = {}
    if plugins.has_widget("map.gps"):
        spec = plugins.widget("map.gps")
        for name in ("every_robot", "fit_all"):
            try:
                spec.make_settings({**out, name: True})
            except Exception:
                break  # an older map without the setting: it shows what it can
            out[name] = True
    return out


def fleet_canvas(n: int, plugins: PluginManager, room: tuple[int, int] = DEFAULT_ROOM,
                 bar: int = DEFAULT_BAR) -> Canvas:
    """The Fleet canvas, laid out by :func:`fleet_layout` to fill ``room`` (the canvas view's size)."""
    canvas = Canvas(new_id("c"), "Fleet", locked=True)
    layout = fleet_layout(n, room, bar)
    for k, (camera, pad) in enumerate(layout.tiles, start=1):
        rid = robot_id(k)
        canvas.widgets.append(_widget(
            plugins, {"sensors.image": {"max_fps": 15.0}},
            Binding("/camera/front/image_raw", "sensor_msgs/Image", Role.SUBSCRIBE, (), robot=rid),
            camera, "Camera"))
        canvas.widgets.append(_widget(
            plugins, {"sensors.teleop": {"max_linear": 2.0, "max_angular": 1.0}},
            Binding("/cmd_vel", "geometry_msgs/Twist", Role.PUBLISH, (), robot=rid), pad, "Drive"))
    # one map, bound to the first vessel's fix; with every_robot it shows every vessel's (on_fleet)
    canvas.widgets.append(_widget(
        plugins, {"map.gps": _map_settings(plugins)},
        Binding("/gps/fix", "sensor_msgs/NavSatFix", Role.SUBSCRIBE, (), robot=robot_id(1)),
        layout.map, "Map of every vessel"))
    return canvas


def drive_canvas(k: int, plugins: PluginManager) -> Canvas:
    canvas = Canvas(new_id("c"), f"Drive · {vessel_name(k)}", locked=True)
    for title, kinds, target, type_name, role, paths, rect in DRIVE:
        canvas.widgets.append(_widget(plugins, kinds, Binding(target, type_name, role, paths, robot=robot_id(k)),
                                      rect, title))
    return canvas


def fleet_workspace(n: int, plugins: PluginManager, room: tuple[int, int] | None = None,
                    bar: int = DEFAULT_BAR) -> Workspace:
    """The fleet demo's workspace for ``n`` vessels (robots ``r-1``.. with empty URLs: the app connects
    them to the sims' run-time ports, which are never saved); its Fleet canvas fills ``room`` (default:
    :data:`DEFAULT_ROOM`, a 1024x600 tablet's)."""
    check_count(n)
    canvases = [fleet_canvas(n, plugins, room or DEFAULT_ROOM, bar)] + [drive_canvas(k, plugins)
                                                                        for k in range(1, n + 1)]
    ws = Workspace(canvases, canvases[0].id)
    ws.robots = [Robot(robot_id(k), vessel_name(k), envelope=DEMO_ENVELOPE) for k in range(1, n + 1)]
    return ws


def fleet_room(window: FleetWindow) -> tuple[tuple[int, int], int]:
    """The room the Fleet canvas gets in ``window`` as it is now (once its layout has settled): the canvas
    view's size without scroll bars, and the width a vertical scroll bar takes from it."""
    from qtpy import QtCore, QtWidgets  # the window's side: Qt only when there is a window

    for _ in range(3):
        QtWidgets.QApplication.sendPostedEvents(None, QtCore.QEvent.Type.LayoutRequest)
    scroll = window.controller.surface.scroll_area
    if scroll is None:
        raise RuntimeError("the canvas view is not built yet")
    size = scroll.maximumViewportSize()
    bar = scroll.verticalScrollBar().sizeHint().width()
    return (size.width(), size.height()), bar


def fit_fleet(window: FleetWindow, n: int, plugins: PluginManager) -> None:
    """Lay the fleet demo's workspace out afresh for ``window``'s canvas room (its first start: the layout
    fills the screen it is on). Replaces the workspace: call it before the robots connect."""
    room, bar = fleet_room(window)
    window.controller.doc.replace_workspace(fleet_workspace(n, plugins, room, bar))


def connect_fleet(window: FleetWindow, urls: list[str]) -> None:
    """Connect the window's robots to the sims: the first through the connection bar, the others with
    run-time URLs. None of them is remembered (the ports are gone after this run)."""
    window.fleet_ui.connect_robot("", urls[0])  # the first robot: the connection bar, not remembered
    for k, url in enumerate(urls[1:], start=2):
        window.fleet_ui.connect_robot(robot_id(k), url)


@contextlib.contextmanager
def fleet_sims(n: int, **kwargs: Any) -> Iterator[list[Any]]:
    """N named SimServers (boat1..), each on its own free loopback port and its own thread, with the plain
    topic names (``namespace=False``: each vessel has its own rosbridge)."""
    from rcon_core.sim import SimServer

    check_count(n)
    kwargs.setdefault("namespace", False)
    with contextlib.ExitStack() as stack:
        yield [stack.enter_context(SimServer.in_thread(port=0, name=vessel_name(k), **kwargs))
               for k in range(1, n + 1)]
