"""The client's fast paths against the sim: direct publish writes, ordering under back-pressure, Nagle off,
and a raising callback on the one-consumer delivery path."""

from __future__ import annotations

import logging
import socket

import pytest

from rcon_core.bridge import BridgeClient
from rcon_core.testing import until

pytestmark = pytest.mark.usefixtures("transport")  # every test runs on each transport


@pytest.fixture
async def client(sim):
    c = BridgeClient(sim.url, call_timeout=5, latency_interval=3600)
    await c.connect(timeout=5)
    yield c
    await c.close()


async def test_nagle_is_off_on_the_client_socket(client):
    sock = client.link.socket
    assert sock.getsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY) != 0


async def test_a_publish_is_handed_to_the_transport_before_publish_returns(sim, client):
    pub = client.node("teleop").advertise("/rcon_test/now", "std_msgs/String")
    await until(lambda: sim.topics.get("/rcon_test/now") is not None, what="the advertisement at the sim")
    sent_before = client.link.buffered(), client.link.queued
    assert sent_before == (0, 0)
    pub.publish({"data": "at once"})
    assert client.link.queued == 0  # not queued for the writer task: already written
    msg = await sim.wait_for_published("/rcon_test/now", lambda m: m["data"] == "at once", timeout=5)
    assert msg == {"data": "at once"}
    assert pub.sent == 1


async def test_publishes_keep_their_order_when_the_transport_backs_up(sim, client):
    pub = client.node("bulk").advertise("/rcon_test/bulk", "std_msgs/String")
    await until(lambda: sim.topics.get("/rcon_test/bulk") is not None, what="the advertisement at the sim")
    n, pad = 200, "x" * (64 << 10)
    for i in range(n):  # ~13 MB without yielding: the transport fills up, the rest waits in the queue
        pub.publish({"data": f"{i:06d}{pad}"})
    assert client.link.queued > 0, "the transport never backed up; the queued path was not exercised"
    await sim.wait_for_published("/rcon_test/bulk", lambda m: m["data"].startswith(f"{n - 1:06d}"), timeout=20)
    got = [int(m["data"][:6]) for m in sim.published("/rcon_test/bulk")]
    assert got == list(range(n))
    assert client.stats["dropped_on_disconnect"] == 0 and pub.sent == n


async def test_a_raising_callback_of_the_only_consumer_is_logged_and_delivery_goes_on(sim, client, caplog):
    calls = []

    def flaky(msg):
        calls.append(msg)
        if len(calls) == 1:
            raise KeyError("widget bug")  # a KeyError from a callback is not mistaken for a malformed frame

    client.node("only").subscribe("/imu/data", flaky)
    with caplog.at_level(logging.ERROR, logger="rcon_core.bridge"):
        await until(lambda: len(calls) >= 3)
    assert "callback for /imu/data raised" in caplog.text and "widget bug" in caplog.text
    assert client.stats["bad_frames"] == 0 and client.connected


async def test_the_link_runs_on_the_transport_the_test_chose(client, transport):
    assert client.transport == transport and client.link.name == transport
