"""Several robots in one workspace: the canvas runtime on two and three sims, each on its own free port.

Each widget runs on the client of the robot its binding names; one robot's link dropping reaches only
that robot's widgets; a fleet-wide model gets a port on every robot. No Qt."""

import copy
import json

import pytest

from rcon_core.bridge import BridgeClient
from rcon_core.canvas import Binding, Document, EditError, Workspace, dumps_workspace, loads_workspace
from rcon_core.canvas.fleet import Fleet
from rcon_core.canvas.robots import Robot, mixes_robots, robot_colour
from rcon_core.canvas.runtime import BrokenWidgetModel, CanvasRuntime
from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import Accepts, PluginManager, WidgetModel, WidgetSpec, hookimpl
from rcon_core.testing import until

BATTERY = ("/battery", "sensor_msgs/BatteryState", "subscribe", ("percentage",))


class Everyone(WidgetModel):
    """A fleet-wide model: counts /battery messages from every robot it is given a port on."""

    def __init__(self, *a, **k):
        super().__init__(*a, **k)
        self.robots = []
        self.counts = {}
        self.links = {}
        self._subs = []

    def on_fleet(self, robots):
        self.robots = list(robots)

    def on_robot_link(self, robot_id, up):
        self.links[robot_id] = up

    def on_start(self):
        for r in self.robots:
            self.counts[r.id] = 0
            self._subs.append(r.port.subscribe("/battery", lambda _m, rid=r.id: self._tally(rid),
                                               type="sensor_msgs/BatteryState"))

    def _tally(self, rid):
        self.counts[rid] += 1

    def on_stop(self):
        for sub in self._subs:
            sub.unsubscribe()
        self._subs = []


class P:
    @hookimpl
    def rcon_register_widgets(self, registry):
        base = "rcon_core.plugins.model:WidgetModel"
        registry.add(WidgetSpec(kind="fl.label", title="Label", model=base, roles=["subscribe"],
                                accepts=Accepts(messages=["any"])))
        registry.add(WidgetSpec(kind="fl.slider", title="Slider", model=base, roles=["publish"],
                                accepts=Accepts(fields=["numeric"])))
        registry.add(WidgetSpec(kind="fl.everyone", title="Everyone", model=Everyone, roles=["subscribe"],
                                accepts=Accepts(messages=["any"])))


@pytest.fixture
def pm():
    pm = PluginManager(environ={})
    pm.register(P(), "fl")
    return pm


def robots(n):
    names = ["Alpha", "Bravo", "Charlie"]
    return [Robot(f"r-{i + 1}", names[i]) for i in range(n)]


async def clients_for(sims):
    out = []
    for sim in sims:
        client = BridgeClient(sim.url, reconnect=False, stall_timeout=5.0)
        await client.connect()
        out.append(client)
    return out


def percentage(model):
    value = model.state.value
    return None if value is None else round(float(value), 3)


async def test_each_widget_talks_to_the_robot_its_binding_names(sim_fleet, pm):
    sims = await sim_fleet(3)
    for sim, charge in zip(sims, (4.0, 10.0, 16.0), strict=True):
        sim.robot.battery_charge = charge  # a distinct battery on each robot (capacity 20 Ah)
    clients = await clients_for(sims)
    ws = Workspace.new("Fleet")
    ws.robots = robots(3)
    doc = Document(ws)
    c = doc.current
    first = doc.add_widget(c.id, "fl.label", Binding(*BATTERY))  # no robot: the first
    second = doc.add_widget(c.id, "fl.label", Binding(*BATTERY, robot="r-2"))
    third = doc.add_widget(c.id, "fl.label", Binding(*BATTERY, robot="r-3"))
    speed = doc.add_widget(c.id, "fl.slider", Binding("/speed_limit", "std_msgs/Float64", "publish", "data",
                                                      robot="r-2"))
    assert mixes_robots(ws.robots, [w.binding for w in c.widgets])
    rt = CanvasRuntime(pm, Fleet(zip(ws.robots, clients, strict=True)), types=TypeRegistry.standard())
    try:
        rt.start(c)
        m = rt.models
        await until(lambda: all(percentage(m[w.id]) is not None for w in (first, second, third)),
                    what="a battery value from every robot")
        got = [percentage(m[w.id]) for w in (first, second, third)]
        assert got[0] < 0.3 < got[1] < 0.6 < got[2], got  # 0.2, 0.5, 0.8: each its own robot's
        for sim in sims:
            assert sim.topic_subscriber_count("/battery") == 1
        m[speed.id].publish_value(1.25)
        msg = await sims[1].wait_for_published("/speed_limit", timeout=5.0)
        assert msg == {"data": 1.25}
        assert sims[0].published("/speed_limit") == [] and sims[2].published("/speed_limit") == []
    finally:
        rt.stop()
        for client in clients:
            await client.close()


