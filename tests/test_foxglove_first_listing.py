"""The first listing after (re)connecting to a Foxglove robot is the whole catalogue, never the part that had
arrived when the link came up (``rcon_core/foxglove/catalog.py``, "Decision: the first listing").

The link is CONNECTED with ``serverInfo``; the server's ``advertise`` and ``advertiseServices`` follow in frames
of their own, sometimes in a later read.  A gated server here sends ``serverInfo`` at once and the
advertisements (the real foxglove-sdk server's, from ``tests/recordings/foxglove-sdk-0.30.3``) only when the test
opens the gate, so the window that picows hit a few times in a thousand connects is held open on purpose.
The client's grace for advertisements that never come is set long in the tests that must not depend on it
(then any wait it ends is the server's doing, not the clock's) and short in the one that is about it.
"""

from __future__ import annotations

import asyncio
import json
from typing import Any

import pytest
import websockets
from fox_legacy import recorded

from rcon_core.bridge import ConnectionState
from rcon_core.bridge.errors import NotConnectedError
from rcon_core.foxglove import FoxgloveClient
from rcon_core.testing import until

pytestmark = pytest.mark.usefixtures("transport")  # every test runs on each WebSocket transport

FRAMES = [json.loads(f["text"]) for f in recorded() if f["dir"] == "in" and "text" in f]
SERVER_INFO = next(m for m in FRAMES if m["op"] == "serverInfo")
ADVERTISE = next(m for m in FRAMES if m["op"] == "advertise")
SERVICES = next(m for m in FRAMES if m["op"] == "advertiseServices")
TOPICS = {ch["topic"] for ch in ADVERTISE["channels"]}
NAMES = {s["name"] for s in SERVICES["services"]}
#: a grace no test may reach: a listing that returns did so because the server advertised
NEVER = 600.0


class GatedServer:
    """A Foxglove server that sends ``serverInfo`` on connect and its advertisements once ``gate`` is set
    (each frame on its own; ``send`` picks which: with or without ``advertiseServices``).  ``drop()`` closes
    the current connection (the client reconnects)."""

    def __init__(self, capabilities: list[str] | None = None, send: tuple[str, ...] = ("advertise",
                                                                                          "advertiseServices")):
        self.info = dict(SERVER_INFO, name="gated")
        if capabilities is not None:
            self.info["capabilities"] = capabilities
        self.frames = [m for m in (ADVERTISE, SERVICES) if m["op"] in send]
        self.gate = asyncio.Event()
        self.connections = 0
        self._ws: Any = None
        self._server: Any = None

    async def __aenter__(self) -> GatedServer:
        self._server = await websockets.serve(self._serve, "127.0.0.1", 0,
                                              subprotocols=["foxglove.sdk.v1"])  # type: ignore[list-item]
        return self

    async def __aexit__(self, *exc: object) -> None:
        self.gate.set()  # a connection still held at the gate ends too
        self._server.close()
        await self._server.wait_closed()

    @property
    def url(self) -> str:
        return f"ws://127.0.0.1:{self._server.sockets[0].getsockname()[1]}"

    async def _serve(self, ws: Any) -> None:
        self._ws = ws
        self.connections += 1
        try:
            await ws.send(json.dumps(self.info))
            await self.gate.wait()
            for m in self.frames:
                await ws.send(json.dumps(m))
            async for _ in ws:
                pass
        except websockets.ConnectionClosed:
            pass

    async def drop(self) -> None:
        await self._ws.close()


async def _connected(server: GatedServer, grace: float, **kw: Any) -> FoxgloveClient:
    client = FoxgloveClient(server.url, backoff_min=0.05, backoff_max=0.2, **kw)
    client.advertise_grace = grace
    await client.connect(timeout=10)
    return client


async def _begun(coro: Any) -> asyncio.Task:
    """``coro`` as a task that has run up to its first real wait."""
    task = asyncio.ensure_future(coro)
    await asyncio.sleep(0)
    return task


