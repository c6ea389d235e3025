"""CanvasRuntime hooks a front end relies on: activity notices (prompt repaint) and focus loss (teleop)."""

import asyncio

import pytest

from rcon_core.bridge import BridgeClient
from rcon_core.canvas import Binding, Document, Workspace
from rcon_core.canvas.runtime import CanvasRuntime
from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import Accepts, PluginManager, WidgetModel, WidgetSpec, hookimpl
from rcon_core.testing import until


class Answerer(WidgetModel):
    def handle_request(self, request):
        self.set_value("asked", message=request)
        return {"success": True, "message": "ok"}


class Driver(WidgetModel):
    """Records focus losses, like a teleop pad that must stop driving."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.focus_losses = 0

    def on_focus_lost(self):
        self.focus_losses += 1


class Clumsy(WidgetModel):
    def on_focus_lost(self):
        raise RuntimeError("clumsy")


class P:
    @hookimpl
    def rcon_register_widgets(self, registry):
        base = "rcon_core.plugins.model:WidgetModel"
        registry.add(WidgetSpec(kind="hk.label", title="Label", model=base, roles=["subscribe", "call"],
                                accepts=Accepts(messages=["any"])))
        registry.add(WidgetSpec(kind="hk.answer", title="Answer", model=Answerer, roles=["serve"]))
        registry.add(WidgetSpec(kind="hk.drive", title="Drive", model=Driver, roles=["publish"]))
        registry.add(WidgetSpec(kind="hk.clumsy", title="Clumsy", model=Clumsy, roles=["publish"]))


@pytest.fixture
def pm():
    pm = PluginManager(environ={})
    pm.register(P(), "hk")
    return pm


async def test_activity_is_reported_after_the_model_took_the_value(sim, pm):
    doc = Document(Workspace.new("Ops"))
    c = doc.current
    label = doc.add_widget(c.id, "hk.label", Binding("/battery", "sensor_msgs/BatteryState", "subscribe",
                                                     ["percentage"]))
    answer = doc.add_widget(c.id, "hk.answer", Binding("/rcon_test/hook", "std_srvs/Trigger", "serve"))
    caller = doc.add_widget(c.id, "hk.label", Binding("/lights/set", "std_srvs/SetBool", "call",
                                                      ["response.success"]))
    client = BridgeClient(sim.url, reconnect=False)
    await client.connect()
    seen: list[tuple[str, int]] = []
    rt = CanvasRuntime(pm, client, types=TypeRegistry.standard(),
                       on_activity=lambda wid: seen.append((wid, rt.models[wid].state.count)))
    try:
        rt.start(c)
        await until(lambda: any(wid == label.id for wid, _ in seen), what="activity of the label")
        # the notice comes after the value was recorded, never before
        assert all(count > 0 for wid, count in seen if wid == label.id)
        assert rt.models[label.id].state.value is not None

        await until(lambda: "/rcon_test/hook" in sim.services, what="service advert")
        reply = await client.node("asker").call_service("/rcon_test/hook", {})
        assert reply["success"] is True
        await until(lambda: any(wid == answer.id for wid, _ in seen), what="activity of the server")

        response = await asyncio.wrap_future(rt.models[caller.id].call({"data": True}))
        assert response["success"] is True
        await until(lambda: any(wid == caller.id for wid, _ in seen), what="activity of the caller")
        assert [n for wid, n in seen if wid == caller.id][0] == 1  # on_response ran before the notice
        assert rt.models[caller.id].state.value is True
    finally:
        rt.stop()
        await client.close()


async def test_focus_loss_reaches_models_that_want_it_and_stop_implies_it(sim, pm, caplog):
    doc = Document(Workspace.new("Drive"))
    c = doc.current
    drive = doc.add_widget(c.id, "hk.drive", Binding("/cmd_vel", "geometry_msgs/Twist", "publish"))
    doc.add_widget(c.id, "hk.clumsy", Binding("/cmd_vel", "geometry_msgs/Twist", "publish"))
    doc.add_widget(c.id, "hk.label", Binding("/battery", "sensor_msgs/BatteryState", "subscribe"))
    client = BridgeClient(sim.url, reconnect=False)
    await client.connect()
    try:
        rt = CanvasRuntime(pm, client, types=TypeRegistry.standard())
        rt.start(c)
        model = rt.models[drive.id]
        rt.focus_lost()
        assert model.focus_losses == 1
        assert "clumsy" in caplog.text  # logged, and the other models were still told
        other = doc.create_canvas("Other")
        rt.start(other)  # leaving the canvas is a focus loss too, before the model stops
        assert model.focus_losses == 2 and not model.running
    finally:
        await client.close()
