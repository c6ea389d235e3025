"""Flatbuffer channels on the Foxglove link (``rcon_core/foxglove/flatbuf.py``): Foxglove's own schemas are
decoded with the classes Foxglove publishes (``foxglove-schemas-flatbuffer``) into the same dicts as the
protobuf ones; any other flatbuffer schema is refused in words, and the flight recorder still records it,
bytes and schema as sent.  The peer is the foxglove-sdk server with flatbuffer channels added."""

from __future__ import annotations

import asyncio
import random
from importlib import resources
from pathlib import Path
from typing import Any

import flatbuffers
import foxglove
import pytest
from foxglove_schemas_flatbuffer import CompressedImage as FbImage
from foxglove_schemas_flatbuffer import LocationFix as FbFix
from foxglove_schemas_flatbuffer import Time as FbTime
from mcap.reader import make_reader

from rcon_core.foxglove import FoxgloveClient
from rcon_core.foxglove.flatbuf import decoder
from rcon_core.foxglove.testing import FoxPeer
from rcon_core.record.foxglove_source import recorder_for, wait_profile
from rcon_core.record.writer import McapSink
from rcon_core.testing import until

pytestmark = pytest.mark.usefixtures("transport")  # every test runs on each WebSocket transport


def get_schema(name: str) -> bytes:
    """The ``.bfbs`` Foxglove ships beside its generated class."""
    return (resources.files("foxglove_schemas_flatbuffer") / f"{name}.bfbs").read_bytes()


def fb_image(data: bytes, sec: int = 5, nsec: int = 7) -> bytes:
    b = flatbuffers.Builder(256)
    frame, fmt, payload = b.CreateString("cam"), b.CreateString("jpeg"), b.CreateByteVector(data)
    FbImage.Start(b)
    FbImage.AddTimestamp(b, FbTime.CreateTime(b, sec, nsec))
    FbImage.AddFrameId(b, frame)
    FbImage.AddData(b, payload)
    FbImage.AddFormat(b, fmt)
    b.Finish(FbImage.End(b))
    return bytes(b.Output())


def fb_fix(lat: float, lon: float) -> bytes:
    b = flatbuffers.Builder(256)
    frame = b.CreateString("gps")
    FbFix.Start(b)
    FbFix.AddFrameId(b, frame)
    FbFix.AddLatitude(b, lat)
    FbFix.AddLongitude(b, lon)
    FbFix.AddAltitude(b, 1.0)
    b.Finish(FbFix.End(b))
    return bytes(b.Output())


def flatbuffer_channel(peer: FoxPeer, topic: str, name: str, schema: bytes) -> Any:
    return foxglove.Channel(topic, message_encoding="flatbuffer", context=peer.ctx,
                            schema=foxglove.Schema(name=name, encoding="flatbuffer", data=schema))


@pytest.fixture
def peer():
    p = FoxPeer()
    p.fb_image = flatbuffer_channel(p, "/fb/image", "foxglove.CompressedImage", get_schema("CompressedImage"))
    p.fb_fix = flatbuffer_channel(p, "/fb/fix", "foxglove.LocationFix", get_schema("LocationFix"))
    p.fb_other = flatbuffer_channel(p, "/fb/other", "acme.Sonar", b"ACME-bfbs-\x00\x01\x02")
    yield p
    p.stop()


async def test_foxglove_flatbuffer_types_read_as_the_protobuf_ones(peer: FoxPeer) -> None:
    client = FoxgloveClient(peer.url, call_timeout=5)
    await client.connect(timeout=10)
    try:
        await until(lambda: "/fb/image" in client.session.by_topic, what="the flatbuffer channels")
        assert (await client.catalog.topics())["/fb/image"] == "foxglove.CompressedImage"
        got: dict[str, list[dict[str, Any]]] = {"/fb/image": [], "/fb/fix": [], "/camera/compressed": [], "/gps": []}
        node = client.node("test")
        for topic, box in got.items():
            node.subscribe(topic, box.append)
        await until(lambda: all(peer.subscribers.get(t) == 1 for t in got), what="subscribed")
        peer.fb_image.log(fb_image(b"\xff\xd8jpeg"))
        peer.fb_fix.log(fb_fix(57.7, 11.97))
        peer.log_image(b"\xff\xd8jpeg")  # the same values over protobuf
        peer.log_fix(57.7, 11.97)
        await until(lambda: all(got.values()), what="a message on each")
    finally:
        await client.close()
    image, fix = got["/fb/image"][0], got["/fb/fix"][0]
    assert (image["data"], image["format"], image["frame_id"]) == (b"\xff\xd8jpeg", "jpeg", "cam")
    assert image["header"] == {"stamp": {"sec": 5, "nanosec": 7}, "frame_id": "cam"}  # the ROS header it maps to
    assert (fix["latitude"], fix["longitude"], fix["frame_id"]) == (57.7, 11.97, "gps")
    proto_image, proto_fix = got["/camera/compressed"][0], got["/gps"][0]
    assert set(proto_image) == set(image) and (proto_image["data"], proto_image["format"]) == (image["data"], "jpeg")
    assert set(proto_fix) == set(fix) and (proto_fix["latitude"], proto_fix["longitude"]) == (57.7, 11.97)


