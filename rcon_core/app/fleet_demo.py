"""The fleet demo (``rcon --demo --robots N``): N embedded vessels, one workspace, one canvas for them all.

Each vessel is its own :class:`~rcon_core.sim.SimServer` (named ``boat1`` ... ``boatN``: it starts a few
hundred metres from the others and its camera has its own sky and its name on the bow; see
``rcon_core/sim/identity.py``) on its own free loopback port, in its own thread. Like boats that each run
their own rosbridge, the vessels keep the plain topic names (``/cmd_vel`` on every one; ``namespace=False``):
which vessel a widget talks to is its binding's robot, so a canvas re-targeted to another boat works
as it is and the map shows the same fix topic of every robot. The workspace has one robot per vessel
(``r-1`` ... ``r-N``, named after the vessel) and:

- canvas **Fleet**: a tile per vessel with its front camera beside its teleop pad (each pad is bound to
  its own vessel and publishes only there), the tiles in a grid (one column for two vessels, two for more),
  and right of them one GPS map with every vessel's fix (``every_robot``) that opens showing them all
  (``fit_all``). Up to four vessels the canvas fits a 1024x600 tablet and a 1280x800 window with the side
  panel open, without scrolling (:func:`fleet_canvas`);
- canvas **Drive · boatK** per vessel: the single-robot demo's Drive canvas, bound to that vessel.

Every vessel has the single-robot demo's safety envelope (``DEMO_ENVELOPE``).

No Qt here: the window wires the links (``rcon_core/app/main.py``).
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from typing import Any

from rcon_core.canvas import Canvas, Geometry, WidgetInstance, Workspace, new_id
from rcon_core.canvas.robots import Robot
from rcon_core.plugins import Binding, PluginManager, Role

from .demo import DEMO_ENVELOPE, DRIVE, pick_kind

MAX_ROBOTS = 6  #: the sim has six distinct camera scenes
#: the part of the Fleet canvas the layout fills (canvas units, from the 16-unit margin): what a 1024x600
#: tablet shows below the toolbars and what a 1280x800 window shows beside its side panel, less the margins
FIT_W, FIT_H = 864, 352
GAP = 16  #: between tiles and from the canvas's edge (the canvas grid: every rect below stays on it)
TILE_H = 160  #: a vessel's tile: its camera beside its pad, both this tall (two rows and a gap within FIT_H)
#: (camera, pad) widths in one column and in two; none below the smallest frame at 48 px touch targets
#: (144 x 112, ``widget_frame.frame_min_size``), so no frame is grown into its neighbour when placed
TILE_WIDTHS = {1: (192, 176), 2: (144, 144)}


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


def fleet_columns(n: int) -> int:
    """How many columns of vessel tiles the Fleet canvas has: one for up to two vessels, else two (more
    than four vessels add rows below, the only case that scrolls)."""
    return 1 if n <= 2 else 2


def fleet_canvas(n: int, plugins: PluginManager) -> Canvas:
    """The Fleet canvas: vessel tiles (camera beside pad) in a grid of :func:`fleet_columns` columns, filled
    row by row, and the map right of them as tall as the grid. With one column the tiles are wider (a larger
    camera and pad); with two they are narrower and the map keeps the width that is left."""
    canvas = Canvas(new_id("c"), "Fleet", locked=True)
    cols = fleet_columns(n)
    rows = -(-n // cols)
    cam_w, pad_w = TILE_WIDTHS[cols]
    tile_w = cam_w + GAP + pad_w
    for k in range(1, n + 1):
        rid = robot_id(k)
        col, row = (k - 1) % cols, (k - 1) // cols
        x, y = GAP + col * (tile_w + GAP), GAP + row * (TILE_H + GAP)
        canvas.widgets.append(_widget(
            plugins, {"sensors.image": {"max_fps": 15.0}},
            Binding("/camera/front/image_raw", "sensor_msgs/Image", Role.SUBSCRIBE, (), robot=rid),
            (x, y, cam_w, TILE_H), "Front camera"))
        canvas.widgets.append(_widget(
            plugins, {"sensors.teleop": {"max_linear": 2.0, "max_angular": 1.0}},
            Binding("/cmd_vel", "geometry_msgs/Twist", Role.PUBLISH, (), robot=rid),
            (x + cam_w + GAP, y, pad_w, TILE_H), "Drive"))
    # one map, bound to the first vessel's fix; with every_robot it shows every vessel's (on_fleet)
    map_x = GAP + cols * (tile_w + GAP)
    map_h = max(2, rows) * TILE_H + (max(2, rows) - 1) * GAP
    canvas.widgets.append(_widget(
        plugins, {"map.gps": _map_settings(plugins)},
        Binding("/gps/fix", "sensor_msgs/NavSatFix", Role.SUBSCRIBE, (), robot=robot_id(1)),
        (map_x, GAP, GAP + FIT_W - map_x, map_h), "Map of every vessel"))
    return canvas


def drive_canvas(k: int, plugins: PluginManager) -> Canvas:
    canvas = Canvas(new_id("c"), f"Drive · {vessel_name(k)}", locked=True)
    for title, kinds, target, type_name, role, paths, rect in DRIVE:
        canvas.widgets.append(_widget(plugins, kinds, Binding(target, type_name, role, paths, robot=robot_id(k)),
                                      rect, title))
    return canvas


def fleet_workspace(n: int, plugins: PluginManager) -> Workspace:
    """The fleet demo's workspace for ``n`` vessels (robots ``r-1``.. with empty URLs: the app connects
    them to the sims' run-time ports, which are never saved)."""
    check_count(n)
    canvases = [fleet_canvas(n, plugins)] + [drive_canvas(k, plugins) for k in range(1, n + 1)]
    ws = Workspace(canvases, canvases[0].id)
    ws.robots = [Robot(robot_id(k), vessel_name(k), envelope=DEMO_ENVELOPE) for k in range(1, n + 1)]
    return ws


def connect_fleet(window: Any, urls: list[str]) -> None:
    """Connect the window's robots to the sims: the first through the connection bar, the others with
    run-time URLs. None of them is remembered (the ports are gone after this run)."""
    window.connect_to(urls[0], remember=False)
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
