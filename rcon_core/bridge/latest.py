"""Latest-only topics: stale frames of a topic are skipped, before decoding, when a newer one already waits.

Decision: where a camera backlog builds and how the client ends it
    A subscription with ``queue_length: 1`` asks the server to keep only the newest message of a topic
    (rosbridge and the sim drop the oldest).  Frames the server has already written still wait downstream:
    in the kernel's socket buffers and in the ``websockets`` receive queue (up to 16 frames: 15 MB of rgb8
    at 640x480).  When the client's loop is slower than the stream (a busy CPU), every one of them would be
    decoded and delivered in turn and the latency of what is shown would grow.

    So for a topic whose every consumer asked for ``queue_length: 1`` (:meth:`TopicEntry.wanted`), the read
    loop skips a frame of at least ``min_size`` bytes when a later complete frame of the *same* topic is
    already in the receive queue (:meth:`~rcon_core.bridge.wslink.Link.waiting`).  A backlog mostly sits in
    the kernel's buffers, which the loop reads 256 kB per turn, so before deciding the read loop gives the
    event loop up to ``READ_AHEAD`` (4) turns to read what the kernel already holds (about one more
    640x480 rgb8 frame; it stops as soon as a newer frame shows up).  A stale frame is not decoded
    and not delivered, and it is counted (``stats.stale_skipped`` and the entry's ``skipped``) as
    deliberately dropped.  The newest frame is always delivered; order between topics is unchanged; small
    frames (values) cost one length comparison.

    Which topic a frame carries is read from the frame's first bytes, without decoding it
    (:func:`topic_of`): rosbridge and the sim write ``op`` and ``topic`` before ``msg``.  Only the part
    before the ``msg`` key is looked at, so a string inside a message can never be taken for the topic;
    a frame whose ``topic`` comes after ``msg`` (or that is not a publish) is never skipped.
"""

from __future__ import annotations

import asyncio
import re
from collections.abc import Callable, Iterable
from typing import Any

from .stats import BridgeStats

#: frames smaller than this are never looked at (values, small messages): skipping saves nothing
MIN_SIZE = 32 * 1024
_HEAD = 512  # bytes of a frame searched for its topic
#: event-loop turns a frame of a latest-only topic waits for a newer one to be read from the kernel
READ_AHEAD = 4
_sleep = asyncio.sleep

_JSON_TOPIC = re.compile(rb'"topic"\s*:\s*"([^"\\]{1,400})"')
_JSON_MSG = b'"msg"'
_CBOR_TOPIC = b"\x65topic"  # CBOR text string of length 5: "topic"
_CBOR_MSG = b"\x63msg"


def topic_of(raw: str | bytes) -> str | None:
    """The ``topic`` of a publish frame (JSON text or CBOR), read from its head; None when not found there."""
    if isinstance(raw, str):
        head = raw[:_HEAD].encode("utf-8", "replace")
        return _json_topic(head)
    head = bytes(raw[:_HEAD])
    if head[:1] == b"{":
        return _json_topic(head)
    return _cbor_topic(head)


def _json_topic(head: bytes) -> str | None:
    cut = head.find(_JSON_MSG)
    if cut < 0:
        return None
    m = _JSON_TOPIC.search(head, 0, cut)
    if m is None or b'"op"' not in head[:m.start()] + head[m.end():cut]:
        return None
    return m.group(1).decode("utf-8", "replace")


def _cbor_topic(head: bytes) -> str | None:
    cut = head.find(_CBOR_MSG)
    i = head.find(_CBOR_TOPIC, 0, cut)
    if cut < 0 or i < 0:
        return None
    i += len(_CBOR_TOPIC)
    if i >= len(head):
        return None
    major = head[i]
    if 0x60 <= major <= 0x77:  # a text string of 0..23 bytes
        n, i = major - 0x60, i + 1
    elif major == 0x78 and i + 1 < len(head):  # a text string with a one-byte length
        n, i = head[i + 1], i + 2
    else:
        return None
    if n == 0 or i + n > cut:
        return None
    return head[i:i + n].decode("utf-8", "replace")


class LatestOnly:
    """The read loop's check: is this frame stale, a newer one of its topic already waiting?"""

    __slots__ = ("topics", "stats", "min_size")

    def __init__(self, topics: dict[str, Any], stats: BridgeStats, min_size: int = MIN_SIZE) -> None:
        self.topics = topics  # the session's TopicEntry by name (``latest_only`` and ``skipped``)
        self.stats = stats
        self.min_size = min_size

    async def stale(self, raw: str | bytes, waiting: Callable[[], Iterable[bytes]]) -> bool:
        """True (and counted) when ``raw`` is a frame of a latest-only topic and a later complete frame of
        the same topic is in ``waiting()``; the caller then drops ``raw`` without decoding it.  Before it
        decides, it gives the event loop up to ``READ_AHEAD`` turns, so what the kernel already holds is
        read into the receive queue (one 256 kB read per turn: a 640x480 rgb8 frame)."""
        topic = topic_of(raw)
        if topic is None:
            return False
        entry = self.topics.get(topic)
        if entry is None or not entry.latest_only:
            return False
        for turn in range(READ_AHEAD + 1):
            if self._newer_waiting(topic, waiting):
                entry.skipped += 1
                self.stats.stale_skipped += 1
                return True
            if turn < READ_AHEAD:
                await _sleep(0)
        return False

    def _newer_waiting(self, topic: str, waiting: Callable[[], Iterable[bytes]]) -> bool:
        size = self.min_size
        return any(len(later) >= size and topic_of(later) == topic for later in waiting())
