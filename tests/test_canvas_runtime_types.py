"""issue 15.3: a robot that cannot load a widget's type says nothing on the wire (rosbridge 0.11), so the
runtime asks it (rosapi message_details) and the widget shows ERROR with a sentence instead of NO DATA;
a server that does report a failed op with a `status` frame is heard too."""

import json

import pytest
from replay_server import ScriptedServer

from rcon_core.bridge import BridgeClient
from rcon_core.canvas import Binding, Document, Workspace
from rcon_core.canvas.runtime import CanvasRuntime
from rcon_core.plugins import Accepts, PluginManager, WidgetSpec, hookimpl
from rcon_core.sim import SimServer
from rcon_core.testing import until

WINCH = "lab_msgs/Winch"
SENTENCE = "the robot does not know lab_msgs/Winch (is its package installed there?)"


class Lab:
    @hookimpl
    def rcon_register_types(self, registry):
        registry.add_msg(WINCH, "float64 payout\nfloat64 tension\n")
        registry.add_srv("lab_msgs/Reel", "float64 length\n---\nbool ok\n")

    @hookimpl
    def rcon_register_widgets(self, registry):
        base = "rcon_core.plugins.model:WidgetModel"
        registry.add(WidgetSpec(kind="lab.any", title="Any", model=base,
                                roles=["subscribe", "publish", "call"], accepts=Accepts(messages=["any"])))


@pytest.fixture
def pm():
    pm = PluginManager(environ={})
    pm.register(Lab(), "lab")
    return pm


def canvas(*bindings):
    doc = Document(Workspace.new("Lab"))
    ids = [doc.add_widget(doc.current.id, "lab.any", b).id for b in bindings]
    return doc.current, ids


async def run_canvas(url, pm, *bindings):
    client = BridgeClient(url, reconnect=False)
    await client.connect()
    rt = CanvasRuntime(pm, client, types=pm.type_registry())
    cv, ids = canvas(*bindings)
    rt.start(cv)
    return client, rt, [rt.models[i] for i in ids]


async def test_a_type_the_robot_lacks_is_an_error_with_a_sentence(pm):
    robot = SimServer(rate_scale=2.0, plugin_types=False)  # a robot without the lab's package
    await robot.start()
    client, rt, (sub, pub, call, battery) = await run_canvas(
        robot.url, pm,
        Binding("/winch", WINCH, "subscribe"),
        Binding("/winch_cmd", "lab_msgs/msg/Winch", "publish"),
        Binding("/reel", "lab_msgs/Reel", "call"),
        Binding("/battery", "sensor_msgs/BatteryState", "subscribe"),
    )
    try:
        await until(lambda: sub.state.error and pub.state.error and call.state.error, what="the three errors")
        assert sub.state.error == SENTENCE
        assert pub.state.error == "the robot does not know lab_msgs/msg/Winch (is its package installed there?)"
        assert call.state.error == "the robot does not know lab_msgs/Reel (is its package installed there?)"
        await until(lambda: battery.state.count > 0, what="a battery message")
        assert battery.state.error is None  # a standard type is not asked about
    finally:
        rt.stop()
        await client.close()
        await robot.stop()


async def test_a_robot_that_has_the_package_is_not_an_error(pm, sim):
    # the sim fixture knows the installed plugins' types; this one is registered by hand, so teach it
    pm.apply_types(sim.types.registry)
    client, rt, (sub,) = await run_canvas(sim.url, pm, Binding("/winch", WINCH, "subscribe"))
    try:
        winch = client.node("robot").advertise("/winch", WINCH, latch=True)
        winch.publish({"payout": 1.5, "tension": 20.0})
        await until(lambda: sub.state.count > 0, what="a winch message")
        assert sub.state.error is None and sub.state.value == {"payout": 1.5, "tension": 20.0}
    finally:
        rt.stop()
        await client.close()


async def test_a_status_frame_naming_the_subscription_is_an_error(pm):
    def refuse(frame):
        return [json.dumps({"op": "status", "level": "error", "id": frame["id"],
                            "msg": f"Subscribing to {frame['topic']} is not allowed"})]

    async with ScriptedServer(replay=False) as server:
        server.on_subscribe = refuse
        client, rt, (sub,) = await run_canvas(server.url, pm,
                                              Binding("/secret", "std_msgs/Float64", "subscribe"))
        try:
            await until(lambda: sub.state.error is not None, what="the refusal")
            assert sub.state.error == "the robot refused /secret: Subscribing to /secret is not allowed"
        finally:
            rt.stop()
            await client.close()
