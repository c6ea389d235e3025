"""One camera frame, drawn once, reaches clients subscribed with different compressions with the same pixels;
the pixels' base64 text (for JSON subscribers) is made in the drawing thread, only when someone needs it."""

from __future__ import annotations

import asyncio
import base64
import json
from collections.abc import Callable
from typing import Any

import websockets

from rcon_core.bridge.protocol import decode_cbor, decode_png
from rcon_core.sim import SimServer
from rcon_core.sim.encoding import Base64Bytes

TOPICS = ("/camera/front/image_raw", "/camera/rear/image_raw/compressed")


def pixels(frame: str | bytes) -> tuple[str, int, bytes] | None:
    """(topic, header stamp in ns, data bytes) of a publish frame in any of the compressions."""
    if isinstance(frame, bytes):
        msg = decode_cbor(frame)
    else:
        msg = json.loads(frame)
        if msg.get("op") == "png":
            msg = decode_png(msg["data"])
    if msg.get("op") != "publish":
        return None
    body: dict[str, Any] = msg["msg"]
    stamp = body["header"]["stamp"]
    data = body["data"]
    return msg["topic"], stamp["secs"] * 10**9 + stamp["nsecs"], base64.b64decode(data) if isinstance(data, str) else data


async def frames_of(url: str, compression: str, out: dict[tuple[str, int], bytes],
                    done: Callable[[], bool]) -> None:
    async with websockets.connect(url, max_size=None) as ws:
        for topic in TOPICS:
            await ws.send(json.dumps({"op": "subscribe", "topic": topic, "compression": compression}))
        while not done():
            got = pixels(await ws.recv())
            if got is not None:
                out[got[:2]] = got[2]


def common(received: dict[str, dict[tuple[str, int], bytes]]) -> set[tuple[str, int]]:
    return set.intersection(*(set(r) for r in received.values()))


async def test_a_frame_reaches_every_compression_with_the_same_pixels() -> None:
    async with SimServer(rate_scale=2.0) as sim:
        made: list[Any] = []  # the camera messages as published, to see what the drawing thread made
        for topic in TOPICS:
            sim.subscribe_internal(topic, "", "/test", lambda msg: made.append(msg["data"]))
        received: dict[str, dict[tuple[str, int], bytes]] = {c: {} for c in ("none", "png", "cbor", "cbor2")}

        def done() -> bool:  # a frame of each camera reached all four clients
            return {topic for topic, _ in common(received)} == set(TOPICS)

        await asyncio.wait_for(asyncio.gather(*(frames_of(sim.url, c.rstrip("2"), received[c], done)
                                                for c in received)), 30)
        for key in common(received):
            first = received["cbor"][key]
            assert len(first) > 10_000 and all(r[key] == first for r in received.values()), key
        # JSON subscribers were there, so frames came with their base64 text made off the loop
        assert any(isinstance(data, Base64Bytes) for data in made)
        assert all(data.base64 == base64.b64encode(data).decode() for data in made if isinstance(data, Base64Bytes))


async def test_no_base64_is_made_for_cbor_subscribers_only() -> None:
    async with SimServer(rate_scale=2.0) as sim:
        made: list[Any] = []
        for topic in TOPICS:
            sim.subscribe_internal(topic, "", "/test", lambda msg: made.append(msg["data"]))
        received: dict[tuple[str, int], bytes] = {}
        await asyncio.wait_for(frames_of(sim.url, "cbor", received, lambda: len(received) >= 6), 30)
        assert made and not any(isinstance(data, Base64Bytes) for data in made)
