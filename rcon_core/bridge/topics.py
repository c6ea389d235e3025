"""Shared per-topic state: one rosbridge subscription and one advertisement per topic, many nodes.

Several nodes on one topic share ONE rosbridge subscription.  Its options are merged:

* ``throttle_rate``: the smallest (the tightest a consumer asked for wins; rosbridge does the same across
  ids on one topic, ``subscribe_options.jsonl:113-114``);
* ``queue_length``: the largest (what rosbridge itself picks across ids); when every consumer asked for 1
  the topic is also *latest-only* on the client side (``latest.py``);
* ``fragment_size``: the smallest given;
* ``compression``: the first of ``cbor``, ``cbor-raw``, ``png``, ``none`` that any consumer asked for
  (every mode is decoded into the same dicts, so the cheapest binary form serves everybody) -- among the
  consumers that take messages; the ``raw=True`` ones (the flight recorder) choose only when they are alone.
  A recorder that joins a topic a widget reads changes nothing on the wire (no re-subscription, no switch of
  the widget's encoding, which made every value go through a slower decoder) and takes the messages as
  they come (``record/ingest.py`` serializes them by the robot's definition);
* ``type``: the first type given.

When the set of consumers changes the options are recomputed and, if they changed, the client subscribes
with a new id and then unsubscribes the old one (no gap: publish frames do not carry the id).  The last
consumer to leave unsubscribes.  Advertisements are shared the same way (``latch`` if any asked,
the largest ``queue_size``); the last publisher to leave unadvertises.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import orjson

if TYPE_CHECKING:
    from .nodes import Publisher, Subscription
    from .traffic import Tally

log = logging.getLogger(__name__)

_COMPRESSION_RANK = {"cbor": 0, "cbor-raw": 1, "png": 2, "none": 3}


class RawPayload:
    """A ``cbor-raw`` message as the server sent it, for consumers that asked for ``raw=True``: ``type``
    (the server's spelling), ``secs``/``nsecs`` (the server's time) and ``data`` (ROS 1 or CDR bytes)."""

    __slots__ = ("type", "secs", "nsecs", "data")

    def __init__(self, type: str, secs: int, nsecs: int, data: bytes) -> None:
        self.type = type
        self.secs = secs
        self.nsecs = nsecs
        self.data = data


class TopicEntry:
    """The client's one subscription to a topic, fanned out to every node's callback."""

    __slots__ = ("topic", "subs", "deliver", "fast", "sid", "sent_options", "raw_type", "decoder", "received",
                 "report", "latest_only", "skipped", "raw_subs", "cooked_subs", "tally", "leftovers_until",
                 "leftovers_type")

    def __init__(self, topic: str, report: Callable[[str, str], None]) -> None:
        self.report = report  # ``report(kind, message)``: a payload that cannot be decoded (a bad frame)
        self.topic = topic
        self.subs: list[Subscription] = []
        self.sid: str | None = None  # id of the rosbridge subscription currently active on the server
        self.sent_options: dict[str, Any] | None = None
        self.raw_type: str | None = None  # set when the active subscription is cbor-raw
        #: until then (monotonic s; 0: not) cbor-raw payloads of a replaced subscription may still arrive
        self.leftovers_until = 0.0
        self.leftovers_type = ""  # the type of those payloads
        self.decoder: Any = None
        self.received = 0
        #: every consumer asked for ``queue_length`` 1: stale frames are skipped when a newer one waits
        #: (``latest.py``); ``skipped`` counts them
        self.latest_only = False
        self.skipped = 0
        #: consumers that take cbor-raw payloads undecoded (``Node.subscribe(raw=True)``) and the others
        self.raw_subs: list[Subscription] = []
        self.cooked_subs: list[Subscription] = []
        #: ``deliver(msg)`` never raises: callback errors are logged.  ``fast(msg)`` is what the client's
        #: read loop calls, inside its own ``try``: the one consumer's callback itself when there is one
        #: consumer (no wrapper frame per message), else the same as ``deliver``.
        self.deliver: Callable[[Any], None] = self._deliver_none
        self.fast: Callable[[Any], None] = self._deliver_none
        #: the topic's row of the connection's traffic counts (``Traffic.row``: a ``Tally`` of bytes and
        #: frames), which the read loop adds to; set by the read loop at the topic's first message
        self.tally: Tally | None = None

    # --- options ---------------------------------------------------------------------------------

    def wanted(self) -> dict[str, Any]:
        """The merged options of every consumer (before the cbor -> cbor-raw decision)."""
        subs = self.subs
        opts: dict[str, Any] = {"throttle_rate": min(s.throttle_rate for s in subs),
                                "queue_length": max(s.queue_length for s in subs)}
        types = [s.type for s in subs if s.type]
        if types:
            opts["type"] = types[0]
        frags = [s.fragment_size for s in subs if s.fragment_size]
        if frags:
            opts["fragment_size"] = min(frags)
        choosers = [s for s in subs if not s.raw] or subs
        opts["compression"] = min((s.compression for s in choosers), key=_COMPRESSION_RANK.__getitem__)
        return opts

    # --- delivery (the hot path) -----------------------------------------------------------------

    def rebuild(self) -> None:
        """Pick the delivery functions for the current set of consumers (no per-message branching)."""
        subs = self.subs
        self.latest_only = bool(subs) and all(s.queue_length == 1 for s in subs)
        self.raw_subs = [s for s in subs if s.raw]
        self.cooked_subs = [s for s in subs if not s.raw]
        if self.raw_type is not None:
            self.deliver = self.fast = self._deliver_raw
        elif subs and self.leftovers_until:
            self.deliver = self.fast = self._deliver_after_raw
        elif not subs:
            self.deliver = self.fast = self._deliver_none
        elif len(subs) == 1:
            self.fast = subs[0].callback
            self.deliver = self._make_one(self.fast)
        else:
            self.deliver = self.fast = self._deliver_many

    def callback_failed(self) -> None:
        """Log the exception a ``fast`` callback raised (called from the read loop's ``except``)."""
        log.exception("callback for %s raised; other subscribers are unaffected", self.topic)

    def _deliver_none(self, msg: Any) -> None:
        self.received += 1

    def _make_one(self, cb: Callable[[Any], None]) -> Callable[[Any], None]:
        topic = self.topic

        def deliver_one(msg: Any) -> None:
            try:
                cb(msg)
            except Exception:
                log.exception("callback for %s raised; other subscribers are unaffected", topic)

        return deliver_one

    def _deliver_many(self, msg: Any) -> None:
        for s in self.subs:
            try:
                s.callback(msg)
            except Exception:
                log.exception("callback for %s (node %s) raised; other subscribers are unaffected",
                              self.topic, s.node.id)

    def _deliver_after_raw(self, msg: Any) -> None:
        """Delivery for a while after the topic left ``cbor-raw``: a payload of the replaced subscription
        still in flight is decoded (as it was before the switch) instead of reaching a consumer as a
        ``{secs, nsecs, bytes}`` dict."""
        if time.monotonic() > self.leftovers_until:
            self.leftovers_until = 0.0
            self.rebuild()
            self.deliver(msg)
            return
        if type(msg) is dict and "bytes" in msg and "secs" in msg and self.decoder is not None:
            self._deliver_payload(msg, self.leftovers_type)
            return
        self._deliver_many(msg)

    def _deliver_raw(self, msg: Any) -> None:
        if type(msg) is dict and "bytes" not in msg and "secs" not in msg:
            # a message of the subscription this one replaced (JSON or cbor), still in flight: as it is
            self._deliver_many(msg)
            return
        self._deliver_payload(msg, self.raw_type or "")

    def _deliver_payload(self, msg: Any, type_name: str) -> None:
        if self.raw_subs:
            self._deliver_undecoded(msg, type_name)
            if not self.cooked_subs:
                return
        try:
            data = msg["bytes"]
            decoded = self.decoder.decode(type_name, data)
        except Exception as exc:
            self.report("cbor-raw", f"{self.topic}: cannot decode cbor-raw message ({exc})")
            return
        for s in self.cooked_subs:
            try:
                s.callback(decoded)
            except Exception:
                log.exception("callback for %s (node %s) raised; other subscribers are unaffected",
                              self.topic, s.node.id)

    def _deliver_undecoded(self, msg: Any, type_name: str) -> None:
        try:
            data = msg["bytes"]
            payload = RawPayload(type_name, int(msg.get("secs", 0)), int(msg.get("nsecs", 0)),
                                 data if isinstance(data, bytes) else bytes(data))
        except Exception as exc:
            self.report("cbor-raw", f"{self.topic}: malformed cbor-raw message ({exc})")
            return
        for s in self.raw_subs:
            try:
                s.callback(payload)  # type: ignore[arg-type]  # raw consumers take RawPayload
            except Exception:
                log.exception("callback for %s (node %s) raised; other subscribers are unaffected",
                              self.topic, s.node.id)


class AdvertEntry:
    """The client's one advertisement of a topic, shared by every node's Publisher."""

    __slots__ = ("topic", "pubs", "type", "latch", "queue_size", "active", "pending", "dropped", "head", "tail")

    def __init__(self, topic: str, type: str) -> None:
        self.topic = topic
        #: the start of every publish frame of this topic, up to the message (encoded once)
        self.head = b'{"op":"publish","topic":' + orjson.dumps(topic) + b',"msg":'
        self.tail = b"}"  # the end of every publish frame: ``,"latch":true}`` when latched (``client_publish.jsonl:26-30``)
        self.type = type
        self.pubs: list[Publisher] = []
        self.latch = False
        self.queue_size = 100
        self.active = False  # advertise sent on the current connection
        self.pending: Any = None  # latest latched value published while the link was down
        self.dropped = 0

    def merge(self) -> bool:
        """Recompute latch/queue_size from the publishers; True when they changed."""
        latch = any(p.latch for p in self.pubs)
        queue_size = max((p.queue_size for p in self.pubs), default=100)
        changed = (latch, queue_size) != (self.latch, self.queue_size)
        self.latch, self.queue_size = latch, queue_size
        self.tail = b',"latch":true}' if latch else b"}"
        return changed

    def advertise_op(self) -> dict[str, Any]:
        return {"op": "advertise", "id": f"adv:{self.topic}", "topic": self.topic, "type": self.type,
                "latch": self.latch, "queue_size": self.queue_size}
