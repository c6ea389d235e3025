"""Seeded hostile rosbridge frames, for the fuzz test and the soak benchmark (no Qt).

:func:`fuzz_frames` yields :class:`FuzzFrame` items: valid publishes on ``topic`` (``msg`` is
``{"seq": n}``, sent as JSON, CBOR, a ``png`` frame or rosbridge fragments) mixed with hostile frames:
invalid UTF-8, bad JSON, JSON nested deeper than the parser or the formatter can take, wrong field types,
bogus fragments, bad png and CBOR data, PNG bombs, unknown ops, non-object ``msg`` on the subscribed
topic and byte-flipped copies of valid frames on another topic.  A frame with ``fatal`` set is one the
WebSocket layer itself must refuse (invalid UTF-8 in a text frame): the connection closes and the client
reconnects.  The same seed gives the same frames.

:class:`FuzzRun` plays a script through a :class:`~rcon_core.loopback.HostileServer`: on every
subscription to ``topic`` it sends the next frames, until a fatal one (then the next connection goes on).
"""

from __future__ import annotations

import asyncio
import base64
import json
import random
from collections.abc import Iterator
from typing import Any

import attrs
import cbor2
import orjson

from .loopback import HostileServer, png_data
from .sim.encoding import fragments, png_frame


@attrs.frozen
class FuzzFrame:
    payload: str | bytes
    text: bool
    valid: int | None = None  # the seq of a valid publish on the topic
    fatal: bool = False
    kind: str = ""


def _deep(rng: random.Random) -> str:
    depth = rng.choice((900, 1000, 1023, 1030, 5000))
    opener, closer = rng.choice((("[", "]"), ('{"a":', "}")))
    inner = opener * depth + "1" + closer * depth
    deep_list = "[" * depth + "1" + "]" * depth  # a non-object msg: an object nested deep would be a valid message
    return rng.choice(('{"op":"publish","topic":"/fuzz","msg":' + deep_list + "}", '{"x":' + inner + "}",
                       '{"op":' + inner + "}", '{"op":"status","level":' + inner + ',"id":' + inner + "}",
                       '{"op":"service_response","id":' + inner + ',"values":' + inner + ',"result":false}',
                       inner))


class _Hostile:
    """Makers of hostile frames (each returns a FuzzFrame)."""

    def __init__(self, rng: random.Random, topic: str, bomb_pixels: int) -> None:
        self.rng, self.topic = rng, topic
        side = max(1, int((bomb_pixels / 3) ** 0.5) + 1)
        self.bomb = orjson.dumps({"op": "png", "data": png_data(
            orjson.dumps({"op": "publish", "topic": topic, "msg": {"bomb": 1}}), side, side)}).decode()
        self.makers = [getattr(self, n) for n in dir(self) if n.startswith("k_")]

    def make(self) -> FuzzFrame:
        return self.rng.choice(self.makers)()

    def _t(self, op: Any, kind: str) -> FuzzFrame:
        return FuzzFrame(json.dumps(op) if not isinstance(op, str) else op, True, kind=kind)  # big ints, NaN

    def _junk(self) -> Any:
        r = self.rng
        return r.choice([None, True, 0, -1, 2 ** 70, 1.5e308, "", "x" * r.randint(1, 300), [], [1, [2]], {},
                         {"a": {"b": []}}, [[[]]], "\u0000\ud7ff", -0.0])

    def k_invalid_utf8(self) -> FuzzFrame:
        if self.rng.random() < 0.04:  # rare: each one costs a reconnect
            return FuzzFrame(b'{"op":"publish","topic":"' + self.topic.encode() + b'","msg":{"s":"\xff\xfe"}}',
                             True, fatal=True, kind="invalid-utf8")
        return self.k_bad_json()

    def k_bad_json(self) -> FuzzFrame:
        r = self.rng
        text = r.choice(['{"op":"publish"', "{", "}", "nul", "[1,]", '{"op":"publish",}', "NaN", '"\\ud800"',
                         "".join(chr(r.randint(32, 0x2FF)) for _ in range(r.randint(0, 60))), " ", "\u2028"])
        return self._t(text, "bad-json")

    def k_deep(self) -> FuzzFrame:
        return self._t(_deep(self.rng), "deep-json")

    def k_wrong_types(self) -> FuzzFrame:
        r, j = self.rng, self._junk
        op = r.choice([
            {"op": "publish", "topic": j(), "msg": {"seq": -1}},
            {"op": j(), "topic": self.topic, "msg": {"seq": -1}},
            {"op": "publish", "topic": self.topic},
            {"op": "publish"},
            {"op": "service_response", "id": j(), "values": j(), "result": j()},
            {"op": "status", "level": j(), "msg": j(), "id": j()},
            {"op": "call_service", "service": j(), "id": j(), "args": j()},
            {"op": "action_result", "id": j(), "values": j(), "status": j(), "result": j()},
            {"op": "action_feedback", "id": j(), "values": j()},
            {"op": "png", "data": j(), "num": j(), "total": j()},
            {"op": "fragment", "id": j(), "data": j(), "num": j(), "total": j()},
        ])
        return self._t(op, "wrong-types")

    def k_non_object_msg(self) -> FuzzFrame:
        msg = self.rng.choice([None, 1, "text", [1, 2], True, 1.5, [{"seq": 1}]])
        if self.rng.random() < 0.5:
            return FuzzFrame(cbor2.dumps({"op": "publish", "topic": self.topic, "msg": msg}), False,
                             kind="non-object-msg")
        return self._t({"op": "publish", "topic": self.topic, "msg": msg}, "non-object-msg")

    def k_fragments(self) -> FuzzFrame:
        r = self.rng
        fid = r.choice([0, "f", 1.5, None])
        op = r.choice([
            {"op": "fragment", "id": fid, "data": "{\"op\":", "num": r.randint(1, 5), "total": 6},
            {"op": "fragment", "id": fid, "data": "x", "num": 0, "total": r.choice([0, -1, 1e12, "6", None, 2.5])},
            {"op": "fragment", "id": fid, "data": "garbage", "num": 0, "total": 1},
            {"op": "fragment", "id": fid, "data": '{"op":"publish","topic":"' + self.topic + '","msg":5}', "num": 0,
             "total": 1},
            {"op": "fragment", "id": [fid], "data": "x", "num": 0, "total": 2},
            {"op": "fragment", "id": fid, "data": _deep(r), "num": 0, "total": 1},
        ])
        return self._t(op, "fragment")

    def k_bad_png(self) -> FuzzFrame:
        r = self.rng
        data = r.choice(["", "#", "====", "iVBORw0KGgo=", base64.b64encode(r.randbytes(r.randint(1, 200))).decode(),
                         base64.b64encode(b"\x89PNG\r\n\x1a\n" + r.randbytes(40)).decode()])
        if r.random() < 0.15:
            return FuzzFrame(self.bomb, True, kind="png-bomb")
        if r.random() < 0.2:
            return FuzzFrame(png_frame(r.choice(["not json", _deep(r), '{"op":"publish","topic":"'
                                                 + self.topic + '","msg":[]}'])), True, kind="png-inner")
        return self._t({"op": "png", "data": data}, "bad-png")

    def k_bad_cbor(self) -> FuzzFrame:
        r = self.rng
        good = cbor2.dumps({"op": "publish", "topic": "/decoy", "msg": {"a": [1.5, 2]}})
        blob = r.choice([r.randbytes(r.randint(1, 100)), good[:r.randint(1, len(good) - 1)], b"\xff", b"\x00",
                         cbor2.dumps(cbor2.CBORTag(80, "not bytes")), cbor2.dumps([1, 2, 3]),
                         cbor2.dumps({"op": "publish", "topic": self.topic, "msg": cbor2.CBORTag(85, b"\x00")}),
                         b"{" + r.randbytes(20)])
        return FuzzFrame(blob, False, kind="bad-cbor")

    def k_unknown_op(self) -> FuzzFrame:
        return self._t({"op": self.rng.choice(["nope", "", "PUBLISH", "subscribe", "publish ", "x" * 500]),
                        "topic": self.topic, "msg": {"seq": -1}}, "unknown-op")

    def k_flipped(self) -> FuzzFrame:
        r = self.rng
        good = bytearray(orjson.dumps({"op": "publish", "topic": "/decoy", "msg": {"seq": r.randint(0, 9)}}))
        for _ in range(r.randint(1, 3)):
            good[r.randrange(len(good))] = r.randint(0, 255)
        try:
            return FuzzFrame(good.decode("utf-8"), True, kind="flipped")
        except UnicodeDecodeError:
            return FuzzFrame(bytes(good), False, kind="flipped")


