"""A scripted rosbridge server for the bridge tests: real websockets, exact recorded frames.

It answers from the recorded frames in ``tests/recordings/rosbridge-ros1``: ``call_service`` requests whose
service and args match a recorded request get the recorded ``received_text`` (only the id is swapped for
the caller's), and a ``subscribe`` to a recorded topic gets that topic's recorded frames (text or CBOR
bytes) for the compression asked.  Tests can add their own service handlers, push any frame, drop the
connection, and inspect everything the client sent.
"""

from __future__ import annotations

import asyncio
import base64
import json
import threading
from collections.abc import Callable
from pathlib import Path
from typing import Any

import orjson
from websockets.asyncio.server import ServerConnection, serve

RECORDINGS = Path(__file__).resolve().parent / "recordings" / "rosbridge-ros1"


def load(name: str) -> list[dict[str, Any]]:
    """The lines of one recording (``tests/recordings/rosbridge-ros1/NAME``), parsed."""
    return [json.loads(line) for line in (RECORDINGS / name).read_text(encoding="utf-8").splitlines() if line.strip()]


def received_frame(line: dict[str, Any]) -> str | bytes | None:
    if line.get("received_text") is not None:
        return line["received_text"]
    if line.get("received_b64"):
        return base64.b64decode(line["received_b64"])
    return None


def _key(service: str, args: Any) -> str:
    return service + "|" + json.dumps(args if args is not None else {}, sort_keys=True)


class Recorded:
    """Indexes of the recordings: service answers and per-topic publish frames per compression."""

    def __init__(self) -> None:
        self.answers: dict[str, tuple[str, str]] = {}  # key -> (recorded id, received_text)
        for name in ("rosapi.jsonl", "services.jsonl", "malformed.jsonl", "client_publish.jsonl"):
            for line in load(name):
                sent = line.get("sent")
                text = line.get("received_text")
                if isinstance(sent, dict) and sent.get("op") == "call_service" and text and "id" in sent \
                        and isinstance(sent.get("service"), str) and len(str(sent["id"])) < 100:
                    self.answers.setdefault(_key(sent["service"], sent.get("args")), (str(sent["id"]), text))
        self.frames: dict[tuple[str, str], list[str | bytes]] = {}
        for name, comp in (("publish_json.jsonl", "none"), ("publish_cbor.jsonl", "cbor"),
                           ("publish_cbor_raw.jsonl", "cbor-raw"), ("publish_png.jsonl", "png")):
            topic = None
            for line in load(name):
                sent = line.get("sent")
                if isinstance(sent, dict) and sent.get("op") == "subscribe":
                    topic = sent["topic"]
                    self.frames.setdefault((topic, comp), [])
                elif isinstance(sent, dict) and sent.get("op") == "unsubscribe":
                    topic = None
                frame = received_frame(line)
                if topic is not None and frame is not None:
                    self.frames[(topic, comp)].append(frame)


_RECORDED: Recorded | None = None


def recorded() -> Recorded:
    global _RECORDED
    if _RECORDED is None:
        _RECORDED = Recorded()
    return _RECORDED


ServiceFn = Callable[[dict[str, Any]], Any]