async def test_a_listing_made_before_the_advertisements_arrived_waits_for_them():
    """The reported bug: ``rcon topics`` printed a partial list (no ``/pose``) when its listing ran between
    ``serverInfo`` (CONNECTED) and the server's ``advertise``."""
    async with GatedServer() as server:
        client = await _connected(server, NEVER)
        try:
            assert client.state is ConnectionState.CONNECTED and not client.session.by_topic  # serverInfo only
            topics = await _begun(client.catalog.topics())
            services = await _begun(client.catalog.services_with_types())
            pose = await _begun(client.catalog.topic_type("/pose"))
            assert not topics.done(), f"listed before the server advertised anything: {topics.result()}"
            server.gate.set()
            listed = await asyncio.wait_for(topics, 10)
            assert set(listed) == TOPICS and listed["/pose"] == "geometry_msgs/msg/Pose"
            assert set(await asyncio.wait_for(services, 10)) == NAMES
            assert await asyncio.wait_for(pose, 10) == "geometry_msgs/msg/Pose"
            assert (await client.detect_ros()).version == 2  # told by the channels' schemas, so it waits too
        finally:
            await client.close()


async def test_a_listing_waits_for_the_services_only_where_the_server_has_them():
    """Without the ``services`` capability no ``advertiseServices`` is due: the channels complete a listing."""
    caps = [c for c in SERVER_INFO["capabilities"] if c != "services"]
    async with GatedServer(capabilities=caps, send=("advertise",)) as server:
        client = await _connected(server, NEVER)
        try:
            topics = await _begun(client.catalog.topics())
            assert not topics.done()
            server.gate.set()
            assert set(await asyncio.wait_for(topics, 10)) == TOPICS
            assert await asyncio.wait_for(client.catalog.services(), 10) == []
        finally:
            await client.close()
    async with GatedServer(send=("advertise",)) as server:  # with it, the channels alone are not the whole list
        client = await _connected(server, NEVER)
        try:
            server.gate.set()
            await until(lambda: client.session.by_topic, what="the channels")
            services = await _begun(client.catalog.services())
            assert not services.done(), "listed services before the server advertised its services"
        finally:
            await client.close()
        with pytest.raises(NotConnectedError):  # closed while it waited: the listing ends with the link
            await asyncio.wait_for(services, 10)


async def test_a_server_that_advertises_nothing_gets_an_empty_listing_never_a_hang():
    """foxglove-sdk sends no ``advertise`` when it has no channels and no ``advertiseServices`` when it has no
    services (the protocol's text says at least one ``advertise`` always comes; the servers do not all
    agree): after the grace the listing is what the server told, here nothing."""
    async with GatedServer(send=()) as server:
        client = await _connected(server, 0.2)
        try:
            server.gate.set()
            assert await asyncio.wait_for(client.catalog.topics(), 10) == {}
            assert await asyncio.wait_for(client.catalog.services_with_types(), 10) == {}
        finally:
            await client.close()


async def test_the_first_listing_after_a_reconnect_waits_for_the_new_sessions_advertisements():
    async with GatedServer() as server:
        client = await _connected(server, NEVER)
        try:
            server.gate.set()
            assert set(await asyncio.wait_for(client.catalog.topics(), 10)) == TOPICS
            server.gate.clear()
            await server.drop()
            await until(lambda: server.connections == 2 and client.state is ConnectionState.CONNECTED,
                        what="the reconnect")
            topics = await _begun(client.catalog.topics())
            assert not topics.done(), f"listed the new session before it advertised: {topics.result()}"
            server.gate.set()
            assert set(await asyncio.wait_for(topics, 10)) == TOPICS
        finally:
            await client.close()


def test_the_session_says_when_the_first_advertisements_came():
    """``session.told`` (what a listing waits for), fed the recorded frames one by one."""
    client = FoxgloveClient("ws://127.0.0.1:1")
    session = client.session
    session.attached(lambda frame: None, lambda data, pub, age: True)
    assert not session.told
    session.receive(json.dumps(SERVER_INFO))
    assert not session.told
    session.receive(json.dumps(ADVERTISE))
    assert not session.told, "the server has the services capability: its advertiseServices is due"
    session.receive(json.dumps(SERVICES))
    assert session.told
    session.detached()  # the next connection is told afresh
    assert not session.told and not session.by_topic
    session.attached(lambda frame: None, lambda data, pub, age: True)
    session.receive(json.dumps(dict(SERVER_INFO, capabilities=["clientPublish"])))
    session.receive(json.dumps({"op": "advertise", "channels": []}))  # an empty one counts: nothing to list
    assert session.told
