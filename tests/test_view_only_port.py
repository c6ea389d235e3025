"""View-only is enforced in the port every widget talks through, below any UI: a widget that tries to
publish, call and serve anyway sends nothing to the real sim, and its port leads to no raw client."""

import asyncio
import time

import pytest
from rogue_widget import RoguePlugin, find_raw

from rcon_core.bridge import BridgeClient
from rcon_core.canvas import Binding, Document, Workspace
from rcon_core.canvas.port import GuardedPort, ViewOnlyError
from rcon_core.canvas.runtime import CanvasRuntime
from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import PluginManager

SENDS = [("advertise", "/cmd_vel"), ("publish", "/cmd_vel"), ("call_service", "/lights/set"),
         ("advertise_service", "/rogue/serve")]


async def until(predicate, timeout=10.0, what="condition"):
    deadline = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out waiting for {what}")
        await asyncio.sleep(0.02)


@pytest.fixture
def pm():
    pm = PluginManager(environ={})
    pm.register(RoguePlugin(), "rogue")
    return pm


def rogue_canvas(view_only):
    doc = Document(Workspace.new("Ops"))
    w = doc.add_widget(doc.current.id, "test.rogue", Binding("/cmd_vel", "geometry_msgs/Twist", "publish"))
    doc.set_view_only(doc.current.id, view_only)
    return doc.current, w


async def run_rogue(sim, pm, *, canvas_view_only=False, link_view_only=None):
    canvas, w = rogue_canvas(canvas_view_only)
    client = BridgeClient(sim.url, reconnect=False)
    await client.connect()
    rt = CanvasRuntime(pm, client, types=TypeRegistry.standard(), view_only=link_view_only)
    rt.start(canvas)
    model = rt.models[w.id]
    await until(lambda: "call" in model.attempts, what="the rogue's call to end")
    # a round trip through the server after every try: whatever was sent has arrived by now
    await client.rosapi.topics()
    return client, rt, model


@pytest.mark.parametrize("where", ["canvas", "connection"])
async def test_a_widget_that_tries_anyway_sends_nothing(sim, pm, where):
    lights = sim.robot.lights
    client, rt, model = await run_rogue(sim, pm, canvas_view_only=where == "canvas",
                                        link_view_only="robot connection is view-only" if where == "connection"
                                        else None)
    try:
        assert [sim.ops_received[s] for s in SENDS] == [0, 0, 0, 0], sim.ops_received
        assert sim.published("/cmd_vel") == [] and "/rogue/serve" not in sim.services
        assert sim.robot.lights == lights
        assert all(text.startswith(("ViewOnlyError", "sent")) for text in model.attempts.values())
        assert not any(text == "sent" for k, text in model.attempts.items() if k != "serve"), model.attempts
        assert "view-only" in (model.state.error or "")
        assert model.view_only and ("view-only" in model.view_only)
        assert model.raw_paths == []  # nothing on the port or its handles leads to the node or the client
        assert model.port.refused >= 4  # publish (twice), serve, call
    finally:
        rt.stop()
        await client.close()


async def test_the_same_widget_without_view_only_reaches_the_sim(sim, pm):
    """The control: the rogue is not harmless by itself; without view-only every try arrives."""
    client, rt, model = await run_rogue(sim, pm)
    try:
        await until(lambda: sim.ops_received[("call_service", "/lights/set")] == 1, what="the call")
        await until(lambda: len(sim.published("/cmd_vel")) >= 2, what="both publishes")
        assert sim.ops_received[("advertise_service", "/rogue/serve")] == 1
        assert model.attempts == {"publish": "sent", "serve": "sent", "call": "sent"}
        assert model.view_only is None and model.state.error is None
        assert model.raw_paths == []  # sealed in either mode
        assert find_raw(client.node("probe"))  # while a bare node does lead to the client (the walk works)
    finally:
        rt.stop()
        await client.close()


async def test_view_only_still_reads_and_allows_read_only_rosapi(sim):
    client = BridgeClient(sim.url, reconnect=False)
    await client.connect()
    try:
        got = []
        port = GuardedPort(client.node("reader"), view_only="test")
        port.subscribe("/battery", got.append)
        await until(lambda: got, what="a battery message")
        details = await port.call_service("/rosapi/message_details", {"type": "std_msgs/Bool"})
        assert details["typedefs"]
        with pytest.raises(ViewOnlyError, match="set_param"):
            await port.call_service("/rosapi/set_param", {"name": "/x", "value": "1"})
        with pytest.raises(ViewOnlyError, match="goal"):
            port.send_action_goal("/navigate", "nav2_msgs/action/NavigateToPose", {})
        assert sim.ops_received[("call_service", "/rosapi/set_param")] == 0
        port.close()
    finally:
        await client.close()
