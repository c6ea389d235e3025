"""Fuzz on the Foxglove link: a hostile Foxglove server sends seeded garbage (``rcon_core/foxglove/fuzz.py``)
mixed with valid messages; the client never dies, counts every bad frame, and every valid message arrives
exactly once and in order.  A text frame that is not UTF-8 closes the connection (a WebSocket rule): the
client reconnects, resubscribes, and the run goes on."""

from __future__ import annotations

import asyncio
import collections
import json

import pytest
import websockets

from rcon_core.bridge import ConnectionState
from rcon_core.foxglove import FoxgloveClient
from rcon_core.foxglove.fuzz import CHANNEL_ID, fuzz_frames
from rcon_core.testing import until

pytestmark = pytest.mark.usefixtures("transport")  # every test runs on each WebSocket transport

SEEDS = (11, 2026)
FRAMES = 2500
INFO = {"op": "serverInfo", "name": "hostile", "capabilities": ["parameters", "services", "connectionGraph"],
        "supportedEncodings": ["json"]}
ADVERTISE = {"op": "advertise", "channels": [{"id": CHANNEL_ID, "topic": "/fuzz", "encoding": "json",
                                              "schemaName": "Fuzz", "schemaEncoding": "jsonschema", "schema": "{}"}]}


class HostileFoxServer:
    def __init__(self, frames) -> None:
        self.frames = collections.deque(frames)
        self.done = asyncio.Event()
        self.fatal = 0
        self.server = None

    async def serve(self, ws) -> None:
        await ws.send(json.dumps(INFO))
        await ws.send(json.dumps(ADVERTISE))
        sub = None
        while sub is None:
            m = json.loads(await ws.recv())
            if m.get("op") == "subscribe":
                sub = next(s["id"] for s in m["subscriptions"] if s["channelId"] == CHANNEL_ID)
        while self.frames:
            frame = self.frames.popleft()
            data = frame.data(sub) if callable(frame.data) else frame.data
            if frame.kind == "invalid-utf8":
                self.fatal += 1
                await ws.send(websockets.frames.Frame(websockets.frames.Opcode.TEXT, data))  # raw bytes as text
                await ws.wait_closed()
                return
            await ws.send(data)
        self.done.set()
        await ws.wait_closed()


@pytest.mark.parametrize("seed", SEEDS)
async def test_hostile_foxglove_frames_never_kill_the_client_and_every_valid_message_arrives(seed):
    frames = fuzz_frames(seed, FRAMES)
    kinds = collections.Counter(f.kind for f in frames)
    assert len(kinds) >= 30 and kinds["invalid-utf8"] == 1, kinds
    expected = [f.seq for f in frames if f.kind == "valid"]
    hostile = HostileFoxServer(frames)
    async with websockets.serve(hostile.serve, "127.0.0.1", 0, subprotocols=["foxglove.sdk.v1"],
                                max_size=None) as server:
        url = f"ws://127.0.0.1:{server.sockets[0].getsockname()[1]}"
        client = FoxgloveClient(url, backoff_min=0.01, backoff_max=0.05)
        got: list = []
        client.node("fuzz").subscribe("/fuzz", got.append)
        await client.connect(timeout=5)
        try:
            await asyncio.wait_for(hostile.done.wait(), 60)
            await until(lambda: len(got) >= len(expected), what="every message the server sent")
            assert got == [{"seq": n} for n in expected]
            assert client.state is ConnectionState.CONNECTED
            assert client.stats["connects"] == hostile.fatal + 1
            assert client.stats["bad_frames"] > FRAMES // 3
            assert client.stats["undecodable"] >= 0
        finally:
            await client.close()
