"""Fuzz: a hostile rosbridge server sends seeded garbage mixed with valid publishes; the client never dies,
every valid message arrives exactly once and in order, nothing else reaches the callback (issue 11)."""

from __future__ import annotations

import asyncio
import collections

import pytest

from rcon_core.bridge import BridgeClient, ConnectionState
from rcon_core.fuzz import FuzzRun, fuzz_frames
from rcon_core.loopback import HostileServer
from rcon_core.testing import until

pytestmark = pytest.mark.usefixtures("transport")  # every test runs on each transport

SEEDS = (11, 2026)
FRAMES = 2500


@pytest.mark.parametrize("seed", SEEDS)
async def test_hostile_frames_never_kill_the_client_and_every_valid_message_arrives(seed):
    kinds = collections.Counter(f.kind for f in fuzz_frames(seed, FRAMES, bomb_pixels=3 << 20))
    assert len(kinds) >= 15 and kinds["invalid-utf8"] >= 1 and kinds["png-bomb"] >= 1, kinds
    async with HostileServer() as server:
        run = FuzzRun(server, fuzz_frames(seed, FRAMES, bomb_pixels=3 << 20))
        client = BridgeClient(server.url, backoff_min=0.01, backoff_max=0.05, max_size=2 << 20)
        got: list = []
        client.node("fuzz").subscribe("/fuzz", got.append)
        await client.connect(timeout=5)
        try:
            await asyncio.wait_for(run.done.wait(), 60)
            await until(lambda: len(got) >= len(run.expected), what="every message the server sent")
            assert got == [{"seq": n} for n in run.expected]
            assert client.state is ConnectionState.CONNECTED
            assert client.stats["connects"] == run.fatal + 1  # only invalid UTF-8 closes a link (WebSocket rule)
            assert client.stats["bad_frames"] > FRAMES // 3 and client.stats["non_object_msgs"] > 0
            assert client.stats["png_refused"] > 0 and client.stats["frame_errors"] >= 0
        finally:
            await client.close()
