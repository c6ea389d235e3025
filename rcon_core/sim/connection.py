"""One WebSocket client of the sim: its subscriptions, its settings and its bounded, budgeted send queue.

The queue never blocks the simulation: frames are appended without awaiting and a writer task drains
them. What keeps one client from costing the others their latency:

* **Publishes are droppable, replies are not.** When a client stops reading, the oldest publishes in its
  queue are thrown away (per topic for ``queue_length``, and to stay under ``max_frames``/``max_bytes``).
  Replies (``service_response``, action results) and requests to a service the client provides are never
  dropped: the server stops *reading* a client with :data:`REPLY_BACKLOG` of them (or :data:`REPLY_BYTES`)
  queued (:meth:`Connection.room_for_replies`) until half of them are gone, so a client that sends calls
  and reads no answers is held back by TCP instead of being answered with silence (the old queue dropped
  them beyond 800 frames: of 10,000 calls sent at once, 5,700 to 7,000 got nothing).
* **Fragments are cut as they are sent**, never ahead: a message waits in the queue whole, and one
  dropped costs nothing. A message is cut in at most :data:`~rcon_core.sim.encoding.MAX_FRAGMENTS`
  fragments however small the client's ``fragment_size`` (``encoding.py``).
* **A send budget per connection**: at most :data:`SEND_RATE` WebSocket frames a second (a burst of
  :data:`SEND_BURST`); a greedy client (``fragment_size: 1`` on the camera) waits for its budget while its
  queue drops old publishes. The writer also gives the loop back every :data:`SLICE_S` seconds, so no one
  client's burst delays another's frame or the robot's timers.
* **A read budget per connection**: the server reads at most :data:`READ_RATE` frames a second from one
  client after a burst of :data:`READ_BURST` (a frame counts one, plus one per :data:`READ_BYTES_PER_TOKEN`
  bytes); beyond it the server waits before reading that client's next frame, so TCP holds a flooding
  client back (20,000 one-byte fragments, a stream of 32 MB frames) and no one client takes more than its
  share of the loop (:meth:`Connection.read_pause`).
* Log lines caused by one client are rate limited (:class:`LogLimiter`): a flood of bad frames costs a few
  lines a second, and a count of what was left out.
"""

from __future__ import annotations

import asyncio
import collections
import logging
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

from websockets.asyncio.server import ServerConnection
from websockets.exceptions import ConnectionClosed

from . import encoding
from .fragments import Reassembler

log = logging.getLogger(__name__)

#: WebSocket frames (each fragment counts) one connection is sent per second at most, and in one burst
SEND_RATE = 4000.0
SEND_BURST = 2.0 * encoding.MAX_FRAGMENTS
#: the writer gives the event loop back after this much time spent sending (seconds)
SLICE_S = 0.002
#: frames read from one client per second at most, after a burst (a 10,000-fragment message fits in it)
READ_RATE = 5000.0
READ_BURST = 20_000.0
#: a frame's size costs one more token per this many bytes (a 32 MB frame: 2049 tokens)
READ_BYTES_PER_TOKEN = 16 * 1024
#: queued replies (and requests to a service the client provides) at which the server stops reading it
REPLY_BACKLOG = 20_000
REPLY_BYTES = 16 * 1024 * 1024


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
    payload: str | bytes
    topic: str | None  # None: not droppable (replies, service requests)
    size: int
    fragment_size: int | None = None  # cut into fragments of this size as it is sent (text only)
    fragment_id: Any = 0  # their id: 0 for a publish, the request's id for a reply


class TokenBucket:
    """``rate`` tokens a second up to ``burst``; :meth:`debit` takes one and says how long to wait
    before the next may be used (0 while there are tokens)."""

    def __init__(self, rate: float, burst: float, clock: Callable[[], float] = time.monotonic) -> None:
        self.rate = rate
        self.burst = burst
        self.clock = clock
        self.tokens = burst
        self._at = clock()

    def debit(self, n: float = 1.0) -> float:
        now = self.clock()
        self.tokens = min(self.burst, self.tokens + (now - self._at) * self.rate)
        self._at = now
        self.tokens -= n
        return 0.0 if self.tokens >= 0 else -self.tokens / self.rate


