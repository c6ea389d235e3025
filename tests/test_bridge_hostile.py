"""BridgeClient against a hostile rosbridge server (issue 11, items 1-4 and 13): whatever one frame holds,
the client drops and counts it and the link carries on -- no frame ends the read loop."""

from __future__ import annotations

import os
import threading

import cbor2
import orjson
import pytest

from rcon_core.bridge import BridgeClient, ConnectionState
from rcon_core.bridge.safety import bounded_repr, png_decoded_size, safe_text
from rcon_core.loopback import HostileServer, png_data
from rcon_core.sim.encoding import fragments, png_frame
from rcon_core.testing import connected, until

pytestmark = pytest.mark.usefixtures("transport")  # every test runs on each transport

DEEP = "[" * 1000 + "]" * 1000  # orjson accepts it (its limit is 1024 levels); repr() of it recurses too deep


@pytest.fixture
async def hostile():
    async with HostileServer() as srv:
        yield srv


@pytest.fixture
async def client(hostile):
    async with connected(hostile.url, backoff_min=0.05, backoff_max=0.2, call_timeout=5) as c:
        yield c


async def subscribe(srv: HostileServer, client: BridgeClient, topic: str = "/t") -> list:
    got: list = []
    client.node("n").subscribe(topic, got.append)
    await srv.wait_for("subscribe", topic=topic)
    return got


async def still_serving(srv: HostileServer, client: BridgeClient, got: list, i: int = 1) -> None:
    """The same connection still delivers a valid message after the hostile frames."""
    await srv.send({"op": "publish", "topic": "/t", "msg": {"i": i}})
    await until(lambda: bool(got) and got[-1] == {"i": i})
    assert client.state is ConnectionState.CONNECTED and client.stats["connects"] == 1


# ------------------------------------------------------------------------------ 1: deep JSON


@pytest.mark.parametrize(("frame", "bad"), [
    ('{"x":' + DEEP + "}", 1),                                         # no 'op': formatted for the log
    ('{"op":' + DEEP + "}", 1),                                        # a non-string op
    ('{"op":"status","level":"error","id":' + DEEP + ',"msg":' + DEEP + "}", 0),  # logged, bounded
    (png_frame('{"x":' + DEEP + "}"), 1),                              # the same inside a png frame
], ids=["no-op", "deep-op", "status", "png"])
async def test_deeply_nested_json_is_dropped_and_the_link_stays(hostile, client, frame, bad):
    got = await subscribe(hostile, client)
    await hostile.send(frame)
    await still_serving(hostile, client, got)
    assert client.stats["bad_frames"] == bad and got == [{"i": 1}]


def test_bounded_repr_never_recurses_and_stays_short():
    deep = orjson.loads(DEEP)
    text = bounded_repr({"id": deep, "s": "x" * 10_000}, limit=100)
    assert len(text) <= 100 and text.startswith("{'id': [[[")
    assert bounded_repr(2 ** 100_000).startswith("<int of")
    assert "RecursionError" in safe_text(RecursionError("x")) and len(safe_text(KeyError(deep), 50)) < 80


# ------------------------------------------------------------------------------ 2: png data that decodes to nothing


@pytest.mark.parametrize("data", ["", "#", "====", "aGVsbG8=", "iVBORw0KGgo="])
async def test_png_frame_without_an_image_is_a_bad_frame(hostile, client, data):
    got = await subscribe(hostile, client)
    await hostile.send({"op": "png", "data": data})
    await still_serving(hostile, client, got)
    assert client.stats["bad_frames"] == 1


# ------------------------------------------------------------------------------ 3: PNG bombs


def test_png_header_gives_the_decoded_size_without_decoding():
    import base64

    assert png_decoded_size(base64.b64decode(png_data(b"{}", 40, 30))) == 40 * 30 * 3


async def test_png_bomb_is_refused_before_decoding(hostile):
    """A 1000x1000 RGB PNG (3 MB of pixels, a few KB on the wire) carrying a valid publish: a client that
    accepts frames of 1 MB refuses it from its header; one that accepts 4 MB decodes it."""
    inner = orjson.dumps({"op": "publish", "topic": "/t", "msg": {"bomb": True}})
    frame = {"op": "png", "data": png_data(inner, 1000, 1000)}
    assert len(orjson.dumps(frame)) < 20_000
    for limit, delivered in ((1 << 20, False), (4 << 20, True)):
        c = BridgeClient(hostile.url, max_size=limit)
        await c.connect(timeout=5)
        try:
            got = await subscribe(hostile, c)
            await hostile.send(frame)
            await hostile.send({"op": "publish", "topic": "/t", "msg": {"i": 1}})
            await until(lambda got=got: {"i": 1} in got)
            assert ({"bomb": True} in got) is delivered
            assert c.stats["png_refused"] == (0 if delivered else 1)
        finally:
            await c.close()


# ------------------------------------------------------------------------------ 4: big frames


async def test_default_max_size_fits_a_1080p_rgb8_image_and_is_configurable():
    c = BridgeClient("ws://127.0.0.1:1")
    assert c.max_size == 32 << 20 >= 1920 * 1080 * 3 * 4 // 3 + 4096  # base64 JSON of a 1080p rgb8 image
    assert BridgeClient("ws://127.0.0.1:1", max_size=1 << 20).max_size == 1 << 20


