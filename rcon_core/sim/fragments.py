"""Reassembling the ``fragment`` ops one client sends, in time linear in the fragments and with bounded
memory (one :class:`Reassembler` per connection).

rosbridge keeps the fragments of each message id until ``total`` of them are there, then handles the joined
text as one frame; a list untouched for ``fragment_timeout`` (600 s) is dropped when the next fragment
comes. The sim does the same, with bounds rosbridge lacks:

* every fragment costs O(1) plus its own size: the bytes held and the parts still missing are counted as
  they change (the old code summed every part held at every fragment: 20,000 one-byte fragments took 18 s
  of CPU and starved every other client);
* a message may have at most :data:`MAX_PARTS` fragments, a connection at most :data:`MAX_MESSAGES`
  unfinished messages, :data:`MAX_PARTS_HELD` parts and ``max_bytes`` bytes (the frame limit) held;
* a message untouched for :data:`EXPIRE_S` is dropped (checked in order of age, so the check is O(1)).

A fragment that breaks a rule raises :class:`FragmentError` once (the server logs that one line); the rest
of a refused message is dropped silently (its id is remembered, with how many fragments are still to come,
for at most :data:`EXPIRE_S` and :data:`REFUSED_KEEP` ids), so a flood of bad fragments costs one log line
per message, not one per fragment.
"""

from __future__ import annotations

import collections
import math
import time
from collections.abc import Callable, Hashable
from dataclasses import dataclass, field
from typing import Any

__all__ = ["Reassembler", "FragmentError", "MAX_PARTS", "MAX_MESSAGES", "MAX_PARTS_HELD", "EXPIRE_S"]

#: fragments one message may be cut in (a 32 MB message in 3.2 KB fragments)
MAX_PARTS = 10_000
#: unfinished messages one connection may have
MAX_MESSAGES = 64
#: fragments one connection may hold in all its unfinished messages
MAX_PARTS_HELD = 2 * MAX_PARTS
#: an unfinished message untouched this long is dropped (rosbridge: fragment_timeout, 600 s)
EXPIRE_S = 60.0
#: ids of refused messages remembered (their later fragments are dropped without a log line)
REFUSED_KEEP = 256


class FragmentError(Exception):
    """A fragment the server refuses (the text says why; logged once per message)."""


@dataclass
class _Message:
    total: int
    parts: dict[int, str] = field(default_factory=dict)
    size: int = 0
    touched: float = 0.0


class Reassembler:
    """The unfinished fragmented messages of one connection."""

    def __init__(self, max_bytes: int, clock: Callable[[], float] = time.monotonic) -> None:
        self.max_bytes = max_bytes
        self.clock = clock
        #: by message id, least recently touched first
        self.messages: collections.OrderedDict[Hashable, _Message] = collections.OrderedDict()
        self.bytes_held = 0
        self.parts_held = 0
        self.refused = 0  # messages refused (each logged once)
        self.expired = 0  # messages dropped for age
        #: refused message id -> [fragments still to come, when the last one came]
        self._refused_ids: collections.OrderedDict[Hashable, list[float]] = collections.OrderedDict()

    def __len__(self) -> int:
        return len(self.messages)

    def add(self, msg: dict[str, Any]) -> str | None:
        """Take one ``fragment`` op; the joined text when it completes its message, else None.
        Raises :class:`FragmentError` for a fragment that breaks a rule (once per message id)."""
        now = self.clock()
        self._expire(now)
        frag_id: Any = msg.get("id")
        data: Any = msg.get("data")
        num: Any = msg.get("num")
        total: Any = msg.get("total")
        if not isinstance(frag_id, Hashable) or not isinstance(data, str) or not _whole(num) \
                or not _number(total):
            raise FragmentError("received invalid fragment! (needs an id, string data, an integer num and a "
                                "numeric total)")
        count = math.floor(total)
        if self._rest_of_refused(frag_id, now):
            return None  # the rest of a refused message: dropped, already logged
        message = self.messages.get(frag_id)
        if message is None:
            if not 1 <= count <= MAX_PARTS:
                self._refuse(frag_id, max(count, MAX_PARTS), now,
                             f"fragment total {total!r} is not between 1 and {MAX_PARTS}")
            if len(self.messages) >= MAX_MESSAGES:
                self._refuse(frag_id, count, now, f"more than {MAX_MESSAGES} unfinished fragmented messages")
            message = self.messages[frag_id] = _Message(count)
        elif count != message.total:
            self._refuse(frag_id, message.total - len(message.parts), now,
                         f"fragment total {total!r} differs from the first fragment's {message.total}")
        if not 0 <= num < message.total:
            self._refuse(frag_id, message.total - len(message.parts), now,
                         f"fragment num {num!r} is outside 0..{message.total - 1}")
        if self.parts_held >= MAX_PARTS_HELD or self.bytes_held + len(data) > self.max_bytes:
            self._refuse(frag_id, message.total - len(message.parts), now,
                         f"fragments held would exceed {MAX_PARTS_HELD} parts or {self.max_bytes} bytes")
        old = message.parts.get(num)
        if old is not None:  # a repeated fragment replaces the earlier one
            message.size -= len(old)
            self.bytes_held -= len(old)
            self.parts_held -= 1
        message.parts[num] = data
        message.size += len(data)
        self.bytes_held += len(data)
        self.parts_held += 1
        message.touched = now
        self.messages.move_to_end(frag_id)
        if len(message.parts) < message.total:
            return None
        self._drop(frag_id)
        return "".join(message.parts[i] for i in range(message.total))

    def clear(self) -> None:
        self.messages.clear()
        self.bytes_held = self.parts_held = 0

    def _drop(self, frag_id: Hashable) -> None:
        message = self.messages.pop(frag_id, None)
        if message is not None:
            self.bytes_held -= message.size
            self.parts_held -= len(message.parts)

    def _refuse(self, frag_id: Hashable, still_to_come: int, now: float, why: str) -> None:
        """Drop message ``frag_id`` and remember to drop its ``still_to_come`` other fragments quietly."""
        self._drop(frag_id)
        self.refused += 1
        self._refused_ids[frag_id] = [still_to_come - 1, now]
        self._refused_ids.move_to_end(frag_id)
        while len(self._refused_ids) > REFUSED_KEEP:
            self._refused_ids.popitem(last=False)
        raise FragmentError(f"{why}; message dropped")

    def _rest_of_refused(self, frag_id: Hashable, now: float) -> bool:
        """Whether this fragment belongs to a message refused lately (counting it off)."""
        entry = self._refused_ids.get(frag_id)
        if entry is None:
            return False
        if entry[0] <= 0 or now - entry[1] > EXPIRE_S:
            del self._refused_ids[frag_id]
            return False
        entry[0] -= 1
        entry[1] = now
        return True

    def _expire(self, now: float) -> None:
        while self.messages:
            frag_id, oldest = next(iter(self.messages.items()))
            if now - oldest.touched <= EXPIRE_S:
                return
            self._drop(frag_id)
            self.expired += 1


def _whole(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)
