"""A server that speaks only the older subprotocol ``foxglove.websocket.v1``, serving the frames recorded from
the real foxglove-sdk server (``tests/recordings/foxglove-sdk-0.30.3/session.jsonl``) with the older shape
of ``advertiseServices`` (``requestSchema``/``responseSchema`` text; the encoding follows
``supportedEncodings``).  A client that subscribes gets the recorded message of that channel under its own
subscription id; a service call gets the recorded answer under its own call id."""

from __future__ import annotations

import base64
import json
import struct
from pathlib import Path
from typing import Any

import websockets

RECORDING = Path(__file__).parent / "recordings" / "foxglove-sdk-0.30.3" / "session.jsonl"


def recorded() -> list[dict[str, Any]]:
    return [json.loads(line) for line in RECORDING.read_text().splitlines()]


class LegacyServer:
    def __init__(self) -> None:
        frames = recorded()
        texts = [json.loads(f["text"]) for f in frames if f["dir"] == "in" and "text" in f]
        self.server_info = next(m for m in texts if m["op"] == "serverInfo")
        self.server_info["metadata"] = {}
        self.advertise = next(m for m in texts if m["op"] == "advertise")
        sdk_services = next(m for m in texts if m["op"] == "advertiseServices")
        reset = next(s for s in sdk_services["services"] if s["name"] == "/reset")
        self.services = {"op": "advertiseServices", "services": [
            {"id": reset["id"], "name": "/reset", "type": reset["type"],
             "requestSchema": reset["request"]["schema"] or "\n", "responseSchema": reset["response"]["schema"]}]}
        subscribe = next(json.loads(f["text"]) for f in frames if f["dir"] == "out" and "text" in f
                         and json.loads(f["text"])["op"] == "subscribe")
        channel_of = {s["id"]: s["channelId"] for s in subscribe["subscriptions"]}
        self.messages: dict[int, bytes] = {}  # channel id -> the recorded message payload (after the header)
        self.answer = b""
        for f in frames:
            if f["dir"] != "in" or "b64" not in f:
                continue
            data = base64.b64decode(f["b64"])
            if data[0] == 1:
                sub = struct.unpack_from("<I", data, 1)[0]
                self.messages[channel_of[sub]] = data[13:]
            elif data[0] == 3:
                elen = struct.unpack_from("<I", data, 9)[0]
                self.answer = data[13 + elen:]
        self.subprotocols_offered: list[list[str]] = []
        self.port = 0
        self._server: Any = None

    async def __aenter__(self) -> LegacyServer:
        self._server = await websockets.serve(self._serve, "127.0.0.1", 0,
                                              subprotocols=["foxglove.websocket.v1"])  # type: ignore[list-item]
        self.port = self._server.sockets[0].getsockname()[1]
        return self

    async def __aexit__(self, *exc: object) -> None:
        self._server.close()
        await self._server.wait_closed()

    @property
    def url(self) -> str:
        return f"ws://127.0.0.1:{self.port}"

    async def _serve(self, ws: Any) -> None:
        await ws.send(json.dumps(self.server_info))
        await ws.send(json.dumps(self.advertise))
        await ws.send(json.dumps(self.services))
        async for frame in ws:
            if isinstance(frame, str):
                m = json.loads(frame)
                if m.get("op") == "subscribe":
                    for s in m["subscriptions"]:
                        payload = self.messages.get(s["channelId"])
                        if payload is not None:
                            await ws.send(struct.pack("<BIQ", 1, s["id"], 1) + payload)
            elif frame[0] == 2:
                sid, cid, elen = struct.unpack_from("<III", frame, 1)
                enc = frame[13:13 + elen]
                await ws.send(struct.pack("<BIII", 3, sid, cid, len(enc)) + enc + self.answer)