async def test_frames_above_max_size_are_dropped_and_the_link_stays(hostile):
    c = BridgeClient(hostile.url, max_size=1 << 20)
    await c.connect(timeout=5)
    try:
        got = await subscribe(hostile, c)
        await hostile.send({"op": "publish", "topic": "/t", "msg": {"blob": "x" * (3 << 19)}})  # 1.5 MB
        await still_serving(hostile, c, got)
        assert c.stats["oversize_frames"] == 1 and got == [{"i": 1}]
    finally:
        await c.close()


async def test_big_frames_are_decoded_in_a_worker_and_keep_their_order(hostile, client):
    got = await subscribe(hostile, client)
    big_json = {"op": "publish", "topic": "/t", "msg": {"n": 2, "blob": "j" * (3 << 20)}}
    big_cbor = cbor2.dumps({"op": "publish", "topic": "/t", "msg": {"n": 4, "blob": b"c" * (3 << 20)}})
    noise = os.urandom(1 << 20).hex()  # 2 MB that zlib cannot squeeze: the png frame is > 1 MB too
    big_png = {"op": "png", "data": png_data(orjson.dumps({"op": "publish", "topic": "/t",
                                                         "msg": {"n": 6, "blob": noise}}), 1000, 800)}
    assert len(orjson.dumps(big_png)) > client.big_frame
    for frame in ({"op": "publish", "topic": "/t", "msg": {"n": 1}}, big_json,
                  {"op": "publish", "topic": "/t", "msg": {"n": 3}}, big_cbor,
                  {"op": "publish", "topic": "/t", "msg": {"n": 5}}, big_png,
                  {"op": "publish", "topic": "/t", "msg": {"n": 7}}):
        await hostile.send(frame)
    await until(lambda: len(got) == 7)
    assert [m["n"] for m in got] == [1, 2, 3, 4, 5, 6, 7]
    assert got[3]["blob"] == b"c" * (3 << 20) and got[5]["blob"] == noise
    assert client.stats["big_frames"] == 3 and client.stats["bad_frames"] == 0
    assert any(t.name.startswith("rcon-bridge-decode") for t in threading.enumerate())


async def test_big_messages_completed_by_fragments_are_decoded_in_the_worker_in_order(hostile, client):
    """A 2 MB publish cut into rosbridge fragments, and a big png frame sent as pieces of its base64 data
    (``png`` with num/total): both are decoded off the loop, between small frames, in order."""
    got = await subscribe(hostile, client)
    big = orjson.dumps({"op": "publish", "topic": "/t", "msg": {"n": 2, "blob": "f" * (2 << 20)}}).decode()
    noise = os.urandom(1 << 20).hex()
    data = png_data(orjson.dumps({"op": "publish", "topic": "/t", "msg": {"n": 4, "blob": noise}}), 1000, 800)
    size = len(data) // 3 + 1
    pieces = [{"op": "png", "id": "p", "data": data[i:i + size], "num": n, "total": 3}
              for n, i in enumerate(range(0, len(data), size))]
    frames = [{"op": "publish", "topic": "/t", "msg": {"n": 1}}, *fragments(big, 400_000),
              {"op": "publish", "topic": "/t", "msg": {"n": 3}}, *pieces, {"op": "publish", "topic": "/t", "msg": {"n": 5}}]
    for frame in frames:
        await hostile.send(frame)
    await until(lambda: len(got) == 5)
    assert [m["n"] for m in got] == [1, 2, 3, 4, 5] and got[3]["blob"] == noise
    assert client.stats["big_frames"] == 2 and client.stats["bad_frames"] == 0


async def test_a_broken_big_frame_is_a_bad_frame(hostile, client):
    got = await subscribe(hostile, client)
    await hostile.send('{"op":"publish","topic":"/t","msg":{"blob":"' + "x" * (2 << 20))
    await hostile.send(b"\xff" * (2 << 20))
    await still_serving(hostile, client, got)
    assert client.stats["bad_frames"] == 2 and client.stats["big_frames"] == 2


# ------------------------------------------------------------------------------ 13: non-object msg


@pytest.mark.parametrize("msg", [5, [1, 2], "text", None, True])
async def test_publish_whose_msg_is_not_an_object_is_dropped_and_counted(hostile, client, msg):
    got = await subscribe(hostile, client)
    await hostile.send({"op": "publish", "topic": "/t", "msg": msg})
    await hostile.send(cbor2.dumps({"op": "publish", "topic": "/t", "msg": msg}), text=False)
    await still_serving(hostile, client, got)
    assert got == [{"i": 1}] and client.stats["non_object_msgs"] == 2


# ------------------------------------------------------------------------------ invalid UTF-8, any size


@pytest.mark.parametrize("size", [100, 40_000, 1_500_000], ids=["small", "heavy", "big"])
async def test_a_text_message_that_is_not_utf8_closes_the_link_whatever_its_size(hostile, client, size):
    """The WebSocket rule (1007), on each transport: the small ones are parsed in the transport's callback,
    the heavy ones (32 kB or more) after a copy, the big ones (over 1 MB) in the worker thread."""
    got = await subscribe(hostile, client)
    pad = "x" * size
    frame = b'{"op":"publish","topic":"/t","msg":{"s":"\xff\xfe' + pad.encode() + b'"}}'
    await hostile.send(frame, text=True)
    await until(lambda: client.stats["connects"] == 2 and client.state is ConnectionState.CONNECTED, 10)
    await hostile.wait_for("subscribe", topic="/t", count=2)
    await hostile.send({"op": "publish", "topic": "/t", "msg": {"i": 1}})
    await until(lambda: got == [{"i": 1}])
    assert client.stats["bad_frames"] == 0