class ScriptedServer:
    """A rosbridge-like websockets server whose behaviour each test scripts."""

    def __init__(self, replay: bool = True, ssl: Any = None) -> None:
        self.replay = replay
        self.ssl = ssl
        self.received: list[Any] = []  # every frame the client sent, parsed
        self.connections: list[ServerConnection] = []
        self.services: dict[str, ServiceFn] = {}  # name -> fn(frame) -> reply text/dict or None (no reply)
        self.on_subscribe: Callable[[dict[str, Any]], list[str | bytes]] | None = None
        self.connects = 0
        self._server: Any = None
        self._changed = asyncio.Event()
        self.port = 0

    @property
    def url(self) -> str:
        return f"{'wss' if self.ssl else 'ws'}://127.0.0.1:{self.port}"

    async def start(self) -> ScriptedServer:
        self._changed = asyncio.Event()
        self._server = await serve(self._handle, "127.0.0.1", self.port, ssl=self.ssl, compression=None,
                                   max_size=None)
        self.port = self._server.sockets[0].getsockname()[1]
        return self

    async def stop(self) -> None:
        if self._server is not None:
            self._server.close()
            await self._server.wait_closed()
            self._server = None

    async def __aenter__(self) -> ScriptedServer:
        return await self.start()

    async def __aexit__(self, *exc: object) -> None:
        await self.stop()

    # ---------------------------------------------------------------- inspection

    def ops(self, op: str, **match: Any) -> list[dict[str, Any]]:
        return [f for f in self.received if isinstance(f, dict) and f.get("op") == op
                and all(f.get(k) == v for k, v in match.items())]

    async def wait_for(self, op: str, count: int = 1, timeout: float = 5.0, **match: Any) -> list[dict[str, Any]]:
        async def poll() -> list[dict[str, Any]]:
            while len(self.ops(op, **match)) < count:
                self._changed.clear()
                await self._changed.wait()
            return self.ops(op, **match)

        return await asyncio.wait_for(poll(), timeout)

    async def wait_connections(self, n: int, timeout: float = 5.0) -> None:
        async def poll() -> None:
            while self.connects < n:
                self._changed.clear()
                await self._changed.wait()

        await asyncio.wait_for(poll(), timeout)

    # ---------------------------------------------------------------- acting

    async def send(self, frame: str | bytes | dict[str, Any]) -> None:
        if isinstance(frame, dict):
            frame = orjson.dumps(frame).decode()
        for ws in list(self.connections):
            await ws.send(frame)

    async def drop(self, abort: bool = False) -> None:
        """Close every client connection (abort: without a close handshake)."""
        for ws in list(self.connections):
            if abort:
                ws.transport.abort()
            else:
                await ws.close()

    # ---------------------------------------------------------------- serving

    async def _handle(self, ws: ServerConnection) -> None:
        self.connections.append(ws)
        self.connects += 1
        self._changed.set()
        try:
            async for raw in ws:
                try:
                    frame = json.loads(raw)
                except ValueError:
                    frame = raw
                self.received.append(frame)
                self._changed.set()
                if isinstance(frame, dict):
                    await self._react(ws, frame)
        except Exception:  # a dropped client is normal here
            pass
        finally:
            self.connections.remove(ws)

    async def _react(self, ws: ServerConnection, frame: dict[str, Any]) -> None:
        op = frame.get("op")
        if op == "call_service":
            name = frame.get("service")
            fn = self.services.get(name)
            if fn is not None:
                reply = fn(frame)
                if asyncio.iscoroutine(reply):
                    reply = await reply
                if reply is not None:
                    await ws.send(reply if isinstance(reply, str) else orjson.dumps(reply).decode())
                return
            if self.replay:
                hit = recorded().answers.get(_key(name, frame.get("args")))
                if hit is not None:
                    rec_id, text = hit
                    text = text.replace(f'"id":"{rec_id}"', f'"id":{json.dumps(frame.get("id"))}')
                    await ws.send(text)
        elif op == "subscribe":
            frames: list[str | bytes] = []
            if self.on_subscribe is not None:
                frames = self.on_subscribe(frame)
            elif self.replay:
                frames = recorded().frames.get((frame["topic"], frame.get("compression", "none")), [])
            for f in frames:
                await ws.send(f)


class ThreadedServer:
    """A ScriptedServer on its own loop in a thread, for code that runs ``asyncio.run`` itself (the CLI)."""

    def __init__(self, **kwargs: Any) -> None:
        self.server = ScriptedServer(**kwargs)
        self.loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self.loop.run_forever, daemon=True)

    def __enter__(self) -> ScriptedServer:
        self._thread.start()
        asyncio.run_coroutine_threadsafe(self.server.start(), self.loop).result(5)
        return self.server

    def __exit__(self, *exc: object) -> None:
        asyncio.run_coroutine_threadsafe(self.server.stop(), self.loop).result(5)
        self.loop.call_soon_threadsafe(self.loop.stop)
        self._thread.join(5)
