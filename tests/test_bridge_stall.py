"""A silent stall (no FIN, no RST) between the client and the sim (issue 11, item 5): the client reports
DEGRADED within ~1.5 s, and no command reaches the robot after its freshness limit.

The link is a loopback TCP proxy (``rcon_core.loopback.StallProxy``) in front of the real embedded sim;
stalling it forwards nothing either way, as a Wi-Fi link that stops carrying packets."""

from __future__ import annotations

import asyncio
import time

import pytest

from rcon_core.bridge import BridgeClient, ConnectionState
from rcon_core.bridge.freshness import DEFAULT_MAX_AGE, LinkWatch, resolve_max_age
from rcon_core.loopback import StallProxy
from rcon_core.testing import flushed, until

pytestmark = pytest.mark.usefixtures("transport")  # every test runs on each transport

#: arrival later than the freshness limit plus this is "stale" (room for a loaded test machine; a command
#: held through the stall arrives seconds late)
SLACK = 0.5


@pytest.fixture
async def proxy(sim):
    async with StallProxy("127.0.0.1", sim.port) as p:
        yield p


@pytest.fixture
async def client(proxy):
    c = BridgeClient(proxy.url, backoff_min=0.05, backoff_max=0.2, call_timeout=5)
    states: list[tuple[float, ConnectionState]] = []
    c.add_state_listener(lambda st: states.append((time.monotonic(), st)))
    c.states = states
    await c.connect(timeout=5)
    yield c
    await c.close()


def first(states, state, after: float) -> float | None:
    return next((t for t, st in states if st is state and t >= after), None)


async def test_an_idle_stall_is_degraded_within_1_5_s_and_recovers_on_the_same_connection(proxy, client):
    await asyncio.sleep(0.3)
    stalled_at = time.monotonic()
    proxy.stall()
    await until(lambda: client.state is ConnectionState.DEGRADED, 3)
    assert first(client.states, ConnectionState.DEGRADED, stalled_at) - stalled_at <= 1.5
    assert client.connected  # the socket is open; nothing was torn down
    proxy.resume()
    await until(lambda: client.state is ConnectionState.CONNECTED, 3)
    assert client.stats["connects"] == 1 and client.stats["stall_cuts"] == 0 and client.stats["degraded"] == 1


async def test_commands_are_never_delivered_late_after_a_silent_stall(sim, proxy, client):
    arrivals: list[tuple[float, float]] = []  # (published at, arrived at), both time.monotonic()
    sim.subscribe_internal("/stall/cmd", "std_msgs/Float64", "test",
                           lambda msg: arrivals.append((msg["data"], time.monotonic())))
    pub = client.node("pad").advertise("/stall/cmd", "std_msgs/Float64")
    assert pub.max_age == DEFAULT_MAX_AGE

    async def drive(seconds: float) -> None:
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            pub.publish({"data": time.monotonic()})
            await asyncio.sleep(0.02)  # 50 Hz

    await drive(0.6)
    assert arrivals, "commands flow before the stall"
    stalled_at = time.monotonic()
    proxy.stall()
    await drive(2.5)
    proxy.resume()
    resumed_at = time.monotonic()
    await until(lambda: client.state is ConnectionState.CONNECTED, 5)
    await drive(1.0)
    await flushed(client, sim)  # every command written has arrived (or died with the cut connection)

    degraded = first(client.states, ConnectionState.DEGRADED, stalled_at)
    assert degraded is not None and degraded - stalled_at <= 1.5
    late = [(round(arrived - sent, 2)) for sent, arrived in arrivals if arrived - sent > DEFAULT_MAX_AGE + SLACK]
    assert late == [], f"{len(late)} commands arrived late: {late[:10]}"
    assert any(sent > resumed_at for sent, _ in arrivals), "commands flow again after the stall"
    assert client.stats["stale_dropped"] > 0 and pub.dropped >= client.stats["stale_dropped"]
    # the commands written before the stall was seen were in flight: the client cut the link with a reset,
    # so they died with it instead of arriving seconds late
    assert client.stats["stall_cuts"] == 1 and proxy.discarded > 0


async def test_latched_publishers_have_no_freshness_limit_and_max_age_is_checked(client):
    node = client.node("n")
    assert node.advertise("/a", "std_msgs/String", latch=True).max_age is None
    assert node.advertise("/b", "std_msgs/String", max_age=1.5).max_age == 1.5
    assert node.advertise("/c", "std_msgs/String", max_age=None).max_age is None
    for bad in (0, -1, float("nan"), "1", True):
        with pytest.raises(ValueError, match="max_age"):
            resolve_max_age(bad, False)


def test_link_watch_says_why_a_link_is_stalled_and_whether_commands_are_at_risk():
    w = LinkWatch(stall_timeout=1.0, probe_interval=0.25, now=0.0)
    assert w.probe_due(0.0) and w.stalled(0.5) is None
    w.sent(1.0)
    w.command(1.1)
    assert not w.probe_due(1.5) and w.at_risk() and w.stalled(1.9) is None
    assert w.stalled(2.0) == "no pong for 1.0 s"
    w.answered(1.0)
    assert w.at_risk()  # the command went out after the answered ping
    w.sent(2.1)
    w.answered(2.1)
    assert not w.at_risk() and w.stalled(9.0) is None
    w.buffer(500, 10.0)
    w.buffer(500, 10.6)
    assert w.stalled(10.9) is None and "500 bytes not drained" in w.stalled(11.0)
    w.buffer(400, 11.0)  # draining: not stuck
    assert w.stalled(11.5) is None


async def test_commands_queued_behind_a_full_write_buffer_are_dropped_once_past_their_limit():
    """The server stops reading: bulk data fills the socket buffers and the client's outgoing queue; commands
    published behind it wait longer than 0.25 s and are dropped when their turn comes, never written."""
    from rcon_core.loopback import HostileServer

    async with HostileServer() as server:
        c = BridgeClient(server.url, stall_timeout=None)  # the queue rule alone, without stall detection
        await c.connect(timeout=5)
        try:
            node = c.node("n")
            bulk = node.advertise("/bulk", "std_msgs/String", max_age=None)
            cmd = node.advertise("/cmd", "std_msgs/String")
            await server.wait_for("advertise", count=2)
            server.ws.transport.pause_reading()
            blob = "x" * 100_000
            for _ in range(300):  # 30 MB: far more than the loopback socket buffers hold
                bulk.publish({"data": blob})
            for i in range(5):
                assert cmd.publish({"data": str(i)})  # accepted (queued), not yet written
            await asyncio.sleep(0.6)
            server.ws.transport.resume_reading()
            await server.wait_for("publish", count=300, topic="/bulk", timeout=20)
            bulk.publish({"data": "last"})
            await server.wait(lambda: any(m.get("msg") == {"data": "last"} for m in server.ops("publish")), 10)
            assert server.ops("publish", topic="/cmd") == []
            assert cmd.dropped == 5 and cmd.sent == 0 and c.stats["stale_dropped"] == 5
            assert bulk.dropped == 0 and c.state is ConnectionState.CONNECTED
        finally:
            await c.close()