async def test_one_robot_dropping_leaves_the_others_live(sim_fleet, pm):
    alpha, bravo = await sim_fleet(2)
    clients = await clients_for([alpha, bravo])
    ws = Workspace.new("Fleet")
    ws.robots = robots(2)
    doc = Document(ws)
    c = doc.current
    a_label = doc.add_widget(c.id, "fl.label", Binding(*BATTERY))
    b_label = doc.add_widget(c.id, "fl.label", Binding(*BATTERY, robot="r-2"))
    a_cmd = doc.add_widget(c.id, "fl.slider", Binding("/speed_limit", "std_msgs/Float64", "publish", "data"))
    b_cmd = doc.add_widget(c.id, "fl.slider", Binding("/speed_limit", "std_msgs/Float64", "publish", "data",
                                                      robot="r-2"))
    both = doc.add_widget(c.id, "fl.everyone", Binding(*BATTERY))
    rt = CanvasRuntime(pm, Fleet(zip(ws.robots, clients, strict=True)), types=TypeRegistry.standard())
    try:
        rt.start(c)
        m = rt.models
        await until(lambda: m[a_label.id].state.count > 0 and m[b_label.id].state.count > 0, what="values")
        everyone = m[both.id]
        assert [r.name for r in everyone.robots] == ["Alpha", "Bravo"]
        assert [r.colour for r in everyone.robots] == [robot_colour(ws.robots, "r-1"), robot_colour(ws.robots, "r-2")]
        await until(lambda: min(everyone.counts.values()) > 0, what="the fleet-wide widget hearing both robots")
        assert everyone.links == {"r-1": True, "r-2": True}

        await alpha.stop()  # Alpha's link drops
        await until(lambda: m[a_label.id].state.link_down, what="LINK DOWN on Alpha's widgets")
        assert m[a_cmd.id].state.link_down  # Alpha's command widget shows it (and its bridge drops commands)
        assert not rt.link_up("r-1") and rt.link_up("r-2")
        assert everyone.links == {"r-1": False, "r-2": True}
        before = m[b_label.id].state.count
        await until(lambda: m[b_label.id].state.count > before + 2, what="Bravo's values going on")
        assert not m[b_label.id].state.link_down and not m[b_cmd.id].state.link_down
        assert m[b_cmd.id].publish_value(0.5)  # Bravo still takes commands
        assert (await bravo.wait_for_published("/speed_limit", timeout=5.0)) == {"data": 0.5}
    finally:
        rt.stop()
        for client in clients:
            await client.close()


async def test_a_new_client_for_one_robot_restarts_only_its_widgets(sim_fleet, pm):
    alpha, bravo = await sim_fleet(2)
    clients = await clients_for([alpha, bravo])
    ws = Workspace.new("Fleet")
    ws.robots = robots(2)
    doc = Document(ws)
    c = doc.current
    a = doc.add_widget(c.id, "fl.label", Binding(*BATTERY))
    b = doc.add_widget(c.id, "fl.label", Binding(*BATTERY, robot="r-2"))
    lost = doc.add_widget(c.id, "fl.label", Binding(*BATTERY, robot="r-9"))
    rt = CanvasRuntime(pm, Fleet(zip(ws.robots, clients, strict=True)), types=TypeRegistry.standard())
    again = BridgeClient(bravo.url, reconnect=False)
    await again.connect()
    try:
        rt.start(c)
        old_a, old_b = rt.models[a.id], rt.models[b.id]
        assert isinstance(rt.models[lost.id], BrokenWidgetModel)
        assert rt.models[lost.id].reason == "robot 'r-9' is not in this workspace"
        rt.set_client("r-2", again)
        assert rt.models[a.id] is old_a and rt.models[b.id] is not old_b
        await until(lambda: rt.models[b.id].state.count > 0, what="Bravo's widget on its new client")
        await until(lambda: bravo.topic_subscriber_count("/battery") == 1, what="the old node's subscription gone")
    finally:
        rt.stop()
        await again.close()
        for client in clients:
            await client.close()


async def test_a_widget_added_while_a_robot_is_offline_moves_to_its_new_client(sim_fleet, pm):
    """A widget added (or reconfigured) after the canvas started is rebuilt on the robot's new client like
    the ones the canvas started with; one removed meanwhile is not brought back."""
    from rcon_core.app.link import OFFLINE

    (alpha,) = await sim_fleet(1)
    ws = Workspace.new("Fleet")
    ws.robots = robots(1)
    doc = Document(ws)
    c = doc.current
    rt = CanvasRuntime(pm, Fleet([(ws.robots[0], OFFLINE)]), types=TypeRegistry.standard())
    client = BridgeClient(alpha.url, reconnect=False)
    await client.connect()
    try:
        rt.start(copy.deepcopy(c))  # a snapshot, as the app's LiveCanvas gives it
        added = doc.add_widget(c.id, "fl.label", Binding(*BATTERY))
        gone = doc.add_widget(c.id, "fl.label", Binding(*BATTERY))
        changed = doc.add_widget(c.id, "fl.label", Binding("/odom", "nav_msgs/Odometry", "subscribe"))
        for w in (added, gone, changed):
            rt.add_widget(copy.deepcopy(w))
        rt.remove_widget(gone.id)
        changed = copy.deepcopy(changed)
        changed.binding = Binding(*BATTERY)
        rt.restart_widget(changed)
        rt.set_client("r-1", client)
        assert gone.id not in rt.models
        await until(lambda: rt.models[added.id].state.count > 0 and rt.models[changed.id].state.count > 0,
                    what="the widgets added offline hearing the robot")
        assert rt.models[changed.id].binding.name == "/battery"
    finally:
        rt.stop()
        await client.close()


