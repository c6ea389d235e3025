"""Safety with several robots: a teleop pad is bound to exactly one robot; losing that robot's link stops
its pad (one zero, then silence) while the other robot's pad keeps driving; focus loss stops every pad.
Two sims on free ports, the real teleop model of rcon_widgets_sensors."""


import pytest

from rcon_core.bridge import BridgeClient
from rcon_core.canvas import Binding, Document, Workspace
from rcon_core.canvas.fleet import Fleet
from rcon_core.canvas.robots import Robot
from rcon_core.canvas.runtime import CanvasRuntime
from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import PluginManager
from rcon_core.testing import until

pytest.importorskip("rcon_widgets_sensors")

TWIST = ("/cmd_vel", "geometry_msgs/Twist", "publish", ())


def teleop_kind(pm):
    return next(s.kind for s in pm.widgets() if s.kind.endswith("teleop"))


async def test_losing_one_robot_stops_only_its_teleop_and_focus_loss_stops_all(sim_fleet):
    alpha, bravo = await sim_fleet(2)
    clients = []
    for sim in (alpha, bravo):
        client = BridgeClient(sim.url, reconnect=False, stall_timeout=5.0)
        await client.connect()
        clients.append(client)
    pm = PluginManager(environ={})
    pm.load_entry_points()
    ws = Workspace.new("Drive")
    ws.robots = [Robot("r-1", "Alpha"), Robot("r-2", "Bravo")]
    doc = Document(ws)
    c = doc.current
    kind = teleop_kind(pm)
    pad_a = doc.add_widget(c.id, kind, Binding(*TWIST))
    pad_b = doc.add_widget(c.id, kind, Binding(*TWIST, robot="r-2"))
    rt = CanvasRuntime(pm, Fleet(zip(ws.robots, clients, strict=True)), types=TypeRegistry.standard())
    try:
        rt.start(c)
        a, b = rt.models[pad_a.id], rt.models[pad_b.id]
        a.set_axes(0.0, 0.8)
        b.set_axes(0.0, 0.6)
        moving = lambda m: m.get("linear", {}).get("x", 0) > 0  # noqa: E731
        await alpha.wait_for_published("/cmd_vel", moving, timeout=5.0)
        await bravo.wait_for_published("/cmd_vel", moving, timeout=5.0)
        assert a.active and b.active

        await alpha.stop()  # Alpha's link drops
        await until(lambda: not a.active, what="Alpha's pad stopping on its lost link")
        assert a.state.value.reason == "link down" and a.state.link_down
        assert b.active and not b.state.link_down  # Bravo's pad still drives Bravo
        sent = len(b.send_times)
        await until(lambda: len(b.send_times) > sent + 2, what="Bravo's pad sending on")
        last_b = bravo.published("/cmd_vel")[-1]
        assert moving(last_b)

        rt.focus_lost()  # the operator looked away: every pad stops
        await until(lambda: not b.active, what="Bravo's pad stopping on focus loss")
        await bravo.wait_for_published("/cmd_vel", lambda m: not moving(m), timeout=5.0)
        assert b.state.value.reason == "focus lost"
    finally:
        rt.stop()
        for client in clients:
            await client.close()