class LogLimiter:
    """Log lines caused by one client: :data:`rate` a second after a burst of :data:`burst`; what is left
    out is counted and said in the next line that goes through."""

    rate = 5.0
    burst = 20.0

    def __init__(self, label: str, clock: Callable[[], float] = time.monotonic) -> None:
        self.label = label
        self._bucket = TokenBucket(self.rate, self.burst, clock)
        self.suppressed = 0

    def __call__(self, level: int, text: str, *args: Any, logger: logging.Logger | None = None) -> None:
        """Log ``text % args`` (prefixed with the client's label) unless this client is over its rate."""
        if self._bucket.debit() > 0:
            self._bucket.tokens += 1  # a line left out costs nothing
            self.suppressed += 1
            return
        if self.suppressed:
            text += f" ({self.suppressed} more lines about this client left out)"
            self.suppressed = 0
        (logger or log).log(level, "%s " + text, self.label, *args)


class Connection:
    """Server-side state of one client connection."""

    def __init__(self, ws: ServerConnection, client_id: int, *, max_frames: int = 200,
                 max_bytes: int = 24 * 1024 * 1024, max_frame: int = 32 * 1024 * 1024,
                 send_rate: float = SEND_RATE, send_burst: float = SEND_BURST) -> None:
        self.ws = ws
        self.id = client_id
        self.connected_at = time.time()
        self.fragment_size: int | None = None
        #: the fragmented messages this client is sending (fragments.py); at most ``max_frame`` bytes held
        self.fragments = Reassembler(max_frame)
        #: the size of the frame being handled, per message in it (what a published message weighs)
        self.frame_size = 0
        self.subscriptions: dict[str, TopicSubscription] = {}
        self.advertised: dict[str, str] = {}  # topic -> type
        #: every op this client sent, by (op, topic/service/action name): what tests check reached the sim
        self.ops_received: collections.Counter[tuple[str, str]] = collections.Counter()
        self.max_frames = max_frames
        self.max_bytes = max_bytes
        self.dropped = 0  # publishes thrown away (a client that does not keep up)
        self.sent = 0  # messages sent (a fragmented one counts once)
        self.frames_sent = 0  # WebSocket frames sent (each fragment counts)
        self.budget_waits = 0  # times the writer waited for its send budget
        self.calls_in_flight = 0  # call_service ops of this client not answered yet (services.py)
        self.log = LogLimiter(self.label)
        self._budget = TokenBucket(send_rate, send_burst)
        self._read_budget = TokenBucket(READ_RATE, READ_BURST)
        self.read_waits = 0  # times reading this client waited for its read budget
        self._queue: collections.deque[_Frame] = collections.deque()
        self._per_topic: collections.Counter[str] = collections.Counter()
        self._bytes = 0
        self._replies = 0  # frames in the queue that may not be dropped
        self._reply_bytes = 0
        self._room = asyncio.Event()
        self._room.set()
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
        self._room.set()
        if self._writer is not None:
            self._writer.cancel()
            try:
                await self._writer
            except (asyncio.CancelledError, Exception):  # noqa: BLE001 - shutting down
                pass
        self._queue.clear()
        self._bytes = self._replies = self._reply_bytes = 0

    # -- queue ---------------------------------------------------------------------------------------

    @property
    def queued(self) -> int:
        return len(self._queue)

    @property
    def replies_queued(self) -> int:
        """Frames in the queue that will not be dropped (replies, requests to the client's services)."""
        return self._replies

    def send(self, payload: str | bytes, *, topic: str | None = None, queue_length: int = 0,
             fragment_size: int | None = None, fragment_id: Any = 0) -> None:
        """Queue a frame without blocking. ``topic`` marks a droppable publish frame; ``fragment_size``
        has a text frame sent as rosbridge ``fragment`` ops (with ``fragment_id``) when it is longer."""
        if self._closed:
            return
        frame = _Frame(payload, topic, len(payload), fragment_size, fragment_id)
        self._queue.append(frame)
        self._bytes += frame.size
        if topic is None:
            self._replies += 1
            self._reply_bytes += frame.size
            if self._replies_full():
                self._room.clear()
        else:
            self._per_topic[topic] += 1
            if queue_length > 0 and self._per_topic[topic] > queue_length:
                self._drop_oldest(topic)
        while len(self._queue) > 1 and (len(self._queue) > self.max_frames or self._bytes > self.max_bytes):
            if not self._drop_oldest(None):
                break
        self._wakeup.set()

    def _replies_full(self) -> bool:
        return self._replies >= REPLY_BACKLOG or self._reply_bytes >= REPLY_BYTES

    async def read_pause(self, size: int) -> None:
        """After a frame of ``size`` bytes was handled: give the loop to the others, and wait as long as this
        client is over its read budget."""
        wait = self._read_budget.debit(1.0 + size / READ_BYTES_PER_TOKEN)
        if wait > 0:
            self.read_waits += 1
        await asyncio.sleep(wait)

    async def room_for_replies(self) -> None:
        """Return once the replies in the queue are under :data:`REPLY_BACKLOG` and :data:`REPLY_BYTES`
        (at once if so; after a wait, once half of them are gone)."""
        while not self._closed and self._replies_full():
            self._room.clear()
            await self._room.wait()

    def _drop_oldest(self, topic: str | None) -> bool:
        """Drop the oldest publish frame (of ``topic`` if given). True when one was dropped."""
        for index, frame in enumerate(self._queue):
            if frame.topic is not None and (topic is None or frame.topic == topic):
                del self._queue[index]
                self._bytes -= frame.size
                self._per_topic[frame.topic] -= 1
                self.dropped += 1
                return True
        return False

    def _take(self) -> _Frame:
        frame = self._queue.popleft()
        self._bytes -= frame.size
        if frame.topic is not None:
            self._per_topic[frame.topic] -= 1
        else:
            self._replies -= 1
            self._reply_bytes -= frame.size
            if self._replies < REPLY_BACKLOG // 2 and self._reply_bytes < REPLY_BYTES // 2:
                self._room.set()
        return frame

    @staticmethod
    def _parts(frame: _Frame) -> Iterator[str | bytes]:
        payload, size = frame.payload, frame.fragment_size
        if size and isinstance(payload, str) and len(payload) > size:
            yield from encoding.iter_fragments(payload, size, frame.fragment_id)
        else:
            yield payload

    async def _write_loop(self) -> None:
        slice_start = time.perf_counter()
        try:
            while not self._closed:
                if not self._queue:
                    self._wakeup.clear()
                    await self._wakeup.wait()
                    slice_start = time.perf_counter()
                    continue
                for part in self._parts(self._take()):  # a fragmented message goes out whole, in order
                    wait = self._budget.debit()
                    if wait > 0:
                        self.budget_waits += 1
                        await asyncio.sleep(wait)
                        slice_start = time.perf_counter()
                    await self.ws.send(part)
                    self.frames_sent += 1
                    if time.perf_counter() - slice_start > SLICE_S:
                        await asyncio.sleep(0)  # let the others (and the robot's timers) have the loop
                        slice_start = time.perf_counter()
                self.sent += 1
        except ConnectionClosed:
            pass
        except asyncio.CancelledError:
            raise
        except Exception as exc:  # noqa: BLE001 - a broken writer must not take the server down
            log.error("%s writer failed, closing the connection: %s", self.label, encoding.bounded(repr(exc)))
            self._closed = True
            self._room.set()
            try:
                await self.ws.close(1011, "internal error while sending")
            except Exception:  # noqa: BLE001 - already going
                pass
        finally:
            self._room.set()
