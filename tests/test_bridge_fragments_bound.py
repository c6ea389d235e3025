"""issue 22.5: unfinished fragmented messages on the client are bounded. A hostile server that starts
fragmented messages and never finishes them held 256 MB for good (8 unfinished messages just under the
32 MB frame limit; 64 of them, the most kept, would be 2 GB): they were expired only when another
fragment arrived, and they survived reconnects. Now they expire by age on a timer, all of them together
hold at most twice the frame limit, and a lost connection drops them."""

from __future__ import annotations

import orjson
import pytest

from rcon_core.bridge.errors import ProtocolError
from rcon_core.bridge.protocol import FragmentAssembler
from rcon_core.loopback import HostileServer
from rcon_core.testing import connected, until


def piece(fid, num: int, total: int, size: int) -> dict:
    return {"op": "fragment", "id": fid, "data": "x" * size, "num": num, "total": total}


def test_64_unfinished_messages_hold_at_most_twice_the_frame_limit():
    """64 messages of (nearly) the frame limit each, none finished: 2 GB at 32 MB; here at 1 MB, 64 MB
    were held; now at most 2 MB, the newest kept."""
    asm = FragmentAssembler(max_bytes=1 << 20, warn=lambda _m: None)
    for fid in range(64):
        for num in range(4):
            asm.add(piece(fid, num, 5, 250_000))
    assert asm.buffered_bytes <= 2 << 20
    assert len(asm) == 2 and asm.dropped == 62
    with pytest.raises(ProtocolError, match="exceeds"):  # one message is still bounded by max_bytes
        for num in range(5):
            asm.add(piece("big", num, 6, 250_000))
    assert asm.buffered_bytes == sum(1_000_000 for _ in range(len(asm)))


def test_a_finished_message_frees_its_bytes():
    asm = FragmentAssembler(max_bytes=1000)
    assert asm.add(piece(1, 0, 2, 300)) is None and asm.buffered_bytes == 300
    assert asm.add(piece(1, 1, 2, 300)) == "x" * 600
    assert asm.buffered_bytes == 0 and asm.completed == 1
    asm.add(piece(2, 0, 2, 300))
    assert asm.clear() == 1 and asm.buffered_bytes == 0 and len(asm) == 0


@pytest.fixture
async def hostile():
    async with HostileServer() as srv:
        yield srv


async def test_unfinished_messages_expire_without_new_fragments(hostile):
    """Before: an unfinished message stayed until the next fragment came, i.e. for good on a quiet link."""
    async with connected(hostile.url, fragment_timeout=0.3) as client:
        await hostile.wait(lambda: hostile.ws is not None)
        for fid in range(8):
            await hostile.send(orjson.dumps(piece(fid, 0, 3, 100_000)).decode())
        await until(lambda: len(client.inbound.fragments) == 8, what="8 unfinished messages")
        assert client.inbound.fragments.buffered_bytes == 800_000
        await until(lambda: len(client.inbound.fragments) == 0, timeout=5, what="expired by age, no new frame")
        assert client.inbound.fragments.buffered_bytes == 0


async def test_a_lost_connection_drops_the_unfinished_messages(hostile):
    """Before: the messages begun on one connection survived the reconnect (and could be completed by
    fragments of another conversation on the next connection)."""
    async with connected(hostile.url, backoff_min=0.05, backoff_max=0.1, fragment_timeout=60) as client:
        got: list = []
        client.node("n").subscribe("/t", got.append)
        await hostile.wait_for("subscribe", topic="/t")
        text = orjson.dumps({"op": "publish", "topic": "/t", "msg": {"n": 1}}).decode()
        half = len(text) // 2
        first = {"op": "fragment", "id": 7, "data": text[:half], "num": 0, "total": 2}
        await hostile.send(first)
        await until(lambda: len(client.inbound.fragments) == 1, what="one unfinished message")
        await hostile.drop()
        await until(lambda: client.stats["connects"] == 2, what="the reconnect")
        assert len(client.inbound.fragments) == 0 and client.inbound.fragments.buffered_bytes == 0
        await hostile.wait(lambda: hostile.ws is not None)
        await hostile.send({"op": "fragment", "id": 7, "data": text[half:], "num": 1, "total": 2})
        await hostile.send({"op": "publish", "topic": "/t", "msg": {"n": 2}})
        await until(lambda: got == [{"n": 2}], what="the next message, and not the half of the old one")
