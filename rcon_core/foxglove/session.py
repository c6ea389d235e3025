"""``FoxgloveSession``: the Foxglove WebSocket protocol's state for one client, apart from the transport.

A pure state machine in the manner of h11 and websockets' ``protocol.py``: frames in (:meth:`receive`
for each text or binary frame from the server, :meth:`attached` / :meth:`detached` when a connection comes
and goes), frames out through the ``write(frame)`` and ``command(frame, pub, max_age)`` functions the shell
hands over at :meth:`attached` (a ``str`` is a text frame, ``bytes`` a binary one; nothing is written while
there is no connection), and events to the shell through callbacks (a service answer, a parameter answer,
the catalogue changed).  Service calls, parameter requests and parameter watches are its part
``requests.py`` (``session.requests``).  No asyncio here: ``client.py`` is the async shell (connect, reconnect, stall
watch, futures and timeouts).  The nodes (``rcon_core.bridge.nodes``: the same ``Node`` the rosbridge link
hands out) call :meth:`add_subscription`, :meth:`add_publisher`, :meth:`publish`... exactly as they call the
rosbridge session, so a widget cannot tell the protocols apart; a ``raw=True`` consumer (the flight
recorder) gets each payload's bytes unchanged, even of a channel RCON cannot decode (``delivery.py``).

Decision: the catalogue
    ``advertise``/``unadvertise`` keep ``channels`` (id -> :class:`Channel`); a topic offered on several
    channels is read from the first.  ``advertiseServices``/``unadvertiseServices`` keep ``services``.
    ``connectionGraphUpdate`` keeps ``graph`` (who publishes, subscribes, provides; removals applied).
    Everything is forgotten with the connection: a new connection (a restarted server) advertises afresh
    with new ids.

Decision: after every (re)connect
    Subscriptions are sent for each wanted topic as soon as its channel is advertised (a subscription made
    before the channel appears waits for it); client channels, parameter subscriptions and the graph
    subscription are sent once ``serverInfo`` said what the server can do.  Parameter subscriptions and
    the graph subscription are kept across reconnects like subscriptions and advertisements.

Decision: publishing and stale commands
    As on the rosbridge link (``rcon_core/bridge/session.py``): nothing is queued while down except a latched
    topic's latest value, a publish past its ``max_age`` is dropped and counted, a view-only link refuses
    with ``ViewOnlyError`` before anything is encoded, and a motion command is held to the robot's safety
    envelope (``rcon_core/bridge/envelope.py``: clamped, or ``EnvelopeRefused``).  The client's channel uses the encoding
    ``codecs.py`` picks from the server's ``supportedEncodings``; a server without ``clientPublish``
    refuses the publish in words (``BridgeError``).

Decision: bad frames
    Every frame that does not follow the protocol (``wire.WireError``), an unknown op, a message for an
    unknown subscription, a payload that does not decode: counted in ``stats.bad_frames`` through the
    rosbridge link's ``BadFrames`` (logged with a bounded text), the frame dropped, the link kept.

Decision: what the protocol cannot do
    Actions and rosauth do not exist in it; providing a service, a parameter delete and a topic without a
    schema cannot be done over it.  Each raises ``BridgeError``/``ActionError`` with a sentence naming the
    protocol (:data:`CANNOT`), so the operator reads it where the request was made.
"""

from __future__ import annotations

import itertools
import logging
import struct
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from rcon_core.bridge.envelope import Envelope, enforce
from rcon_core.bridge.errors import BridgeError
from rcon_core.bridge.inbound import BadFrames
from rcon_core.bridge.safety import bounded_repr, safe_text
from rcon_core.bridge.stats import FoxgloveStats
from rcon_core.bridge.tap import OperatorTap
from rcon_core.bridge.topics import TopicEntry

from . import wire
from .codecs import CodecError, Codecs, Decode
from .delivery import frame_decoder
from .entries import CANNOT, STATUS_LEVELS, Channel, ClientChannel, Service, _NoActions, _NoServices
from .guard import FoxgloveGuard
from .requests import Requests

if TYPE_CHECKING:
    from rcon_core.bridge.nodes import Node, Publisher, Subscription

__all__ = ["CANNOT", "FoxgloveSession"]

log = logging.getLogger(__name__)

Write = Callable[[str | bytes], None]
_SUB_ID = struct.Struct("<I").unpack_from
Command = Callable[[bytes, Any, float], bool]


