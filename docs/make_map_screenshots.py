"""Renders the map widget's README screenshots offscreen against the embedded sim (run it by hand):

    QT_QPA_PLATFORM=offscreen python docs/make_map_screenshots.py docs/screenshots/map

Drives the vessel in an arc through /cmd_vel, adds a second fix topic (the operator), then saves the map
on the plain grid (no tiles) and on a generated offline MBTiles file, with a goal waiting for confirmation.
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

# the map tests' generated tiles (their conftest), so the pictures show the tiles the tests use
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "plugins" / "rcon_widgets_map" / "tests"))

from qtpy import QtCore, QtWidgets  # noqa: E402
from rcon_widgets_map import mercator  # noqa: E402
from rcon_widgets_map.mbtiles import write_mbtiles  # noqa: E402
from rcon_widgets_map.model import MapModel  # noqa: E402
from rcon_widgets_map.settings import MapPluginSettings, MapSettings  # noqa: E402
from rcon_widgets_map.view import MapView  # noqa: E402

from conftest import SIM_LAT, SIM_LON, tiles_around  # noqa: E402
from rcon_core.app import theme  # noqa: E402
from rcon_core.bridge import BridgeClient  # noqa: E402
from rcon_core.bridge.threaded import BridgeThread  # noqa: E402
from rcon_core.msgs import TypeRegistry  # noqa: E402
from rcon_core.plugins import Binding  # noqa: E402
from rcon_core.sim import SimServer  # noqa: E402


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    app = QtWidgets.QApplication([])
    theme.apply(app)
    types = TypeRegistry.standard()
    tmp = Path(tempfile.mkdtemp())
    mbtiles = tmp / "harbour.mbtiles"
    write_mbtiles(mbtiles, tiles_around(SIM_LAT, SIM_LON, range(0, 19), radius=2), {"name": "generated test tiles"})
    with SimServer.in_thread(port=0, rate_scale=4.0) as sim, BridgeThread() as bt:
        client = BridgeClient(sim.url, reconnect=False)
        bt.run(client.connect()).result(10)
        drive = client.node("drive").advertise("/cmd_vel", "geometry_msgs/Twist")
        operator = client.node("operator").advertise("/operator/fix", "sensor_msgs/NavSatFix")
        models = []
        for name, extra in (("grid", {}), ("mbtiles", {"mbtiles_path": str(mbtiles), "zoom": 17.5})):
            settings = MapSettings(**{"extra_topics": "operator=/operator/fix", "zoom": 18.0, **extra})
            m = MapModel(settings, Binding("/gps/fix", "sensor_msgs/NavSatFix", "subscribe"),
                         client.node(f"map-{name}"), types=types, dispatch=bt.call,
                         plugin_settings=MapPluginSettings(cache_dir=str(tmp / "cache")))
            bt.call(m.start).result(5)
            models.append((name, m))
        end = time.monotonic() + 12.0
        op = types.default("sensor_msgs/NavSatFix")
        op["latitude"], op["longitude"] = mercator.offset_m(SIM_LAT, SIM_LON, -20.0, 25.0)
        while time.monotonic() < end:
            turn = 0.12 if time.monotonic() > end - 7 else 0.0
            bt.call(drive.publish, {"linear": {"x": 2.0, "y": 0.0, "z": 0.0},
                                    "angular": {"x": 0.0, "y": 0.0, "z": turn}})
            bt.call(operator.publish, op)
            time.sleep(0.1)
        for name, m in models:
            view = MapView(m)
            view.resize(480, 400)
            view.show()
            view.refresh(m.state)
            deadline = time.monotonic() + 3
            while time.monotonic() < deadline:
                bt.call(operator.publish, op)
                app.processEvents()
                time.sleep(0.02)
            if name == "grid":
                view.pan_by(-60, 40)
            main = m.state.value.main
            sx, sy = view.viewport.to_screen(main.lat, main.lon)
            if name == "mbtiles":  # a goal waiting for confirmation
                view.tap(QtCore.QPointF(sx + 60, sy + 75))
            app.processEvents()
            view.refresh(m.state)
            app.processEvents()
            path = out / f"gps_map_{name}.png"
            view.grab().save(str(path))
            print(path, path.stat().st_size, "bytes")
            view.close_loader()
            bt.call(m.stop).result(5)
        bt.run(client.close()).result(10)


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "docs/screenshots/map"))
