"""Found walking the app as an operator: Dock tapped while the robot's link was down (LINK DOWN on the
widget, the button still enabled) went to the robot 3-5 s later, when the link came back: the call waited
for the connection. A tap is the operator's intent *now*; a service call that changes the robot (Dock,
Lights) is never kept to be sent later. It fails at once with a sentence on the widget, and the robot
never gets it."""

from __future__ import annotations

import pytest

from rcon_core.bridge import BridgeClient, ConnectionState
from rcon_core.bridge.errors import NotConnectedError
from rcon_core.canvas import Binding, Document, Workspace
from rcon_core.canvas.runtime import CanvasRuntime
from rcon_core.loopback import StallProxy
from rcon_core.msgs import TypeRegistry
from rcon_core.testing import until


async def test_a_call_tapped_while_the_link_is_down_is_refused_and_never_sent_later(sim, plugins):
    doc = Document(Workspace.new("Ops"))
    w = doc.add_widget(doc.current.id, "std.button", Binding("/dock", "std_srvs/Trigger", "call"))
    async with StallProxy("127.0.0.1", sim.port) as proxy:
        client = BridgeClient(proxy.url, backoff_min=0.05, backoff_max=0.1)
        await client.connect(timeout=10)
        rt = CanvasRuntime(plugins, client, types=TypeRegistry.standard())
        rt.start(doc.current)
        try:
            model = rt.models[w.id]
            proxy.refuse(True)
            proxy.cut()  # the robot's link is down and stays down
            await until(lambda: client.state is not ConnectionState.CONNECTED and model.state.link_down,
                        what="the widget to say LINK DOWN")
            with pytest.raises(NotConnectedError, match="link is down"):
                await model.call_async({})
            assert "link is down" in (model.state.error or "")
            proxy.refuse(False)  # the link comes back...
            await until(lambda: client.state is ConnectionState.CONNECTED and not model.state.link_down,
                        timeout=20, what="the link back")
            await client.rosapi.topics()  # a round trip: anything queued would have arrived by now
            assert sim.ops_received[("call_service", "/dock")] == 0  # ...and the tap is not delivered late
            await model.call_async({})  # a new tap, link up: sent
            assert sim.ops_received[("call_service", "/dock")] == 1
        finally:
            rt.stop()
            await client.close()