class FoxgloveSession:
    """The protocol state of one Foxglove client (see the module docstring)."""

    def __init__(self, url: str, stats: FoxgloveStats, bad: BadFrames, codecs: Codecs | None = None) -> None:
        self.url = url
        self.stats = stats
        self.bad = bad
        self.codecs = codecs or Codecs()
        self.guard = FoxgloveGuard(url)
        self.guard.add_listener(self._guard_changed)
        self.nodes: dict[str, Node] = {}
        self.services_provided = _NoServices()
        self.services: Any = self.services_provided  # what Node.advertise_service reaches
        self.goals = self.provided_actions = _NoActions()
        #: the robot's safety envelope: every motion command is held to it, as on the rosbridge link
        self.envelope: Envelope | None = None
        #: what the nodes send, told to listeners (the flight recorder; ``rcon_core/bridge/tap.py``)
        self.tap = OperatorTap()
        # the connection
        self._write: Write | None = None
        self._command: Command | None = None
        self.server: dict[str, Any] | None = None  # the serverInfo frame
        self.channels: dict[int, Channel] = {}
        self.by_topic: dict[str, Channel] = {}
        self.service_list: dict[int, Service] = {}
        self.service_by_name: dict[str, Service] = {}
        self.graph: dict[str, dict[str, list[str]]] = {"published": {}, "subscribed": {}, "services": {}}
        self.time_ns: int | None = None
        self.statuses: dict[str, tuple[str, str]] = {}
        # what this client wants (kept across reconnects)
        self.topics: dict[str, TopicEntry] = {}
        self.adverts: dict[str, ClientChannel] = {}
        self.graph_wanted = False
        # ids
        self._sub_ids = itertools.count(1)
        self._chan_ids = itertools.count(1)
        self.subs: dict[int, tuple[TopicEntry, Decode]] = {}  # subscription id -> (topic, decoder)
        self.listeners: list[Callable[[str], None]] = []  # fn(kind): "catalog", "graph", "status", "params"
        self.status_listeners: list[Callable[[dict[str, Any]], None]] = []
        #: service calls, parameter requests and watches (``requests.py``)
        self.requests = Requests(self, self._send, self._notify)
        self._ops: dict[str, Callable[[dict[str, Any]], None]] = {
            "serverInfo": self._on_server_info, "status": self._on_status, "removeStatus": self._on_remove_status,
            "advertise": self._on_advertise, "unadvertise": self._on_unadvertise,
            "advertiseServices": self._on_advertise_services, "unadvertiseServices": self._on_unadvertise_services,
            "parameterValues": self.requests.on_parameter_values, "connectionGraphUpdate": self._on_graph,
            "serviceCallFailure": self.requests.on_call_failure, "playbackState": lambda m: None,
        }

    # ================================================================== the connection comes and goes

    @property
    def capabilities(self) -> list[str]:
        caps = (self.server or {}).get("capabilities")
        return [c for c in caps if isinstance(c, str)] if isinstance(caps, list) else []

    @property
    def encodings(self) -> list[str]:
        enc = (self.server or {}).get("supportedEncodings")
        return [e for e in enc if isinstance(e, str)] if isinstance(enc, list) else []

    def attached(self, write: Write, command: Command) -> None:
        self._write, self._command = write, command

    def detached(self) -> None:
        """The connection is gone: forget the server's catalogue; the calls waiting fail (``requests.py``)."""
        self._write = self._command = None
        self.server = None
        self.channels.clear()
        self.by_topic.clear()
        self.service_list.clear()
        self.service_by_name.clear()
        self.graph = {"published": {}, "subscribed": {}, "services": {}}
        self.statuses.clear()
        self.subs.clear()
        for entry in self.topics.values():
            entry.sid = None
        for adv in self.adverts.values():
            adv.active = False
        self.guard.offered.clear()
        self._notify("catalog")
        self.requests.detached()

    def _send(self, kind: str, target: str, frame: str | bytes) -> bool:
        write = self._write
        if write is None or not self.guard.admit_op(kind, target):
            return False
        write(frame)
        return True

    def _notify(self, kind: str) -> None:
        for fn in list(self.listeners):
            try:
                fn(kind)
            except Exception:
                log.exception("foxglove session listener raised")

    # ================================================================== frames in

    def receive(self, frame: str | bytes) -> None:
        """One frame from the server (a text frame as ``str``); a bad one is counted and dropped, never raised."""
        if isinstance(frame, str):
            self.receive_text(frame)
        else:
            self.receive_binary(frame)

    def receive_binary(self, frame: bytes | memoryview) -> None:
        """One binary frame (bytes-like; a view into the transport's read buffer is read during this call
        only: whatever is kept is copied).  A MessageData frame of a subscription takes the short way (no
        parse into a tuple; the decoder reads the frame at offset 13)."""
        if len(frame) >= 13 and frame[0] == 1:
            found = self.subs.get(_SUB_ID(frame, 1)[0])
            if found is None:
                self.stats.unknown_subscription += 1  # still in flight after an unsubscribe: not an error
                return
            entry, decode = found
            try:
                msg = decode(frame)
            except Exception as exc:
                self.bad.report("payload", f"{entry.topic}: cannot decode a message ({safe_text(exc)})")
                return
            try:
                entry.fast(msg)
            except Exception:
                entry.callback_failed()
            return
        self.receive_text(frame, False)

    def receive_text(self, frame: Any, text: bool = True) -> None:
        """One text frame (a JSON op; with ``text`` False: a binary frame that is not a MessageData one)."""
        try:
            if not text:
                self._on_binary(wire.parse_binary(frame))
                return
            m = wire.parse_text(frame)
            handler = self._ops.get(m["op"])
            if handler is None:
                self.bad.report("op", f"unknown op {bounded_repr(m['op'], 60)} ignored")
                return
            handler(m)
        except wire.WireError as exc:
            self.bad.report("frame", str(exc))
        except (KeyError, TypeError, ValueError, AttributeError) as exc:
            self.bad.report("field", f"malformed frame ignored ({safe_text(exc)})")

    def _on_server_info(self, m: dict[str, Any]) -> None:
        wire.text_field(m, "name", required=False)
        wire.items(m, "capabilities", required=False)
        self.server = m
        # restore what this client offered and watches (subscriptions wait for their channels)
        for adv in self.adverts.values():
            self._advertise(adv)
        self.requests.restore()
        if self.graph_wanted and "connectionGraph" in self.capabilities:
            self._send("subscribeConnectionGraph", "", wire.graph_frame())
        self._notify("server")

    def _on_status(self, m: dict[str, Any]) -> None:
        level = m.get("level")
        word = STATUS_LEVELS.get(level, "info") if isinstance(level, int) else "info"
        text = m.get("message")
        text = text if isinstance(text, str) else bounded_repr(text, 200)
        sid = m.get("id")
        if isinstance(sid, str):
            self.statuses[sid] = (word, text)
        log.log({"error": logging.ERROR, "warning": logging.WARNING}.get(word, logging.INFO),
                "server status (%s): %s", word, text[:500])
        frame = {"op": "status", "level": word, "msg": text, "id": sid if isinstance(sid, str) else None}
        for fn in list(self.status_listeners):
            try:
                fn(frame)
            except Exception:
                log.exception("status listener raised")

    def _on_remove_status(self, m: dict[str, Any]) -> None:
        for sid in wire.items(m, "statusIds"):
            if isinstance(sid, str):
                self.statuses.pop(sid, None)

    def _on_advertise(self, m: dict[str, Any]) -> None:
        for raw in wire.items(m, "channels"):
            try:
                ch = Channel(wire.channel(raw))
            except wire.WireError as exc:  # one bad channel, the others stand
                self.bad.report("frame", str(exc))
                continue
            old = self.channels.get(ch.id)
            if old is not None:
                self._drop_channel(old)
            self.channels[ch.id] = ch
            self.by_topic.setdefault(ch.topic, ch)
            entry = self.topics.get(ch.topic)
            if entry is not None and entry.sid is None:
                self._subscribe(entry)
        self._notify("catalog")

    def _on_unadvertise(self, m: dict[str, Any]) -> None:
        for cid in wire.items(m, "channelIds"):
            ch = self.channels.get(cid) if isinstance(cid, int) else None
            if ch is not None:
                self._drop_channel(ch)
        self._notify("catalog")

    def _drop_channel(self, ch: Channel) -> None:
        del self.channels[ch.id]
        if self.by_topic.get(ch.topic) is ch:
            del self.by_topic[ch.topic]
            other = next((c for c in self.channels.values() if c.topic == ch.topic), None)
            if other is not None:
                self.by_topic[ch.topic] = other
        entry = self.topics.get(ch.topic)
        if entry is not None and entry.sid is not None:
            sub = int(entry.sid)
            self.subs.pop(sub, None)
            entry.sid = None
            if ch.topic in self.by_topic:
                self._subscribe(entry)

    def _on_advertise_services(self, m: dict[str, Any]) -> None:
        for s in wire.items(m, "services"):
            if not isinstance(s, dict):
                self.bad.report("frame", "advertiseServices: a service is not an object")
                continue
            try:
                srv = Service(wire.ident(s.get("id"), "service id"), wire.text_field(s, "name"),
                              wire.text_field(s, "type", required=False), wire.service_schemas(s, self.encodings))
            except wire.WireError as exc:
                self.bad.report("frame", str(exc))
                continue
            self.service_list[srv.id] = srv
            self.service_by_name[srv.name] = srv
        self._notify("catalog")

    def _on_unadvertise_services(self, m: dict[str, Any]) -> None:
        for sid in wire.items(m, "serviceIds"):
            srv = self.service_list.pop(sid, None) if isinstance(sid, int) else None
            if srv is not None and self.service_by_name.get(srv.name) is srv:
                del self.service_by_name[srv.name]
        self._notify("catalog")

    def _on_graph(self, m: dict[str, Any]) -> None:
        g = self.graph
        for key, field, ids in (("published", "publishedTopics", "publisherIds"),
                                ("subscribed", "subscribedTopics", "subscriberIds"),
                                ("services", "advertisedServices", "providerIds")):
            for item in wire.items(m, field, required=False):
                if isinstance(item, dict) and isinstance(item.get("name"), str):
                    who = item.get(ids)
                    g[key][item["name"]] = [w for w in who if isinstance(w, str)] if isinstance(who, list) else []
        for name in wire.items(m, "removedTopics", required=False):
            g["published"].pop(name, None) if isinstance(name, str) else None
            g["subscribed"].pop(name, None) if isinstance(name, str) else None
        for name in wire.items(m, "removedServices", required=False):
            g["services"].pop(name, None) if isinstance(name, str) else None
        self._notify("graph")

    def _on_binary(self, frame: tuple[Any, ...]) -> None:
        kind = frame[0]
        if kind == "time":  # ("message", ...) is not reached: receive_binary takes MessageData the short way
            self.time_ns = frame[1]
        elif kind == "service_response":
            _, _sid, cid, encoding, payload = frame
            self.requests.on_response(cid, encoding, payload)

    # ================================================================== subscriptions (for the nodes)

    def add_subscription(self, sub: Subscription) -> None:
        entry = self.topics.get(sub.topic)
        if entry is None:
            entry = self.topics[sub.topic] = TopicEntry(sub.topic, self.bad.report)
        entry.subs.append(sub)
        entry.rebuild()
        if entry.sid is None:
            self._subscribe(entry)
        else:
            self._refit(entry)

    def remove_subscription(self, sub: Subscription) -> None:
        entry = self.topics.get(sub.topic)
        if entry is None or sub not in entry.subs:
            return
        entry.subs.remove(sub)
        entry.rebuild()
        if entry.subs:
            self._refit(entry)
            return
        del self.topics[sub.topic]
        if entry.sid is not None:
            self.subs.pop(int(entry.sid), None)
            self._send("unsubscribe", sub.topic, wire.unsubscribe_frame([int(entry.sid)]))
            entry.sid = None

    def _subscribe(self, entry: TopicEntry) -> None:
        ch = self.by_topic.get(entry.topic)
        if ch is None or self._write is None:
            return  # sent when the channel is advertised
        decode: Decode | None
        try:
            decode = self.codecs.decoder(ch.encoding, ch.schema_name, ch.schema_encoding, ch.schema, offset=13)
        except CodecError as exc:
            self.stats.undecodable += 1
            log.warning("not subscribing to %s on %s: %s", entry.topic, self.url, exc)
            self._on_status({"level": 1, "message": f"{entry.topic}: {exc}"})
            if not entry.raw_subs:
                return
            decode = None  # the payload bytes still reach raw consumers (the recorder): delivery.py
        sid = next(self._sub_ids)
        if self._send("subscribe", entry.topic, wire.subscribe_frame([(sid, ch.id)])):
            entry.sid = str(sid)  # TopicEntry keeps rosbridge's string ids
            entry.decoder = decode
            self.subs[sid] = (entry, frame_decoder(entry, ch, decode))

    def _refit(self, entry: TopicEntry) -> None:  # its consumers changed: raw or decoded delivery (delivery.py)
        ch = self.by_topic.get(entry.topic)
        if entry.sid is not None and ch is not None and int(entry.sid) in self.subs:
            self.subs[int(entry.sid)] = (entry, frame_decoder(entry, ch, entry.decoder))

    # ================================================================== publishing

    def add_publisher(self, pub: Publisher) -> None:
        adv = self.adverts.get(pub.topic)
        if adv is None:
            adv = self.adverts[pub.topic] = ClientChannel(next(self._chan_ids), pub.topic, pub.type)
        elif adv.type.split("/")[-1] != pub.type.split("/")[-1]:
            raise BridgeError(f"{pub.topic} is already advertised as {adv.type}, not {pub.type}")
        adv.pubs.append(pub)
        adv.latch = any(p.latch for p in adv.pubs)
        if not adv.active and self.server is not None:
            self._advertise(adv)

    def _advertise(self, adv: ClientChannel) -> None:
        if "clientPublish" not in self.capabilities:
            return
        encoding, schema_encoding, schema = self.codecs.publish_encoding(adv.type, self.encodings)
        try:
            adv.encode = self.codecs.encoder(encoding, adv.type)
        except (CodecError, ValueError) as exc:
            log.warning("cannot advertise %s on %s: %s", adv.topic, self.url, exc)
            return
        adv.encoding = encoding
        item: dict[str, Any] = {"id": adv.id, "topic": adv.topic, "encoding": encoding, "schemaName": adv.type}
        if schema_encoding:
            item.update(schemaEncoding=schema_encoding, schema=schema)
        adv.active = self._send("advertise", adv.topic, wire.advertise_frame([item]))
        if adv.active and adv.pending is not None:
            pending, adv.pending = adv.pending, None
            self._write_message(adv, pending)

    def remove_publisher(self, pub: Publisher) -> None:
        adv = self.adverts.get(pub.topic)
        if adv is None or pub not in adv.pubs:
            return
        adv.pubs.remove(pub)
        if adv.pubs:
            adv.latch = any(p.latch for p in adv.pubs)
            return
        del self.adverts[pub.topic]
        if adv.active:
            self._send("unadvertise", adv.topic, wire.unadvertise_frame([adv.id]))

    def publish(self, pub: Publisher, msg: dict[str, Any]) -> bool:
        if self.guard.reason is not None:
            raise self.guard.refuse(f"publishing on {pub.topic}")
        if self.server is not None and "clientPublish" not in self.capabilities:
            raise BridgeError(f"publishing on {pub.topic}: this Foxglove server does not accept messages from "
                              "clients (no clientPublish capability)")
        adv = self.adverts[pub.topic]
        msg = enforce(self.envelope, adv.type, msg, self.stats)  # the robot's safety envelope (envelope.py)
        if self._write is not None and adv.active:
            data = self._write_message(adv, msg, pub)
            if data is None:
                return False
            pub.sent += 1
            return True
        if adv.latch:
            adv.pending = msg
            return True
        pub.dropped += 1
        adv.dropped += 1
        self.stats.dropped_while_down += 1
        return False

    def _write_message(self, adv: ClientChannel, msg: dict[str, Any], pub: Any = None) -> bytes | None:
        assert adv.encode is not None
        data = adv.head + adv.encode(msg)
        if not self.guard.admit_op("publish", adv.topic):
            return None
        if pub is not None and pub.max_age is not None and self._command is not None:
            if not self._command(data, pub, pub.max_age):
                pub.dropped += 1
                self.stats.stale_dropped += 1
                return None
        elif self._write is not None:
            self._write(data)
        return data

    def stale_in_queue(self, pub: Any) -> None:
        pub.sent -= 1
        pub.dropped += 1
        self.stats.stale_dropped += 1

    def node_closed(self, node: Node) -> None:
        if self.nodes.get(node.id) is node:
            del self.nodes[node.id]

    def _guard_changed(self, view_only: bool) -> None:
        if self._write is None:
            return
        if view_only:
            for op in self.guard.withdrawals():
                adv = self.adverts.get(op["topic"])
                if adv is not None and adv.active:
                    self._send("unadvertise", adv.topic, wire.unadvertise_frame([adv.id]))
                    adv.active = False
            return
        for adv in self.adverts.values():
            if not adv.active and self.server is not None:
                self._advertise(adv)

    # ================================================================== the connection graph

    def watch_graph(self) -> None:
        if not self.graph_wanted:
            self.graph_wanted = True
            if self.server is not None and "connectionGraph" in self.capabilities:
                self._send("subscribeConnectionGraph", "", wire.graph_frame())