async def test_another_flatbuffer_schema_is_refused_in_words_and_still_recorded(peer: FoxPeer, tmp_path: Path) -> None:
    client = FoxgloveClient(peer.url, call_timeout=5)
    await client.connect(timeout=10)
    statuses: list[dict[str, Any]] = []
    client.add_status_listener(statuses.append)
    out = tmp_path / "fb.mcap"
    try:
        await until(lambda: "/fb/other" in client.session.by_topic, what="the flatbuffer channels")
        got: list[Any] = []
        client.node("widget").subscribe("/fb/other", got.append)
        await until(lambda: any("/fb/other" in s["msg"] for s in statuses), what="the refusal")
        words = next(s["msg"] for s in statuses if "/fb/other" in s["msg"])
        assert "Foxglove's own schemas only" in words and "acme.Sonar" in words
        sink = McapSink(str(out), await wait_profile(client, ["/fb/other", "/fb/image"]))
        rec = recorder_for(client, sink, ros2=False, topics=["/fb/other", "/fb/image"], operator=False)
        await rec.start()
        await until(lambda: peer.subscribers.get("/fb/other") == 1 and peer.subscribers.get("/fb/image") == 1,
                    what="the recorder subscribed")
        sonar = [bytes([i]) * 10 for i in range(5)]
        for data in sonar:
            peer.fb_other.log(data)
            peer.fb_image.log(fb_image(data))
        await until(lambda: sink.stats.per_topic.get("/fb/other") == 5 and sink.stats.per_topic.get("/fb/image") == 5,
                    what="recorded")
        rec.stop()
        await asyncio.get_running_loop().run_in_executor(None, sink.close)
        assert got == []  # the widget got nothing it could not read
    finally:
        await client.close()
    with open(out, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        msgs: dict[str, list[bytes]] = {}
        for _s, ch, m in reader.iter_messages():
            msgs.setdefault(ch.topic, []).append(m.data)
    chans = {c.topic: (summary.schemas[c.schema_id], c) for c in summary.channels.values() if c.schema_id}
    schema, ch = chans["/fb/other"]
    assert (schema.name, schema.encoding, schema.data, ch.message_encoding) == (
        "acme.Sonar", "flatbuffer", b"ACME-bfbs-\x00\x01\x02", "flatbuffer")
    assert msgs["/fb/other"] == sonar
    schema, _ch = chans["/fb/image"]
    assert schema.data == get_schema("CompressedImage")  # the .bfbs, stored as its bytes (sent in base64)
    assert [decoder("foxglove.CompressedImage")(d)["data"] for d in msgs["/fb/image"]] == sonar


def test_hostile_flatbuffers_are_refused_never_hang() -> None:
    """Mutated and random buffers: a ValueError or a dict, never another exception, never a long loop."""
    decode = decoder("foxglove.CompressedImage")
    assert decode is not None
    good = fb_image(b"\xff\xd8" + bytes(200))
    rng = random.Random(26)
    outcomes = {"ok": 0, "refused": 0}
    for i in range(3000):
        bad = bytearray(good) if i % 3 else bytearray(rng.randbytes(rng.randint(0, 64)))
        for _ in range(rng.randint(1, 4)):
            if bad:
                bad[rng.randrange(len(bad))] = rng.randrange(256)
        try:
            assert isinstance(decode(bytes(bad)), dict)
            outcomes["ok"] += 1
        except ValueError:
            outcomes["refused"] += 1
    assert outcomes["ok"] and outcomes["refused"]
    assert decoder("acme.Sonar") is None and decoder("foxglove.NoSuchType") is None and decoder("foxglove.a.b") is None
