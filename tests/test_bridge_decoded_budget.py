"""issue 22.14 (client side): the 32 MB frame limit bounded the bytes on the wire, not the objects they
become: a 30 MB frame peaked at +300-450 MB (a JSON array of numbers: 32 bytes of objects per 4 bytes of
text). A big frame is now refused when its objects would take more than the client's ``max_decoded``
(four times ``max_size`` by default): a JSON frame by an estimate counted in its text before it is parsed,
a CBOR frame as it is decoded. Here at a smaller scale (``max_size`` 4 MB, 16 MB of objects)."""

from __future__ import annotations

import base64
import tracemalloc

import cbor2
import numpy as np
import orjson
import pytest

from rcon_core.bridge import protocol
from rcon_core.bridge.protocol import (
    JSON_MOST_PER_BYTE,
    DecodedTooBig,
    check_json_size,
    decode_binary,
    json_decoded_size,
)
from rcon_core.loopback import HostileServer
from rcon_core.testing import connected, until


def measured(text: bytes) -> int:
    """Bytes of Python objects ``orjson.loads(text)`` makes (tracemalloc)."""
    tracemalloc.start()
    try:
        before = tracemalloc.get_traced_memory()[0]
        value = orjson.loads(text)
        size = tracemalloc.get_traced_memory()[0] - before
    finally:
        tracemalloc.stop()
    del value
    return size


@pytest.mark.parametrize("text", [
    b"[" + b",".join([b"0.5"] * 200_000) + b"]",                              # floats
    b"[" + b",".join([b"{}"] * 100_000) + b"]",                               # empty objects
    b"[" + b",".join([b"[1,2]"] * 100_000) + b"]",                            # small lists
    orjson.dumps([{"name": f"n{i}", "x": i * 0.5, "s": "abc" * 5} for i in range(30_000)]),
    orjson.dumps({"data": base64.b64encode(bytes(3_000_000)).decode()}),      # an image's base64
], ids=["floats", "dicts", "lists", "records", "base64"])
def test_the_estimate_covers_what_parsing_makes(text):
    assert json_decoded_size(text) >= 0.9 * measured(text)
    assert json_decoded_size(text.decode()) == json_decoded_size(text)


@pytest.mark.parametrize("text", [
    b"[" + b",".join([b"{}"] * 10_000) + b"]",
    b'{"":' * 5_000 + b"1" + b"}" * 5_000,
    b"[" * 5_000 + b"]" * 5_000,
    b"[" + b",".join([b'""'] * 10_000) + b"]",
    b"[" + b",".join([b"0.5"] * 10_000) + b"]",
], ids=["empty-objects", "nested-objects", "nested-lists", "empty-strings", "floats"])
def test_no_frame_counts_for_more_than_the_most_per_byte(text):
    """The shortcut in check_json_size (a frame shorter than budget / JSON_MOST_PER_BYTE is not counted)
    is sound only if no JSON text's estimate is above that many bytes per byte."""
    assert json_decoded_size(text) <= JSON_MOST_PER_BYTE * len(text)


def test_a_short_frame_is_not_counted_a_long_one_is(monkeypatch):
    """Counting cost ten times the parse of a 1.2 MB JSON camera frame (6 ms against 0.6; bench_bridge's
    image JSON phase: 7.1 ms a frame against 1.2 before the budget)."""
    counted: list[int] = []
    real = protocol.json_decoded_size
    monkeypatch.setattr(protocol, "json_decoded_size", lambda raw: counted.append(len(raw)) or real(raw))
    frame = orjson.dumps({"data": base64.b64encode(bytes(900_000)).decode()})
    check_json_size(frame, 128 << 20)  # 1.2 MB under a 128 MB budget: cannot be over it
    assert counted == []
    check_json_size(frame, len(frame) * JSON_MOST_PER_BYTE - 1)  # could be: counted, and well under it
    assert counted == [len(frame)]
    with pytest.raises(DecodedTooBig):
        check_json_size(b"[" + b",".join([b"{}"] * 10_000) + b"]", 1 << 20)


def test_cbor_typed_arrays_and_maps_are_counted_as_they_are_decoded():
    floats = cbor2.dumps({"data": cbor2.CBORTag(85, np.zeros(1_000_000, "<f4").tobytes())})  # float32 LE
    assert len(decode_binary(floats, budget=64 << 20)["data"]) == 1_000_000
    with pytest.raises(DecodedTooBig, match="CBOR frame"):
        decode_binary(floats, budget=16 << 20)  # 1M floats as a list: 32 MB of objects from 4 MB
    maps = cbor2.dumps([{} for _ in range(200_000)])  # 1 byte each on the wire, ~100 bytes decoded
    with pytest.raises(DecodedTooBig):
        decode_binary(maps, budget=8 << 20)
    raw = cbor2.dumps({"data": cbor2.CBORTag(64, bytes(3_000_000))})  # uint8[]: stays bytes
    assert decode_binary(raw, budget=8 << 20)["data"] == bytes(3_000_000)


async def test_a_frame_of_numbers_is_refused_and_the_link_goes_on():
    """A 3.5 MB JSON frame of floats (28 MB of objects) with a 4 MB frame limit and a 16 MB budget."""
    async with HostileServer() as srv, connected(srv.url, max_size=4 << 20) as client:
        assert client.max_decoded == 16 << 20
        got: list = []
        client.node("n").subscribe("/t", got.append)
        await srv.wait_for("subscribe", topic="/t")
        numbers = '{"op":"publish","topic":"/t","msg":{"data":[' + ",".join(["0.5"] * 875_000) + "]}}"
        assert 3 << 20 < len(numbers) < 4 << 20
        await srv.send(numbers)
        picture = orjson.dumps({"op": "publish", "topic": "/t",
                                "msg": {"data": base64.b64encode(bytes(2_500_000)).decode()}}).decode()
        await srv.send(picture)  # as big on the wire, a few MB of objects: delivered
        await srv.send({"op": "publish", "topic": "/t", "msg": {"n": 1}})
        await until(lambda: len(got) == 2, what="the picture and the next message")
        assert len(got[0]["data"]) == len(base64.b64encode(bytes(2_500_000))) and got[1] == {"n": 1}
        assert client.stats["decode_refused"] == 1 and client.stats["connects"] == 1
