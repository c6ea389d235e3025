"""issue 22.7: the app grew ~0.85 MB per reconnect (+95 MB in 10 minutes with 111 reconnects; +12 MB
without them). The app's collector policy freezes long-lived objects (``gcpolicy.py``), a live connection
among them, and frozen *cyclic* garbage waits for a full settle: each dropped connection's websockets
protocol (in a cycle with its frame parser, and with the tracebacks kept in ``parser_exc`` and the client's
``last_error``) kept its buffers and last frames for good. A dropped connection's objects are now freed by
reference counting, frozen or not. ``benchmarks/soak.py --parts reconnect`` measures the app's RSS per
reconnect."""

from __future__ import annotations

import gc
import weakref

import pytest

from rcon_core.bridge import BridgeClient, ConnectionState
from rcon_core.bridge.safety import without_traceback
from rcon_core.loopback import StallProxy
from rcon_core.testing import until


@pytest.fixture
def frozen_collector():
    """Objects alive now are frozen as the app's policy does (undone afterwards)."""
    yield lambda: (gc.collect(), gc.freeze())
    gc.unfreeze()
    gc.collect()


async def test_a_dropped_connection_frozen_while_alive_is_freed(sim, frozen_collector):
    async with StallProxy("127.0.0.1", sim.port) as proxy:
        client = BridgeClient(proxy.url, backoff_min=0.02, backoff_max=0.05)
        got: list = []
        client.node("n").subscribe("/odom", got.append)
        await client.connect(timeout=10)
        try:
            await until(lambda: len(got) >= 3, what="messages on the first connection")
            ws = client.link.ws
            protocol = weakref.ref(ws.protocol)
            connection = weakref.ref(ws)
            del ws
            frozen_collector()  # the app's light settle, a few seconds after the robot connected
            proxy.cut()
            await until(lambda: client.stats["connects"] == 2 and client.state is ConnectionState.CONNECTED,
                        what="the reconnect")
            await until(lambda: len(got) >= 6, what="messages on the second connection")
            # its last tasks may still be ending (a loaded machine): freed within moments, or never
            await until(lambda: connection() is None, what="the dropped connection freed")
            await until(lambda: protocol() is None, what="its protocol (its buffers) freed")
            assert client.last_error is not None and client.last_error.__traceback__ is None
        finally:
            await client.close()


def test_without_traceback_drops_the_chain_of_tracebacks():
    def fail() -> None:
        try:
            raise KeyError("inner")
        except KeyError as inner:
            raise RuntimeError("outer") from inner

    with pytest.raises(RuntimeError) as info:
        fail()
    exc = info.value
    assert exc.__traceback__ is not None and exc.__cause__.__traceback__ is not None
    assert without_traceback(exc) is exc
    assert exc.__traceback__ is None and exc.__cause__.__traceback__ is None
