"""Frames recorded from the real foxglove-sdk server (``tests/recordings/foxglove-sdk-0.30.3``, made by
``tools/record_foxglove.py``) replayed into the pure session state machine, and the older subprotocol
``foxglove.websocket.v1`` against a server that speaks only that (``tests/fox_legacy.py``)."""

from __future__ import annotations

import base64
import json

import pytest
from fox_legacy import LegacyServer, recorded

from rcon_core.foxglove import FoxgloveClient, wire
from rcon_core.link import detect
from rcon_core.testing import until

pytestmark = pytest.mark.usefixtures("transport")  # every test runs on each WebSocket transport


def _frames(direction: str) -> list[str | bytes]:
    return [f["text"] if "text" in f else base64.b64decode(f["b64"]) for f in recorded() if f["dir"] == direction]


def test_every_recorded_server_frame_is_understood_without_a_bad_frame():
    client = FoxgloveClient("ws://127.0.0.1:1")
    session = client.session
    out: list = []
    session.attached(out.append, lambda data, pub, age: out.append(data) or True)
    got: dict[str, list] = {}
    node = client.node("replay")
    for topic in ("/chatter", "/rosout_str", "/pose", "/camera/compressed", "/gps"):
        node.subscribe(topic, lambda m, t=topic: got.setdefault(t, []).append(m))
    frames = _frames("in")
    for frame in frames[:2]:  # serverInfo, advertise: the subscriptions follow the channels
        session.receive(frame)
    subs = {json.loads(f)["subscriptions"][0]["channelId"]: json.loads(f)["subscriptions"][0]["id"]
            for f in out if isinstance(f, str) and json.loads(f)["op"] == "subscribe"}
    assert len(subs) == 5
    # the recording's subscription ids differ from this session's: map them through the channel ids
    recorded_sub = json.loads(next(f for f in _frames("out") if isinstance(f, str) and '"subscribe"' in f))
    channel_of = {s["id"]: s["channelId"] for s in recorded_sub["subscriptions"]}
    for frame in frames[2:]:
        if isinstance(frame, bytes) and frame[0] == wire.MESSAGE_DATA:
            _, sub, stamp, payload, _whole = wire.parse_binary(frame)
            frame = wire.message_frame(subs[channel_of[sub]], stamp, bytes(payload))
        session.receive(frame)
    assert client.stats["bad_frames"] == 0
    assert got["/chatter"] == [{"data": "hello"}]
    assert got["/rosout_str"] == [{"data": "hello cdr"}]
    assert got["/pose"][0]["position"]["x"] == 1.5
    assert got["/camera/compressed"][0]["data"].startswith(b"\xff\xd8")
    assert got["/gps"][0]["latitude"] == 57.7
    assert session.time_ns == 1_700_000_000_000_000_000
    assert session.requests.params["/boat.max_speed"] == 2.5
    assert session.graph["published"]["/pose"] == ["/boat"]
    assert session.service_by_name["/reset"].request["schemaEncoding"] == "ros2msg"


def test_the_recorded_client_frames_are_what_this_client_writes():
    ops = {json.loads(f)["op"] for f in _frames("out") if isinstance(f, str)} - {"bogus"}
    assert ops == {"subscribe", "getParameters", "subscribeConnectionGraph"}
    assert wire.subscribe_frame([(1, 4)]) == '{"op":"subscribe","subscriptions":[{"id":1,"channelId":4}]}'
    call = next(f for f in _frames("out") if isinstance(f, bytes))
    assert call == wire.call_frame(1, 7, "cdr", call[16:])


async def test_a_server_speaking_only_the_older_subprotocol():
    async with LegacyServer() as server:
        assert await detect(server.url) == "foxglove"
        client = FoxgloveClient(server.url, reconnect=False, call_timeout=5)
        await client.connect(timeout=5)
        try:
            assert client.subprotocol == "foxglove.websocket.v1"
            got: list = []
            client.node("old").subscribe("/pose", got.append)
            await until(lambda: got, what="the recorded pose")
            assert got[0]["position"]["x"] == 1.5
            # services in the older shape: the schemas are text, the encoding the server's first one
            assert await client.call_service("/reset", {}) == {"success": True, "message": "reset done"}
            assert client.stats["bad_frames"] == 0
        finally:
            await client.close()