def fuzz_frames(seed: int, count: int, topic: str = "/fuzz", valid_share: float = 0.3,
                bomb_pixels: int = 5 << 20) -> Iterator[FuzzFrame]:
    """``count`` frames (a few more when the last valid message is cut into fragments), about
    ``valid_share`` of the draws valid publishes on ``topic``; deterministic per seed.  PNG bombs declare
    about ``bomb_pixels`` bytes of pixels (more than the client accepts)."""
    rng = random.Random(seed)
    hostile = _Hostile(rng, topic, bomb_pixels)
    seq = sent = 0
    while sent < count:
        sent += 1
        if rng.random() >= valid_share:
            yield hostile.make()
            continue
        seq += 1
        frame = {"op": "publish", "topic": topic, "msg": {"seq": seq}}
        text = orjson.dumps(frame).decode()
        how = rng.random()
        if how < 0.6:
            yield FuzzFrame(text, True, valid=seq, kind="valid-json")
        elif how < 0.8:
            yield FuzzFrame(cbor2.dumps(frame), False, valid=seq, kind="valid-cbor")
        elif how < 0.9:
            yield FuzzFrame(png_frame(text), True, valid=seq, kind="valid-png")
        else:
            parts = fragments(text, rng.randint(5, 20))
            sent += len(parts) - 1
            for part in parts[:-1]:
                yield FuzzFrame(part, True, kind="valid-fragment")
            yield FuzzFrame(parts[-1], True, valid=seq, kind="valid-fragment")


class FuzzRun:
    """Plays ``frames`` to a client through ``server``, resuming on the next connection after a fatal one."""

    def __init__(self, server: HostileServer, frames: Iterator[FuzzFrame], topic: str = "/fuzz") -> None:
        self.server, self.topic = server, topic
        self.frames = frames
        self.expected: list[int] = []  # seq of every valid publish sent
        self.sent = 0
        self.fatal = 0
        self.done = asyncio.Event()
        server.on_subscribe = self._on_subscribe

    def _on_subscribe(self, op: dict[str, Any]) -> Iterator[tuple[str | bytes, bool]]:
        if op.get("topic") != self.topic:
            return
        for frame in self.frames:
            self.sent += 1
            if frame.valid is not None:
                self.expected.append(frame.valid)
            yield frame.payload, frame.text
            if frame.fatal:
                self.fatal += 1
                return
        self.done.set()
