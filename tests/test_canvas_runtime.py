"""CanvasRuntime against the real embedded sim over a loopback WebSocket: start, switch, stop."""

import pytest

from rcon_core.bridge import BridgeClient
from rcon_core.canvas import Binding, Document, Geometry, Workspace
from rcon_core.canvas.runtime import BrokenWidgetModel, CanvasRuntime, MissingWidgetModel
from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import Accepts, PluginManager, WidgetModel, WidgetSpec, hookimpl
from rcon_core.testing import until

BRIDGE = "/rosbridge_websocket"


class Responder(WidgetModel):
    def handle_request(self, request):
        self.set_value("called", message=request)
        return {"success": True, "message": "done by the widget"}


class P:
    @hookimpl
    def rcon_register_widgets(self, registry):
        base = "rcon_core.plugins.model:WidgetModel"
        registry.add(WidgetSpec(kind="rt.label", title="Label", model=base, roles=["subscribe"],
                                accepts=Accepts(messages=["any"])))
        registry.add(WidgetSpec(kind="rt.slider", title="Slider", model=base, roles=["publish"],
                                accepts=Accepts(fields=["numeric"])))
        registry.add(WidgetSpec(kind="rt.responder", title="Responder", model=Responder, roles=["serve"]))
        registry.add(WidgetSpec(kind="rt.broken", title="Broken", model="rcon_no_such_module:Model"))


@pytest.fixture
def pm():
    pm = PluginManager(environ={})
    pm.register(P(), "rt")
    return pm


def layout():
    doc = Document(Workspace.new("Ops"))
    ops = doc.current
    label = doc.add_widget(ops.id, "rt.label", Binding("/battery", "sensor_msgs/BatteryState", "subscribe",
                                                       ["percentage"]))
    slider = doc.add_widget(ops.id, "rt.slider", Binding("/speed_limit", "std_msgs/Float64", "publish", "data"))
    responder = doc.add_widget(ops.id, "rt.responder", Binding("/rcon_test/ask", "std_srvs/Trigger", "serve"))
    gone = doc.add_widget(ops.id, "retired.gauge", Binding("/depth", "sensor_msgs/Range", "subscribe"),
                          Geometry(), {"keep": [1, 2]})
    broken = doc.add_widget(ops.id, "rt.broken", Binding("/depth", "sensor_msgs/Range", "subscribe"))
    nav = doc.create_canvas("Nav")
    odom = doc.add_widget(nav.id, "rt.label", Binding("/odom", "nav_msgs/Odometry", "subscribe",
                                                      ["pose.pose.position.x"]))
    return doc, ops, nav, dict(label=label, slider=slider, responder=responder, gone=gone, broken=broken,
                               odom=odom)


async def test_switching_canvases_starts_and_stops_on_the_server(sim, pm):
    doc, ops, nav, w = layout()
    saved_gone = dict(w["gone"].settings)
    client = BridgeClient(sim.url, reconnect=False)
    await client.connect()
    try:
        rt = CanvasRuntime(pm, client, types=TypeRegistry.standard())
        rt.start(ops)
        models = rt.models
        await until(lambda: sim.topic_subscriber_count("/battery") == 1, what="battery subscription")
        await until(lambda: BRIDGE in sim.topics["/speed_limit"].publishers, what="speed_limit advert")
        await until(lambda: "/rcon_test/ask" in sim.services, what="service advert")

        label = models[w["label"].id]
        await until(lambda: label.state.count > 0, what="a battery message")
        assert 0.0 <= label.state.value <= 1.0 and label.state.message["percentage"] == label.state.value
        assert not label.state.stale and label.state.running and label.problems() == []

        assert models[w["slider"].id].publish_value(3.5)
        got = await sim.wait_for_published("/speed_limit", lambda m: m.get("data") == 3.5, timeout=10)
        assert got == {"data": 3.5}

        answer = await client.node("caller").call_service("/rcon_test/ask", {})
        assert answer == {"success": True, "message": "done by the widget"}
        assert models[w["responder"].id].state.value == "called"

        gone = models[w["gone"].id]
        assert isinstance(gone, MissingWidgetModel) and "retired.gauge" in gone.state.error
        assert gone.problems() == [gone.reason]
        broken = models[w["broken"].id]
        assert isinstance(broken, BrokenWidgetModel) and "rcon_no_such_module" in broken.state.error

        rt.start(nav)
        await until(lambda: sim.topic_subscriber_count("/battery") == 0, what="battery unsubscribed")
        await until(lambda: BRIDGE not in sim.topics["/speed_limit"].publishers, what="unadvertised")
        await until(lambda: "/rcon_test/ask" not in sim.services, what="service unadvertised")
        await until(lambda: sim.topic_subscriber_count("/odom") == 1, what="odom subscription")
        assert not label.running and set(rt.models) == {w["odom"].id}
        odom = rt.models[w["odom"].id]
        await until(lambda: odom.state.count > 0, what="an odom message")
        assert isinstance(odom.state.value, float)

        rt.start(ops)
        await until(lambda: sim.topic_subscriber_count("/battery") == 1, what="battery again")
        await until(lambda: sim.topic_subscriber_count("/odom") == 0, what="odom unsubscribed")
        rt.stop()
        await until(lambda: sim.topic_subscriber_count("/battery") == 0, what="all stopped")
        assert rt.models == {}
        assert w["gone"].settings == saved_gone  # the placeholder never touched the instance
    finally:
        await client.close()


