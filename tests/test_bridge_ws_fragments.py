"""Messages split into WebSocket continuation frames, on each transport: joined and delivered in order, and a
data frame that interrupts an unfinished message fails the link with 1002 (the WebSocket rule), after which
the client reconnects.  picows hands the client single frames (``pwlink.py`` joins them itself); websockets
joins them in its own reader."""

from __future__ import annotations

import struct

import cbor2
import orjson
import pytest

from rcon_core.bridge import ConnectionState
from rcon_core.loopback import HostileServer
from rcon_core.testing import connected, until

pytestmark = pytest.mark.usefixtures("transport")  # every test runs on each transport


@pytest.fixture
async def hostile():
    async with HostileServer() as srv:
        yield srv


def frame(opcode: int, payload: bytes, fin: bool = True) -> bytes:
    """One unmasked (server-to-client) WebSocket frame."""
    head = (0x80 if fin else 0) | opcode
    n = len(payload)
    if n < 126:
        return bytes((head, n)) + payload
    if n < 1 << 16:
        return bytes((head, 126)) + struct.pack("!H", n) + payload
    return bytes((head, 127)) + struct.pack("!Q", n) + payload


def publish(i: int, pad: str = "") -> bytes:
    return orjson.dumps({"op": "publish", "topic": "/t", "msg": {"i": i, "pad": pad}})


async def test_a_message_in_continuation_frames_is_joined_and_delivered_in_order(hostile):
    async with connected(hostile.url, backoff_min=0.05, backoff_max=0.2) as client:
        got: list = []
        client.node("n").subscribe("/t", lambda m: got.append(m["i"]))
        await hostile.wait_for("subscribe", topic="/t")
        text = publish(2, "x" * 50_000)  # a heavy one (32 kB or more) in three parts
        cbor = cbor2.dumps({"op": "publish", "topic": "/t", "msg": {"i": 4, "pad": ""}})
        ws = hostile.ws
        assert ws is not None
        ws.transport.write(
            frame(0x1, publish(1))                                    # whole, small
            + frame(0x1, text[:10], fin=False) + frame(0x0, text[10:30_000], fin=False)
            + frame(0x9, b"ping", fin=True)                           # a control frame may come in between
            + frame(0x0, text[30_000:])
            + frame(0x1, publish(3)[:5], fin=False) + frame(0x0, publish(3)[5:])   # small, in two parts
            + frame(0x2, cbor[:7], fin=False) + frame(0x0, cbor[7:])  # binary (CBOR), in two parts
            + frame(0x1, publish(5)))
        await until(lambda: len(got) >= 5)
        assert got == [1, 2, 3, 4, 5]
        assert client.stats["connects"] == 1 and client.stats["bad_frames"] == 0
        assert client.traffic.snapshot()[1]["/t"] == (sum(map(len, (publish(1), text, publish(3), cbor, publish(5)))), 5)


@pytest.mark.parametrize("interrupting", [frame(0x1, publish(9)), frame(0x2, b"\xa0"), frame(0x1, b"{", fin=False)],
                         ids=["text", "binary", "text-unfinished"])
async def test_a_data_frame_inside_an_unfinished_message_fails_the_link_with_1002(hostile, interrupting):
    async with connected(hostile.url, backoff_min=0.05, backoff_max=0.2) as client:
        got: list = []
        client.node("n").subscribe("/t", lambda m: got.append(m["i"]))
        await hostile.wait_for("subscribe", topic="/t")
        ws = hostile.ws
        assert ws is not None
        ws.transport.write(frame(0x1, publish(1)) + frame(0x1, publish(2)[:5], fin=False) + interrupting)
        await until(lambda: client.stats["connects"] == 2 and client.state is ConnectionState.CONNECTED, 10)
        assert ws.close_code == 1002
        await hostile.wait_for("subscribe", topic="/t", count=2)
        await hostile.send(publish(3), text=True)
        await until(lambda: got == [1, 3])


async def test_a_continuation_frame_without_a_message_fails_the_link_with_1002(hostile):
    async with connected(hostile.url, backoff_min=0.05, backoff_max=0.2) as client:
        got: list = []
        client.node("n").subscribe("/t", lambda m: got.append(m["i"]))
        await hostile.wait_for("subscribe", topic="/t")
        ws = hostile.ws
        assert ws is not None
        ws.transport.write(frame(0x1, publish(1)) + frame(0x0, publish(2)))
        await until(lambda: client.stats["connects"] == 2 and client.state is ConnectionState.CONNECTED, 10)
        assert ws.close_code == 1002 and got[:1] == [1]
