"""A second opinion on what a Foxglove server sends: a bare client (``websockets``, no RCON code) that
subscribes to topics and keeps every MessageData payload as it came off the wire, per topic and in order.
The flight recorder's tests compare the recorded bytes with these."""

from __future__ import annotations

import asyncio
import json
import struct
from typing import Any

from websockets.asyncio.client import connect


class RawFoxClient:
    """``async with RawFoxClient(url, topics) as raw``: ``raw.payloads[topic]`` fills as messages come."""

    def __init__(self, url: str, topics: list[str]) -> None:
        self.url = url
        self.topics = list(topics)
        self.payloads: dict[str, list[bytes]] = {t: [] for t in topics}
        self.channels: dict[str, dict[str, Any]] = {}  # topic -> its advertisement
        self.subscribed: set[str] = set()
        self._of_sub: dict[int, str] = {}
        self._task: asyncio.Task[None] | None = None

    async def __aenter__(self) -> RawFoxClient:
        self._ws = await connect(self.url, subprotocols=["foxglove.sdk.v1", "foxglove.websocket.v1"],  # type: ignore[list-item]
                                 max_size=None, compression=None)
        self._task = asyncio.create_task(self._read())
        return self

    async def __aexit__(self, *exc: object) -> None:
        if self._task is not None:
            self._task.cancel()
        await self._ws.close()

    async def _read(self) -> None:
        async for frame in self._ws:
            if isinstance(frame, str):
                m = json.loads(frame)
                if m["op"] == "advertise":
                    subs = []
                    for ch in m["channels"]:
                        if ch["topic"] in self.topics and ch["topic"] not in self.channels:
                            self.channels[ch["topic"]] = ch
                            sid = len(self._of_sub) + 1
                            self._of_sub[sid] = ch["topic"]
                            subs.append({"id": sid, "channelId": ch["id"]})
                    if subs:
                        await self._ws.send(json.dumps({"op": "subscribe", "subscriptions": subs}))
                        self.subscribed.update(self._of_sub[s["id"]] for s in subs)
            elif frame[0] == 1:
                sid = struct.unpack_from("<I", frame, 1)[0]
                self.payloads[self._of_sub[sid]].append(bytes(frame[13:]))


def run_of(part: list[bytes], whole: list[bytes]) -> bool:
    """``part`` is a contiguous run of ``whole`` (a recorder that started or stopped at another moment)."""
    if not part:
        return False
    n = len(part)
    return any(whole[i:i + n] == part for i in range(len(whole) - n + 1))