async def test_link_state_reaches_the_models(sim, pm):
    doc, ops, _nav, w = layout()
    client = BridgeClient(sim.url, reconnect=False)
    await client.connect()
    rt = CanvasRuntime(pm, client, types=TypeRegistry.standard())
    rt.start(ops)
    label = rt.models[w["label"].id]
    assert not label.state.link_down
    await client.close()
    await until(lambda: label.state.link_down, what="link down flag")
    rt.stop()


async def test_models_get_the_apps_plugins_and_share_per_link_through_their_context(sim, pm):
    """WidgetContext: specs through the runtime's plugin manager (a disabled plugin's kinds are unknown
    there), one shared object per key for the widgets on one robot link."""
    doc, ops, _nav, w = layout()
    pm.register(Other(), "other")
    off = PluginManager(disabled=["other"], environ={})
    off.register(P(), "rt")
    off.register(Other(), "other")
    client = BridgeClient(sim.url, reconnect=False)
    await client.connect()
    try:
        for manager, offered in ((pm, True), (off, False)):
            rt = CanvasRuntime(manager, client, types=TypeRegistry.standard())
            rt.start(ops)
            label, slider = rt.models[w["label"].id], rt.models[w["slider"].id]
            assert label.context.spec("rt.slider").kind == "rt.slider"
            if offered:
                assert label.context.spec("other.dial").kind == "other.dial"
            else:
                with pytest.raises(KeyError):
                    label.context.spec("other.dial")
            made = label.context.shared("pads", object)
            assert slider.context.shared("pads", object) is made
            assert CanvasRuntime(manager, client).shared.get(id(client), "pads", object) is not made
            rt.stop()
    finally:
        await client.close()


class Other:
    @hookimpl
    def rcon_register_widgets(self, registry):
        registry.add(WidgetSpec(kind="other.dial", title="Dial", model="rcon_core.plugins.model:WidgetModel",
                                roles=["subscribe"], accepts=Accepts(messages=["any"])))


async def test_reconfigure_restarts_one_widget(sim, pm):
    doc, ops, _nav, w = layout()
    client = BridgeClient(sim.url, reconnect=False)
    await client.connect()
    try:
        rt = CanvasRuntime(pm, client, types=TypeRegistry.standard())
        rt.start(ops)
        await until(lambda: sim.topic_subscriber_count("/battery") == 1, what="battery")
        doc.reconfigure_widget(w["label"].id, binding=Binding("/depth", "sensor_msgs/Range", "subscribe", "range"))
        model = rt.restart_widget(w["label"])
        await until(lambda: sim.topic_subscriber_count("/battery") == 0, what="old binding gone")
        await until(lambda: model.state.count > 0, what="a depth message")
        assert isinstance(model.state.value, float)
        rt.stop()
    finally:
        await client.close()
