"""Server-side subscriptions and the payload decoders behind them (part of the session).

Decisions:

* A topic's shared subscription (``topics.py``) is made to match what its nodes want: when the merged
  options change, the client subscribes with a new id, then unsubscribes the old one (no gap).
* ``compression="cbor"`` on a type with fixed-size arrays is switched to ``"cbor-raw"``, because rosbridge's
  cbor encoder sends nothing for those types (Imu, Odometry, NavSatFix, ...).  Either needs the type and its
  typedefs first (``/rosapi/topic_type``, ``/rosapi/message_details``); when they cannot be had the topic is
  subscribed without compression.
* ``png`` is never asked of a ROS 2 server: rosbridge 2.1.0 cannot serialize its own png frame and sends
  *nothing* -- it even silences a plain subscription to the same topic on that connection
  (``rosbridge-ros2-2.1.0/publish_png.jsonl:1-8``).  A png subscription waits for the server's ROS
  (``client.rosapi_profile()``, once per connection) and becomes plain JSON on ROS 2.
* ``fragment_size`` never goes with a binary compression: rosbridge 2.1.0 then sends nothing at all
  (``subscribe_options.jsonl:41``), and a CBOR frame cannot be cut into text fragments anyway; the
  compression wins.  (A size the client does send stays in force for the whole connection, service
  responses included, ``subscribe_options.jsonl:29-35``; the read loop joins whatever arrives in
  fragments, with the float ``total`` 2.x sends.)
* A switch of encoding under traffic loses nothing: until the server has the old subscription's
  unsubscribe, messages of both come (a message may come twice, never not at all); a payload of the old
  encoding is delivered as what it is (a JSON or cbor message when the topic became ``cbor-raw``; a
  ``cbor-raw`` payload decoded, for :data:`LEFTOVER_SECONDS`, when it left it), never reported as a bad
  frame (``tests/test_record_beside_widgets.py``).
* ``cbor-raw`` payloads are decoded by the one type system (``rawdecode.py``): CDR for types learned from a
  ROS 2 server (sniffed per payload when the flavour is unknown, ``cdrdecode.py``); else the
  application's registry (``BridgeClient(registry=...)``) when it knows the type -- it learns the server's
  typedefs in :meth:`Subscriber.typedefs` -- else a registry of the client's own, learned from the server.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Awaitable, Callable
from typing import TYPE_CHECKING, Any

from rcon_core.msgs import names

from .cdrdecode import CdrDecoder, SniffingDecoder, flavour_from_typedefs
from .errors import BridgeError, NotConnectedError, ServiceError
from .rawdecode import RawDecoder, has_fixed_arrays

if TYPE_CHECKING:
    from .topics import TopicEntry

log = logging.getLogger(__name__)

#: how long after a topic left ``cbor-raw`` a payload of the replaced subscription is still expected (s)
LEFTOVER_SECONDS = 2.0


class Subscriber:
    """Subscribes the session's topics on the server and picks each cbor-raw topic's decoder."""

    def __init__(self, session: Any, host: Any, spawn: Callable[[Awaitable[Any]], Any]) -> None:
        self.session = session
        self._spawn = spawn  # the shell's (shell.py): the session makes no task
        self.host = host  # rosapi, registry, ros_version (see session.Host)
        self.typedef_cache: dict[str, list[dict[str, Any]]] = {}
        self.ros1 = RawDecoder()  # cbor-raw from ROS 1 servers, learned from their typedefs
        self.cdr = CdrDecoder()  # cbor-raw from ROS 2 servers (CDR)
        self._registry_decoder: RawDecoder | None = None

    def sync(self, entry: TopicEntry) -> None:
        """Make the server-side subscription match what the nodes want (resubscribe when it changed)."""
        if not self.session.up or not entry.subs:
            return
        wanted = entry.wanted()
        if wanted == entry.sent_options:
            return
        entry.sent_options = wanted
        if wanted["compression"] in ("cbor", "cbor-raw"):
            self._spawn(self._resolve_and_subscribe(entry, wanted))
        elif wanted["compression"] == "png" and getattr(self.host, "rosapi_profile", None) is not None:
            self._spawn(self._png_unless_ros2(entry, wanted))
        else:
            self._subscribe_now(entry, wanted)

    async def _png_unless_ros2(self, entry: TopicEntry, wanted: dict[str, Any]) -> None:
        opts = dict(wanted)
        try:
            ros2 = (await self.host.rosapi_profile()).version == 2
        except Exception as exc:  # no answer: png as asked (a ROS 1 server, most likely)
            log.debug("%s: could not learn the server's ROS (%s)", entry.topic, exc)
            ros2 = False
        if ros2:
            log.info("%s: rosbridge 2.x sends nothing for png compression; subscribing as plain JSON",
                     entry.topic)
            opts["compression"] = "none"
        session = self.session
        if session.topics.get(entry.topic) is not entry or entry.sent_options is not wanted or not session.up:
            return  # superseded while we were asking the server
        self._subscribe_now(entry, opts)

    async def _resolve_and_subscribe(self, entry: TopicEntry, wanted: dict[str, Any]) -> None:
        opts = dict(wanted)
        try:
            type_name = opts.get("type") or await self.host.rosapi.topic_type(entry.topic)
            if not type_name:
                raise BridgeError(f"the server does not know the type of {entry.topic}")
            opts["type"] = type_name
            typedefs = await self.typedefs(type_name)
            if opts["compression"] == "cbor" and has_fixed_arrays(type_name, typedefs):
                log.info("%s [%s] has fixed-size arrays, which rosbridge's cbor encoder cannot send; "
                         "using cbor-raw instead", entry.topic, type_name)
                opts["compression"] = "cbor-raw"
            if opts["compression"] == "cbor-raw":
                self._learn_raw_flavour(type_name, typedefs)
        except Exception as exc:
            log.warning("%s: cannot prepare %s compression (%s); subscribing without compression",
                        entry.topic, opts["compression"], exc)
            opts["compression"] = "none"
        session = self.session
        if session.topics.get(entry.topic) is not entry or entry.sent_options is not wanted or not session.up:
            return  # superseded while we were asking the server
        self._subscribe_now(entry, opts)

    def _subscribe_now(self, entry: TopicEntry, opts: dict[str, Any]) -> None:
        if opts.get("fragment_size") and opts["compression"] in ("cbor", "cbor-raw"):
            log.info("%s: fragment_size is not sent with %s compression (rosbridge would send nothing)",
                     entry.topic, opts["compression"])
            opts = {k: v for k, v in opts.items() if k != "fragment_size"}
        sid = self.session.next_id("sub", entry.topic)
        op = {"op": "subscribe", "id": sid, "topic": entry.topic, **opts}
        was_raw = entry.raw_type
        entry.raw_type = opts["type"] if opts["compression"] == "cbor-raw" else None
        if entry.raw_type is not None:
            entry.decoder = self.raw_decoder(entry.raw_type)
            entry.leftovers_until = 0.0
        elif was_raw is not None:  # the old subscription's cbor-raw payloads may still come: decoded, a while
            entry.leftovers_until = time.monotonic() + LEFTOVER_SECONDS
            entry.leftovers_type = was_raw
        old, entry.sid = entry.sid, sid
        entry.rebuild()
        self.session.send(op)
        if old is not None:
            self.session.send({"op": "unsubscribe", "id": old, "topic": entry.topic})

    def _learn_raw_flavour(self, type_name: str, typedefs: list[dict[str, Any]]) -> None:
        """cbor-raw is CDR from a ROS 2 server: hand the typedefs to the CDR decoder when the server is (or
        its typedefs look) ROS 2; when neither tells, each payload is sniffed (``cdrdecode.py``)."""
        version = self.host.ros_version or flavour_from_typedefs(typedefs)
        if version != 1:
            self.cdr.add_typedefs(typedefs)
        key = names.pkg_type(type_name)
        if version is None:
            self.cdr.uncertain.add(key)
        else:
            self.cdr.uncertain.discard(key)

    def raw_decoder(self, type_name: str) -> Any:
        """The decoder of a cbor-raw topic of ``type_name`` (see the module docstring)."""
        if self.cdr.knows(type_name):
            if names.pkg_type(type_name) in self.cdr.uncertain:
                return SniffingDecoder(self.cdr, self._ros1_decoder(type_name))
            return self.cdr
        return self._ros1_decoder(type_name)

    def _ros1_decoder(self, type_name: str) -> RawDecoder:
        reg = self.host.registry
        if reg is not None and hasattr(reg, "deserialize_ros1"):
            try:
                known = reg.has(type_name)
            except Exception:
                known = False
            if known:
                if self._registry_decoder is None or self._registry_decoder.registry is not reg:
                    self._registry_decoder = RawDecoder(ros2=False, registry=reg)
                return self._registry_decoder
        return self.ros1

    async def typedefs(self, type_name: str) -> list[dict[str, Any]]:
        """rosapi typedefs of a message type, from the server (cached), else from the local registry."""
        key = names.pkg_type(type_name)
        cached = self.typedef_cache.get(key)
        if cached is not None:
            return cached
        registry = self.host.registry
        try:
            typedefs = await self.host.rosapi.message_details(key if "/msg/" not in type_name else type_name)
        except (ServiceError, NotConnectedError) as exc:
            if registry is None or not registry.has(type_name):
                raise
            log.info("rosapi message_details failed for %s (%s); using the local registry", type_name, exc)
            typedefs = registry.typedefs(type_name)
        if not typedefs and registry is not None and registry.has(type_name):
            typedefs = registry.typedefs(type_name)  # rosapi 2.x answers [] for what it cannot load
        if not typedefs:
            raise BridgeError(f"the server has no definition for {type_name}")
        self.typedef_cache[key] = typedefs
        try:
            self.ros1.add_typedefs(typedefs)
        except BridgeError as exc:
            log.debug("the ROS 1 decoder did not take typedefs of %s: %s", type_name, exc)
        if registry is not None and hasattr(registry, "add_typedefs"):
            try:
                registry.add_typedefs(typedefs)
            except Exception as exc:
                log.debug("registry did not take typedefs of %s: %s", type_name, exc)
        return typedefs