async def test_a_view_only_robot_refuses_commands_the_others_take_them(sim_fleet, pm):
    alpha, bravo = await sim_fleet(2)
    clients = await clients_for([alpha, bravo])
    ws = Workspace.new("Fleet")
    ws.robots = [Robot("r-1", "Alpha"), Robot("r-2", "Bravo", view_only=True)]
    doc = Document(ws)
    c = doc.current
    speed = ("/speed_limit", "std_msgs/Float64", "publish", "data")
    a_cmd = doc.add_widget(c.id, "fl.slider", Binding(*speed))
    b_cmd = doc.add_widget(c.id, "fl.slider", Binding(*speed, robot="r-2"))
    b_label = doc.add_widget(c.id, "fl.label", Binding(*BATTERY, robot="r-2"))
    rt = CanvasRuntime(pm, Fleet(zip(ws.robots, clients, strict=True)), types=TypeRegistry.standard())
    try:
        rt.start(c)
        m = rt.models
        assert rt.view_only_reason(robot_id="r-2") == "robot “Bravo” is view-only"
        assert rt.view_only_reason(robot_id="r-1") is None
        m[b_cmd.id].publish_value(1.5)
        m[a_cmd.id].publish_value(0.5)
        assert (await alpha.wait_for_published("/speed_limit", timeout=5.0)) == {"data": 0.5}
        await until(lambda: "view-only" in (m[b_cmd.id].state.error or ""), what="Bravo's refusal on its widget")
        await until(lambda: m[b_label.id].state.count > 0, what="Bravo still watched")
        assert bravo.published("/speed_limit") == []  # nothing reached the view-only robot
    finally:
        rt.stop()
        for client in clients:
            await client.close()


def test_a_bare_client_is_a_fleet_of_one():
    fleet = Fleet.single("client")
    assert fleet.client("") == "client" and fleet.ids == ["r-1"] and "" in fleet and "r-2" not in fleet


def test_re_targeting_a_canvas_is_one_undo_step():
    ws = Workspace.new("Boat")
    ws.robots = robots(3)
    doc = Document(ws)
    c = doc.current
    doc.add_widget(c.id, "fl.label", Binding(*BATTERY))
    doc.add_widget(c.id, "fl.slider", Binding("/speed_limit", "std_msgs/Float64", "publish", "data"))
    doc.add_widget(c.id, "fl.label", Binding(*BATTERY, robot="r-3"))  # a mixed canvas
    dup = doc.duplicate_for_robot(c.id, "r-2", from_robot="r-1")
    assert [cv.name for cv in ws.canvases] == ["Boat", "Boat · Bravo"]
    assert [w.binding.robot for w in dup.widgets] == ["r-2", "r-2", "r-3"]  # only Alpha's widgets moved
    assert {w.id for w in dup.widgets}.isdisjoint({w.id for w in c.widgets})
    assert [w.binding.robot for w in c.widgets] == ["", "", "r-3"]  # the original is untouched
    every = doc.duplicate_for_robot(c.id, "r-1")  # every widget to the first robot: written ""
    assert [w.binding.robot for w in every.widgets] == ["", "", ""]
    assert doc.undo() and doc.undo()
    assert [cv.name for cv in ws.canvases] == ["Boat"]
    assert doc.redo() and ws.canvases[1].widgets[0].binding.robot == "r-2"
    with pytest.raises(EditError, match="robot 'r-7' is not in this workspace"):
        doc.duplicate_for_robot(c.id, "r-7")
    # the copy is saved with its robots
    back = loads_workspace(dumps_workspace(ws))
    assert [w.binding.robot for w in back.canvases[1].widgets] == ["r-2", "r-2", "r-3"]


def test_a_workspace_without_robots_gets_the_default_one():
    doc = Document(Workspace([], robots=[]))
    assert [(r.id, r.name) for r in doc.workspace.robots] == [("r-1", "Robot")]


def test_robots_are_edited_in_one_undo_step_and_refused_when_ambiguous():
    doc = Document(Workspace.new())
    changes = []
    doc.add_listener(lambda ch: changes.append(ch.what))
    doc.set_robots([Robot("r-1", "Alpha", "ws://10.0.0.5:9090"), Robot("r-2", "Bravo", "ws://10.0.0.6:9090")])
    assert [r.name for r in doc.workspace.robots] == ["Alpha", "Bravo"] and changes == ["robots-changed"]
    assert doc.undo() and [r.name for r in doc.workspace.robots] == ["Robot"]
    for bad in ([], [Robot("a"), Robot("a")], [Robot("")]):
        with pytest.raises(EditError):
            doc.set_robots(bad)
    data = json.loads(dumps_workspace(doc.workspace))
    assert [r["id"] for r in data["robots"]] == ["r-1"]
