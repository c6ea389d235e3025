"""Sending one published message to the clients subscribed to its topic, in the encodings they asked for.

A subscription names its compression (``none``, ``png``, ``cbor``, ``cbor-raw``) and may ask for fragments;
each compression is encoded once per message however many clients share it, and a message that cannot be
encoded is logged and sent to nobody (as rosbridge does). Each connection's own bounded queue
(``connection.py``) takes it from there, and cuts a text frame into fragments only as it sends it: a frame
dropped from a slow client's queue is never cut at all.
"""

from __future__ import annotations

import logging
import time
from typing import TYPE_CHECKING, Any

from . import encoding

if TYPE_CHECKING:
    from .flavour import Flavour
    from .graph import Topic
    from .typesource import TypeSource

log = logging.getLogger("rcon.sim")


def fan_out(topic: Topic, msg: dict[str, Any], flavour: Flavour, types: TypeSource) -> None:
    """Send ``msg`` to every connection subscribed to ``topic``, each in the encoding it asked for
    (throttled subscriptions skip it); each encoding is made once per message."""
    cache: dict[Any, Any] = {}
    now = time.monotonic()
    for conn in list(topic.client_subscribers):
        sub = conn.subscriptions.get(topic.name)
        if sub is None:
            continue
        throttle = sub.throttle_s
        if throttle > 0 and now - sub.last_sent < throttle:
            continue  # throttling drops, it does not delay
        payload = encoded(cache, topic, msg, sub.compression, flavour, types)
        if payload is None:
            continue
        sub.last_sent = now
        conn.send(payload, topic=topic.name, queue_length=sub.queue_length, fragment_size=conn.fragment_size)


def wants_text(topic: Topic) -> bool:
    """Whether a client subscribed to ``topic`` takes it as JSON text (compression ``none`` or ``png``)."""
    for conn in topic.client_subscribers:
        sub = conn.subscriptions.get(topic.name)
        if sub is not None and sub.compression in ("none", "png"):
            return True
    return False


def encoded(cache: dict[Any, Any], topic: Topic, msg: dict[str, Any], compression: str,
            flavour: Flavour, types: TypeSource) -> str | bytes | None:
    """``msg`` as a publish frame in ``compression``, from or into ``cache``; None if it cannot be encoded
    (logged, as rosbridge does)."""
    key = ("frame", compression)
    if key in cache:
        return cache[key]
    try:
        payload: str | bytes | None
        if compression == "cbor":
            payload = encoding.cbor_dumps(encoding.publish_frame(topic.name, msg))
        elif compression == "cbor-raw":
            recorded = getattr(msg, "raw", None)  # a recording's own bytes (playback.RecordedMessage)
            raw = {**flavour.time(), "bytes": recorded if recorded is not None else types.serialize(topic.type, msg)}
            if flavour.ros2:
                raw = {"secs": raw["sec"], "nsecs": raw["nanosec"], "bytes": raw["bytes"]}
            payload = encoding.cbor_dumps(encoding.publish_frame(topic.name, raw))
        else:
            text = cache.get("text")
            if text is None:
                text = cache["text"] = encoding.dumps(encoding.publish_frame(topic.name, msg))
            if compression == "png":
                text = encoding.png_frame(text)
            payload = text
    except Exception as exc:  # noqa: BLE001 - mirror rosbridge: log once per message, send nothing
        log.error("Exception calling subscribe callback: %s", exc)
        payload = None
    cache[key] = payload
    return payload
