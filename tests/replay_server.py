"""A scripted rosbridge server for the bridge tests: real websockets, exact recorded frames.

It answers from the recorded frames of one real server: ``tests/recordings/rosbridge-ros1`` (rosbridge
0.11, the default) or ``tests/recordings/rosbridge-ros2-2.1.0`` (``ScriptedServer(recording=ROS2)``).
``call_service`` requests whose service and args match a recorded request get the recorded
``received_text`` (only the id is swapped for the caller's; a request the real server never answered gets
no answer here either), and a ``subscribe`` to a recorded topic gets that topic's recorded frames (text or
CBOR bytes) for the compression asked.  Tests can add their own service handlers, push any frame, drop the
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

ROS1 = "rosbridge-ros1"
ROS2 = "rosbridge-ros2-2.1.0"
RECORDINGS = Path(__file__).resolve().parent / "recordings" / ROS1


def load(name: str, recording: str = ROS1) -> list[dict[str, Any]]:
    """The lines of one recording (``tests/recordings/<recording>/NAME``), parsed."""
    path = RECORDINGS.parent / recording / name
    return [json.loads(line) for line in path.read_text(encoding="utf-8").splitlines() if line.strip()]


def received_frame(line: dict[str, Any]) -> str | bytes | None:
    if line.get("received_text") is not None:
        return line["received_text"]
    if line.get("received_b64"):
        return base64.b64decode(line["received_b64"])
    return None


def _key(service: str, args: Any) -> str:
    return service + "|" + json.dumps(args if args is not None else {}, sort_keys=True)


class Recorded:
    """Indexes of one set of recordings: service answers and per-topic publish frames per compression.

    ``answers[key]`` is ``(recorded id, received_text)``, or ``(recorded id, None)`` for a request the real
    server never answered (rosbridge 2.1.0's silences: a call that killed rosapi, a wedged connection)."""

    def __init__(self, recording: str = ROS1) -> None:
        self.answers: dict[str, tuple[str, str | None]] = {}
        for name in ("rosapi.jsonl", "services.jsonl", "malformed.jsonl", "client_publish.jsonl"):
            lines = load(name, recording)
            for i, line in enumerate(lines):
                sent = line.get("sent")
                if not (isinstance(sent, dict) and sent.get("op") == "call_service" and "id" in sent
                        and isinstance(sent.get("service"), str) and len(str(sent["id"])) < 100):
                    continue
                text = line.get("received_text")
                if text is None and recording != ROS1:  # the answer may follow on a later line of the script
                    text = next((r["received_text"] for r in lines[i + 1:]
                                 if (r.get("received") or {}).get("id") == sent["id"] and r.get("received_text")),
                                None)
                self.answers.setdefault(_key(sent["service"], sent.get("args")), (str(sent["id"]), text))
        #: ROS 2 goals: (action, action_type, args) -> the frames the real server sent for that goal (ids
        #: swapped for the caller's when replayed); a goal it never answered (a rejection) has []
        self.goals: dict[str, tuple[str, list[str]]] = {}
        if recording != ROS1:
            lines = load("actions.jsonl", recording)
            for line in lines:
                sent = line.get("sent")
                if isinstance(sent, dict) and sent.get("op") == "send_action_goal" and "action_type" in sent:
                    replies = [r["received_text"] for r in lines if (r.get("received") or {}).get("id") == sent["id"]
                               and (r.get("received") or {}).get("op", "").startswith("action_")]
                    key = json.dumps([sent["action"], sent["action_type"], sent.get("args")], sort_keys=True)
                    self.goals.setdefault(key, (sent["id"], replies))
        self.frames: dict[tuple[str, str], list[str | bytes]] = {}
        for name, comp in (("publish_json.jsonl", "none"), ("publish_cbor.jsonl", "cbor"),
                           ("publish_cbor_raw.jsonl", "cbor-raw"), ("publish_png.jsonl", "png")):
            topic = None
            for line in load(name, recording):
                sent = line.get("sent")
                if isinstance(sent, dict) and sent.get("op") == "subscribe":
                    topic = sent["topic"]
                    self.frames.setdefault((topic, comp), [])
                elif isinstance(sent, dict) and sent.get("op") == "unsubscribe":
                    topic = None
                frame = received_frame(line)
                own = (line.get("received") or line.get("received_decoded") or {}).get("topic")
                if frame is not None and (own, comp) in self.frames:  # a frame names its topic
                    self.frames[(own, comp)].append(frame)
                elif topic is not None and frame is not None:  # fragments and png frames do not
                    self.frames[(topic, comp)].append(frame)


_RECORDED: dict[str, Recorded] = {}


def recorded(recording: str = ROS1) -> Recorded:
    if recording not in _RECORDED:
        _RECORDED[recording] = Recorded(recording)
    return _RECORDED[recording]


ServiceFn = Callable[[dict[str, Any]], Any]


class ScriptedServer:
    """A rosbridge-like websockets server whose behaviour each test scripts."""

    def __init__(self, replay: bool = True, ssl: Any = None, recording: str = ROS1) -> None:
        self.replay = replay
        self.recording = recording
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
                hit = recorded(self.recording).answers.get(_key(name, frame.get("args")))
                if hit is not None and hit[1] is not None:
                    rec_id, text = hit
                    new_id = json.dumps(frame.get("id"))
                    text = text.replace(f'"id":"{rec_id}"', f'"id":{new_id}').replace(f'"id": "{rec_id}"',
                                                                                     f'"id": {new_id}')
                    await ws.send(text)
        elif op == "send_action_goal" and self.replay:
            key = json.dumps([frame.get("action"), frame.get("action_type"), frame.get("args")], sort_keys=True)
            hit = recorded(self.recording).goals.get(key)
            if hit is not None:
                rec_id, replies = hit
                for text in replies:
                    await ws.send(text.replace(f'"id": "{rec_id}"', f'"id": {json.dumps(frame.get("id"))}'))
        elif op == "subscribe":
            frames: list[str | bytes] = []
            if self.on_subscribe is not None:
                frames = self.on_subscribe(frame)
            elif self.replay:
                frames = recorded(self.recording).frames.get((frame["topic"], frame.get("compression", "none")),
                                                             [])
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
