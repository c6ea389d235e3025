"""Hostile Foxglove frames for the fuzz test: seeded garbage of every shape the protocol allows a server to
get wrong, mixed with valid ``{"seq": n}`` JSON messages on one channel.  The test server
(``tests/test_foxglove_fuzz.py``) sends them; the client must survive each, count it, and deliver every
valid message exactly once, in order.

A frame is ``(kind, data)`` where ``data`` is ``str`` (a text frame), ``bytes`` (binary), or a callable
``data(sub_id) -> bytes`` for frames that need the connection's subscription id (valid messages, and bad
payloads on the real subscription).  ``kind == "valid"`` frames carry their ``seq`` in ``FuzzFrame.seq``.
"""

from __future__ import annotations

import json
import random
import struct
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from . import wire

#: the channel the valid messages use (the test server advertises it with this id)
CHANNEL_ID = 7


@dataclass
class FuzzFrame:
    kind: str
    data: str | bytes | Callable[[int], bytes]
    seq: int | None = None


def _msg(sub: int, payload: bytes) -> bytes:
    return wire.message_frame(sub, 0, payload)


def _hostile(rng: random.Random) -> list[tuple[str, Any]]:
    big = rng.randint(1 << 31, (1 << 32) - 1)
    junk = bytes(rng.getrandbits(8) for _ in range(rng.randint(1, 64)))
    deep = "[" * 2000 + "]" * 2000
    return [
        ("random-bytes", junk),
        ("empty-binary", b""),
        ("short-message", bytes([1, 2, 3])),
        ("short-time", bytes([2, 1])),
        ("unknown-opcode", bytes([rng.randint(5, 255)]) + junk),
        ("short-response", bytes([3, 1, 0, 0])),
        ("response-long-encoding", struct.pack("<BIII", 3, 1, 1, big) + b"cdr"),
        ("response-unknown-call", wire.response_frame(9, rng.randint(1000, 9999), "json", b"{}")),
        ("message-unknown-sub", _msg(rng.randint(1000, 100000), b'{"seq": -1}')),
        ("message-bad-json", lambda sub: _msg(sub, b'{"seq": ')),
        ("message-json-array", lambda sub: _msg(sub, b"[1, 2, 3]")),
        ("message-invalid-utf8", lambda sub: _msg(sub, b'{"seq": "\xff\xfe"}')),
        ("message-deep", lambda sub: _msg(sub, deep.encode())),
        ("text-not-json", "{not json"),
        ("text-array", "[1, 2]"),
        ("text-no-op", '{"channels": []}'),
        ("text-op-number", '{"op": 5}'),
        ("unknown-op", json.dumps({"op": "explode" + str(rng.randint(0, 99))})),
        ("deep-json", deep),
        ("advertise-not-list", '{"op": "advertise", "channels": 5}'),
        ("advertise-bad-channel", json.dumps({"op": "advertise", "channels": [
            {"id": -1, "topic": "/x", "encoding": "json"}, {"id": "seven"}, 5, None,
            {"id": big * 4, "topic": 3, "encoding": "json", "schemaName": "", "schema": ""}]})),
        ("advertise-undecodable", json.dumps({"op": "advertise", "channels": [
            {"id": 900 + rng.randint(0, 99), "topic": "/weird", "encoding": "flatbuffer", "schemaName": "x",
             "schema": "!!", "schemaEncoding": "flatbuffer"}]})),
        ("unadvertise-unknown", json.dumps({"op": "unadvertise", "channelIds": [12345, "x", None]})),
        ("unadvertise-not-list", '{"op": "unadvertise", "channelIds": {"a": 1}}'),
        ("services-garbage", json.dumps({"op": "advertiseServices", "services": [5, {"id": "x"}, {
            "id": 3, "name": 4}, {"id": 4, "name": "/s", "type": "t", "request": {"schema": 5}}]})),
        ("unservices-garbage", json.dumps({"op": "unadvertiseServices", "serviceIds": "all"})),
        ("params-garbage", json.dumps({"op": "parameterValues", "parameters": [1, {"name": 3}, None], "id": 9})),
        ("params-not-list", '{"op": "parameterValues", "parameters": "x"}'),
        ("graph-garbage", json.dumps({"op": "connectionGraphUpdate", "publishedTopics": [{"name": 1},
                                      {"name": "/a", "publisherIds": "x"}, 7], "removedTopics": [3, None]})),
        ("graph-not-list", '{"op": "connectionGraphUpdate", "publishedTopics": 5}'),
        ("call-failure-unknown", json.dumps({"op": "serviceCallFailure", "serviceId": 1, "callId": "x",
                                             "message": 5})),
        ("status-weird", json.dumps({"op": "status", "level": "loud", "message": {"a": [1]}, "id": 5})),
        ("remove-status-garbage", '{"op": "removeStatus", "statusIds": 5}'),
        ("server-info-garbage", '{"op": "serverInfo", "name": 5, "capabilities": "all"}'),
        ("huge-text-string", json.dumps({"op": "status", "level": 0, "message": "x" * 200_000})),
    ]


def fuzz_frames(seed: int, count: int, valid_share: float = 0.3, invalid_utf8: int = 1) -> list[FuzzFrame]:
    """``count`` frames: about ``valid_share`` valid messages (``seq`` 0, 1, ...), the rest hostile, and
    ``invalid_utf8`` text frames that are not UTF-8 (each closes the connection: a WebSocket rule)."""
    rng = random.Random(seed)
    frames: list[FuzzFrame] = []
    seq = 0
    for _ in range(count):
        if rng.random() < valid_share:
            payload = json.dumps({"seq": seq}).encode()
            frames.append(FuzzFrame("valid", (lambda p: lambda sub: _msg(sub, p))(payload), seq))
            seq += 1
        else:
            kind, data = rng.choice(_hostile(rng))
            frames.append(FuzzFrame(kind, data))
    for _ in range(invalid_utf8):
        frames.insert(rng.randint(len(frames) // 4, len(frames) - 1), FuzzFrame("invalid-utf8", b"\xff\xfe{}"))
    return frames
