"""What one Foxglove subscription hands its consumers: decoded dicts, or the payload bytes as the server sent them.

Decision: a raw consumer gets the MessageData payload unchanged
    A consumer that subscribed with ``raw=True`` (the flight recorder) gets a
    :class:`~rcon_core.bridge.topics.RawPayload` per message, as on the rosbridge link's ``cbor-raw`` path:
    ``type`` is the channel's schema name, ``secs``/``nsecs`` the MessageData timestamp (the server's log
    time) and ``data`` the payload bytes -- the frame from offset 13 on, in the channel's own encoding
    (``cdr``, ``ros1``, ``json``, ``protobuf``, ``flatbuffer``...), nothing decoded or re-encoded.  When every
    consumer of a topic is raw the payload is never decoded (a recorder pays for one slice per message, and
    a channel RCON cannot decode is still recorded); when raw and decoding consumers share a topic the raw
    ones get the payload first and the frame is decoded once for the others.  A consumer that is not raw
    never sees a payload: with no raw consumer the session's hot path is the one it always was.

The session calls :func:`frame_decoder` each time a topic's consumers change and keeps what it returns as
the subscription's per-frame function; it also sets ``entry.fast``, the function the read loop hands that
function's result to.  No asyncio, no Qt.
"""

from __future__ import annotations

import logging
import struct
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from rcon_core.bridge.topics import RawPayload

if TYPE_CHECKING:
    from rcon_core.bridge.topics import TopicEntry

    from .entries import Channel

__all__ = ["frame_decoder", "payload_of"]

log = logging.getLogger(__name__)

_STAMP = struct.Struct("<Q").unpack_from
HEAD = 13  # opcode (1), subscription id (4), log time (8)


def payload_of(frame: bytes | memoryview, schema_name: str) -> RawPayload:
    """A MessageData frame as a :class:`RawPayload` (see the module docstring); the payload is a copy, ``bytes``
    (the frame may be a view into the transport's read buffer, valid only while it is handled)."""
    ns = _STAMP(frame, 5)[0]
    return RawPayload(schema_name, ns // 1_000_000_000, ns % 1_000_000_000, bytes(frame[HEAD:]))


def frame_decoder(entry: TopicEntry, ch: Channel, decode: Callable[[Any], Any] | None) -> Callable[[Any], Any]:
    """The per-frame function of ``entry``'s subscription to ``ch`` for its current consumers; sets
    ``entry.fast``/``entry.deliver`` to match.  ``decode``: the channel's decoder of whole frames (None when
    RCON cannot decode the channel: only the raw consumers are then served, the others get nothing)."""
    raw_subs, cooked = list(entry.raw_subs), list(entry.cooked_subs)
    if not raw_subs:
        if decode is None:  # the raw consumers left and RCON cannot decode the channel: nobody is served
            entry.fast = entry.deliver = _nobody
            return _nobody
        return decode  # entry.fast is the consumers' own, as TopicEntry.rebuild set it
    name = ch.schema_name
    to_raw = _fan_out(entry, raw_subs)
    if not cooked or decode is None:
        entry.fast = entry.deliver = to_raw
        return lambda frame: payload_of(frame, name)
    to_cooked = _fan_out(entry, cooked)
    topic, report = entry.topic, entry.report

    def both(pair: tuple[RawPayload, bytes]) -> None:
        payload, frame = pair
        to_raw(payload)
        try:
            msg = decode(frame)
        except Exception as exc:  # noqa: BLE001 - counted as a bad frame, as the session does
            report("payload", f"{topic}: cannot decode a message ({exc})")
            return
        to_cooked(msg)

    entry.fast = entry.deliver = both
    return lambda frame: (payload_of(frame, name), frame)


def _nobody(_item: Any) -> None:
    return None


def _fan_out(entry: TopicEntry, subs: list[Any]) -> Callable[[Any], None]:
    topic = entry.topic

    def deliver(msg: Any) -> None:
        for s in subs:
            try:
                s.callback(msg)
            except Exception:  # noqa: BLE001 - one consumer never stops the others
                log.exception("callback for %s (node %s) raised; other subscribers are unaffected", topic,
                              s.node.id)

    return deliver
