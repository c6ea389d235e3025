"""Record real frames from a foxglove-sdk server (the test peer, ``rcon_core/foxglove/testing.py``) into
``tests/recordings/foxglove-sdk-0.30.3/session.jsonl``: one line per frame, ``{"dir": "in"|"out",
"text": ...}`` or ``{"dir": ..., "b64": ...}`` for binary frames, in the order they crossed the link.

Run from the repository root: ``python tools/record_foxglove.py``.  The recording is what the legacy
(``foxglove.websocket.v1``-only) replay server in the tests serves and what the frame tests parse.
"""

from __future__ import annotations

import asyncio
import base64
import json
import struct
from pathlib import Path

import websockets

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "tests" / "recordings" / "foxglove-sdk-0.30.3" / "session.jsonl"


async def main() -> None:
    from rcon_core.foxglove.testing import FoxPeer
    from rcon_core.msgs import TypeRegistry

    reg = TypeRegistry.standard(ros2=True)
    peer = FoxPeer()
    lines: list[dict] = []

    def log(direction: str, frame: str | bytes) -> None:
        if isinstance(frame, str):
            lines.append({"dir": direction, "text": frame})
        else:
            lines.append({"dir": direction, "b64": base64.b64encode(frame).decode()})

    async with websockets.connect(peer.url, subprotocols=["foxglove.sdk.v1"]) as ws:  # type: ignore[list-item]
        async def send(frame: str | bytes) -> None:
            log("out", frame)
            await ws.send(frame)

        async def drain(seconds: float = 0.4) -> None:
            try:
                while True:
                    log("in", await asyncio.wait_for(ws.recv(), seconds))
            except TimeoutError:
                pass

        await drain()
        channels = {}
        for line in lines:
            if "text" in line and json.loads(line["text"])["op"] == "advertise":
                channels = {c["topic"]: c["id"] for c in json.loads(line["text"])["channels"]}
        subs = [{"id": i + 1, "channelId": channels[t]} for i, t in enumerate(sorted(channels))]
        await send(json.dumps({"op": "subscribe", "subscriptions": subs}))
        await send(json.dumps({"op": "getParameters", "parameterNames": [], "id": "all"}))
        await send(json.dumps({"op": "subscribeConnectionGraph"}))
        await drain(0.3)
        peer.say("hello")
        peer.log_string("hello cdr")
        peer.log_pose(1.5)
        peer.log_image(b"\xff\xd8\xff\xe0 not really a jpeg")
        peer.log_fix(57.7, 11.97)
        peer.server.broadcast_time(1_700_000_000_000_000_000)
        await drain()
        await send(struct.pack("<BIII", 2, 1, 7, 3) + b"cdr" + reg.serialize_cdr("std_srvs/srv/Trigger_Request", {}))
        await drain()
        await send(json.dumps({"op": "bogus"}))
        await drain()
    peer.stop()
    OUT.write_text("".join(json.dumps(line) + "\n" for line in lines))
    print(f"{len(lines)} frames -> {OUT.relative_to(ROOT)}")


if __name__ == "__main__":
    asyncio.run(main())
