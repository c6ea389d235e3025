"""What clients published, kept for tests and tools (``SimServer.published``), bounded by count and bytes.

The sim used to keep the last 500 messages of every topic whatever their size: 500 camera frames a topic
took its RSS from 72 to 872 MB. Now each topic keeps at most :data:`KEEP` messages and
:data:`TOPIC_BYTES` bytes, and all topics together :data:`TOTAL_BYTES` bytes and :data:`TOTAL_MESSAGES`
messages; the oldest go first. The newest message of a topic is kept whatever its size unless newer
messages of other topics fill the total (a test waiting for a 30 MB image finds it). A message's size is the size of the
frame it came in (what the client sent), a fair measure of what its decoded form costs.

Thread-safe: tests read it from other threads (``SimServer.in_thread``).
"""

from __future__ import annotations

import collections
import threading
from dataclasses import dataclass
from typing import Any

__all__ = ["PublishedLog", "KEEP", "TOPIC_BYTES", "TOTAL_BYTES", "TOTAL_MESSAGES"]

KEEP = 500
TOPIC_BYTES = 16 * 1024 * 1024
TOTAL_BYTES = 64 * 1024 * 1024
TOTAL_MESSAGES = 20_000


@dataclass
class _Entry:
    topic: str
    msg: dict[str, Any]
    size: int
    gone: bool = False


class PublishedLog:
    """The messages clients published, per topic, oldest first."""

    def __init__(self, keep: int = KEEP, topic_bytes: int = TOPIC_BYTES, total_bytes: int = TOTAL_BYTES,
                 total_messages: int = TOTAL_MESSAGES) -> None:
        self.keep, self.topic_bytes = keep, topic_bytes
        self.total_bytes, self.total_messages = total_bytes, total_messages
        self._lock = threading.Lock()
        self._topics: dict[str, collections.deque[_Entry]] = {}
        self._topic_bytes: collections.Counter[str] = collections.Counter()
        self._order: collections.deque[_Entry] = collections.deque()  # every entry, oldest first
        self._count = 0
        self.bytes = 0

    def add(self, topic: str, msg: dict[str, Any], size: int) -> None:
        entry = _Entry(topic, msg, max(1, size))
        with self._lock:
            entries = self._topics.setdefault(topic, collections.deque())
            entries.append(entry)
            self._order.append(entry)
            self._count += 1
            self._topic_bytes[topic] += entry.size
            self.bytes += entry.size
            while len(entries) > 1 and (len(entries) > self.keep or self._topic_bytes[topic] > self.topic_bytes):
                self._forget(entries.popleft())
            while self._count > 1 and (self.bytes > self.total_bytes or self._count > self.total_messages):
                oldest = self._order.popleft()
                if oldest.gone:
                    continue
                own = self._topics[oldest.topic]
                own.popleft()  # the oldest of all is the oldest of its topic
                self._forget(oldest)
            while self._order and self._order[0].gone:
                self._order.popleft()
            if len(self._order) > 2 * self._count + 1000:  # entries a topic dropped itself, mid-queue
                self._order = collections.deque(e for e in self._order if not e.gone)

    def messages(self, topic: str) -> list[dict[str, Any]]:
        with self._lock:
            return [e.msg for e in self._topics.get(topic, ())]

    def __len__(self) -> int:
        return self._count

    def _forget(self, entry: _Entry) -> None:
        entry.gone = True
        self._count -= 1
        self.bytes -= entry.size
        self._topic_bytes[entry.topic] -= entry.size
        if not self._topics[entry.topic]:
            del self._topics[entry.topic]
            del self._topic_bytes[entry.topic]
