"""One WebSocket client of the sim: its subscriptions, its settings and its bounded send queue.

The queue never blocks the simulation: frames are appended without awaiting, a writer task drains them,
and when a client stops reading the oldest droppable frames (publishes) are thrown away.
"""

from __future__ import annotations

import asyncio
import collections
import logging
import time
from dataclasses import dataclass, field
from typing import Any

from websockets.asyncio.server import ServerConnection
from websockets.exceptions import ConnectionClosed

log = logging.getLogger(__name__)


@dataclass
class SubOptions:
    """The options of one subscription id."""

    throttle_rate: int = 0  # ms
    queue_length: int = 0
    compression: str = "none"


@dataclass
class TopicSubscription:
    """All subscription ids a connection holds on one topic (one frame per message, whatever the ids)."""

    topic: str
    type: str
    ids: dict[Any, SubOptions] = field(default_factory=dict)
    last_sent: float = float("-inf")
    compression: str = "none"

    @property
    def throttle_s(self) -> float:
        """The lowest throttle rate of all ids wins (rosbridge 0.11)."""
        return min((o.throttle_rate for o in self.ids.values()), default=0) / 1000.0

    @property
    def queue_length(self) -> int:
        lengths = [o.queue_length for o in self.ids.values() if o.queue_length > 0]
        return max(lengths) if lengths else 0


@dataclass
class _Frame:
    payload: str | bytes | list[str]  # a list: fragments of one message, sent back to back
    topic: str | None  # None: not droppable (replies, service requests)
    size: int


class Connection:
    """Server-side state of one client connection."""

    def __init__(self, ws: ServerConnection, client_id: int, *, max_frames: int = 200,
                 max_bytes: int = 24 * 1024 * 1024) -> None:
        self.ws = ws
        self.id = client_id
        self.connected_at = time.time()
        self.fragment_size: int | None = None
        self.incoming_fragments: dict[Any, dict[int, str]] = {}
        self.subscriptions: dict[str, TopicSubscription] = {}
        self.advertised: dict[str, str] = {}  # topic -> type
        #: every op this client sent, by (op, topic/service/action name): what tests check reached the sim
        self.ops_received: collections.Counter[tuple[str, str]] = collections.Counter()
        self.max_frames = max_frames
        self.max_bytes = max_bytes
        self.dropped = 0
        self.sent = 0
        self._queue: collections.deque[_Frame] = collections.deque()
        self._per_topic: collections.Counter[str] = collections.Counter()
        self._bytes = 0
        self._wakeup = asyncio.Event()
        self._closed = False
        self._writer: asyncio.Task[None] | None = None

    def __repr__(self) -> str:
        return f"<Connection {self.id}>"

    @property
    def label(self) -> str:
        return f"[Client {self.id}]"

    def start(self) -> None:
        self._writer = asyncio.get_running_loop().create_task(self._write_loop(), name=f"sim-writer-{self.id}")

    async def close(self) -> None:
        self._closed = True
        self._wakeup.set()
        if self._writer is not None:
            self._writer.cancel()
            try:
                await self._writer
            except (asyncio.CancelledError, Exception):  # noqa: BLE001 - shutting down
                pass

    # -- queue ---------------------------------------------------------------------------------------

    @property
    def queued(self) -> int:
        return len(self._queue)

    def send(self, payload: str | bytes | list[str], *, topic: str | None = None, queue_length: int = 0) -> None:
        """Queue a frame without blocking. ``topic`` marks a droppable publish frame."""
        if self._closed:
            return
        size = sum(len(p) for p in payload) if isinstance(payload, list) else len(payload)
        frame = _Frame(payload, topic, size)
        self._queue.append(frame)
        self._bytes += frame.size
        if topic is not None:
            self._per_topic[topic] += 1
            if queue_length > 0 and self._per_topic[topic] > queue_length:
                self._drop_oldest(topic)
        while len(self._queue) > 1 and (len(self._queue) > self.max_frames or self._bytes > self.max_bytes):
            if not self._drop_oldest(None):
                break
        self._wakeup.set()

    def _drop_oldest(self, topic: str | None) -> bool:
        """Drop the oldest publish frame (of ``topic`` if given). True when one was dropped."""
        for index, frame in enumerate(self._queue):
            if frame.topic is not None and (topic is None or frame.topic == topic):
                del self._queue[index]
                self._bytes -= frame.size
                self._per_topic[frame.topic] -= 1
                self.dropped += 1
                return True
        if topic is None and len(self._queue) > self.max_frames * 4:
            frame = self._queue.popleft()  # a client that never reads its replies: bound memory anyway
            self._bytes -= frame.size
            self.dropped += 1
            return True
        return False

    async def _write_loop(self) -> None:
        try:
            while not self._closed:
                if not self._queue:
                    self._wakeup.clear()
                    await self._wakeup.wait()
                    continue
                frame = self._queue.popleft()
                self._bytes -= frame.size
                if frame.topic is not None:
                    self._per_topic[frame.topic] -= 1
                if isinstance(frame.payload, list):
                    for part in frame.payload:
                        await self.ws.send(part)
                else:
                    await self.ws.send(frame.payload)
                self.sent += 1
        except ConnectionClosed:
            pass
        except asyncio.CancelledError:
            raise
        except Exception:  # noqa: BLE001 - a broken writer must not take the server down
            log.exception("%s writer failed", self.label)
