"""The GPS map showing every robot of a workspace: three sims on free ports, the canvas runtime with a
Fleet, one map bound to the first robot's /gps/fix with "Every robot" on. Each robot's fix is a track of
its own, named and coloured as its robot; a robot whose link drops keeps its last position (going stale)
while the others move on."""

from __future__ import annotations

from rcon_widgets_map import mercator

from rcon_core.bridge import BridgeClient
from rcon_core.canvas import Binding, Document, Workspace
from rcon_core.canvas.fleet import Fleet
from rcon_core.canvas.robots import Robot, robot_colour
from rcon_core.canvas.runtime import CanvasRuntime
from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import PluginManager
from rcon_core.testing import until

FIX = ("/gps/fix", "sensor_msgs/NavSatFix", "subscribe", ())


async def test_the_map_shows_every_robots_fix_with_its_name_and_colour(sim_fleet):
    sims = await sim_fleet(3)
    for i, sim in enumerate(sims):
        sim.robot.x, sim.robot.y = 200.0 * i, -150.0 * i  # three boats, 250 m apart
    clients = []
    for sim in sims:
        client = BridgeClient(sim.url, reconnect=False, stall_timeout=5.0)
        await client.connect()
        clients.append(client)
    pm = PluginManager(environ={})
    pm.load_entry_points()
    ws = Workspace.new("Harbour")
    ws.robots = [Robot("r-1", "Alpha"), Robot("r-2", "Bravo"), Robot("r-3", "Charlie", colour="#8f6200")]
    doc = Document(ws)
    c = doc.current
    both = doc.add_widget(c.id, "map.gps", Binding(*FIX), settings={"every_robot": True, "goal_topic": ""})
    own = doc.add_widget(c.id, "map.gps", Binding(*FIX, robot="r-2"), settings={"goal_topic": ""})
    rt = CanvasRuntime(pm, Fleet(zip(ws.robots, clients, strict=True)), types=TypeRegistry.standard())
    try:
        rt.start(c)
        model = rt.models[both.id]

        def tracks():
            value = model.state.value
            return {} if value is None else {t.label: t for t in value.tracks if t.has_position}

        await until(lambda: len(tracks()) == 3, what="a fix from every robot on the map")
        shown = tracks()
        assert [t.label for t in model.state.value.tracks] == ["Alpha", "Bravo", "Charlie"]
        assert [shown[n].colour for n in ("Alpha", "Bravo", "Charlie")] == [
            robot_colour(ws.robots, "r-1"), robot_colour(ws.robots, "r-2"), "#8f6200"]
        for name, sim in zip(("Alpha", "Bravo", "Charlie"), sims, strict=True):
            lat, lon = sim.robot.lat_lon()
            assert mercator.haversine_m(lat, lon, shown[name].lat, shown[name].lon) < 10.0, name
        # each robot's /gps/fix is subscribed once for this map (its own robot's through its own port)
        for sim in sims:
            assert sim.topic_subscriber_count("/gps/fix") == 1
        # a map without "Every robot" shows only its own robot
        plain = rt.models[own.id]
        await until(lambda: plain.state.value is not None and plain.state.value.main.has_position)
        assert len(plain.state.value.tracks) == 1

        # Charlie's link drops: its marker keeps its last position and goes stale; the others go on
        charlie = shown["Charlie"]
        await sims[2].stop()
        await until(lambda: not rt.link_up("r-3"), what="Charlie's link down")
        bravo_count = tracks()["Bravo"].count
        await until(lambda: tracks()["Bravo"].count > bravo_count + 2, what="Bravo's fixes going on")
        assert tracks()["Charlie"].count == charlie.count and tracks()["Charlie"].lat == charlie.lat
        assert not model.state.link_down  # the map's own robot (Alpha) is up
    finally:
        rt.stop()
        for client in clients:
            await client.close()
    for sim in sims[:2]:  # every node the map had on the other robots was closed
        assert sim.topic_subscriber_count("/gps/fix") == 0
