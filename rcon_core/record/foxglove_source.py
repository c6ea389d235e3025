"""Recording a Foxglove robot: each channel's own schema and encoding, each payload's bytes unchanged.

``RobotRecorder`` (``ingest.py``) learns a rosbridge robot's topics from rosapi and takes ``cbor-raw``
bytes; a Foxglove server says everything in its advertisement, so :class:`FoxgloveRecorder` keeps the
rest of the recorder (operator events, ``/rcon/link``, which topics, the sink) and changes only where the
topics, schemas and bytes come from.  :func:`recorder_for` and :func:`wait_profile` are the hooks the CLI
(``rcon record``) and the app (``session.py``) call for any client.

Decisions:

* **The advertisement is the schema.** A channel is written with the schema name, schema encoding and
  message encoding it was advertised with (``ros2msg``/``cdr``, ``ros1msg``/``ros1``, ``ros2idl``/``cdr``,
  ``jsonschema``/``json``, ``protobuf``/``protobuf``, ``flatbuffer``/``flatbuffer``: MCAP takes each as it
  is).  The schema's bytes are the advertised text as UTF-8, except for the binary schema encodings
  (``protobuf``: a ``FileDescriptorSet``; ``flatbuffer``: a ``.bfbs``), which the protocol sends in base64
  and MCAP stores decoded.  A channel without a schema (plain ``json``) is written without one.
* **The payload is the message.** The recorder subscribes with ``raw=True``; the Foxglove session then
  hands it each MessageData payload as the server sent it (``foxglove/delivery.py``), never decoded, so
  even a channel RCON cannot decode (``flatbuffer``) is recorded.
* **Times as on rosbridge.** ``log_time`` is when the recorder got the message (wall clock, ns);
  ``publish_time`` the message's own header stamp, read from the bytes, for a ROS type whose first field is
  a ``std_msgs/Header`` (``schema.stamp_reader``), else ``log_time``.  (The MessageData timestamp is the
  server's own log time; like the ``cbor-raw`` time on rosbridge it is not written.)
* **The profile.** ``ros2`` when every channel to be recorded is ROS 2 CDR (``ros2msg``/``ros2idl`` with
  ``cdr``: ``rosbags`` reads such a file), ``ros1`` when every one is ROS 1, else none (a file of mixed
  encodings, as the MCAP spec allows; the ``mcap`` reader, Foxglove and Lichtblick read it).  Which
  channels: the named topics, or with ``--all`` and in the app every channel the robot advertises when the
  recording starts (:func:`wait_profile` waits up to ``ADVERTISE_WAIT`` for the first advertisement).  The
  recorder's own channels (``/rcon/operator/...``, ``/rcon/link``) are ROS 2 CDR, or ROS 1 in a ``ros1``
  file.  A channel advertised later whose encoding breaks the file's profile is left out and said in
  ``problems`` (the profile is the file's promise to its readers).
* **The catalogue changes.** A topic is recorded as soon as it is advertised (the session's catalogue
  events trigger discovery; no polling).  A channel advertised again with another schema (the server
  restarted with another version of the type) is said in ``problems`` and its messages left out: the
  file's channel has the old schema.
"""

from __future__ import annotations

import asyncio
import base64
import binascii
import logging
import time
from typing import Any

from rcon_core.bridge.topics import RawPayload

from .ingest import RobotRecorder, _Topic
from .schema import Schema, stamp_reader

log = logging.getLogger(__name__)

__all__ = ["FoxgloveRecorder", "recorder_for", "channel_schema", "profile_of", "wait_profile", "ADVERTISE_WAIT"]

#: seconds to wait, once connected, for a Foxglove server's first advertisement (the profile needs it)
ADVERTISE_WAIT = 2.0
#: schema encodings whose schema the protocol sends in base64
BINARY_SCHEMAS = ("protobuf", "flatbuffer")
_ROS2 = ("ros2msg", "ros2idl")
NOT_ADVERTISED = "(not advertised)"


def is_foxglove(client: Any) -> bool:
    return getattr(client, "protocol", "rosbridge") == "foxglove"


def channel_schema(ch: Any) -> Schema:
    """The MCAP schema of a Foxglove channel (see the module docstring); ValueError for a binary schema
    that is not base64."""
    if ch.schema_encoding in BINARY_SCHEMAS:
        try:
            data = base64.b64decode(ch.schema, validate=True)
        except (binascii.Error, ValueError) as exc:
            raise ValueError(f"its {ch.schema_encoding} schema is not base64 ({exc})") from None
    else:
        data = ch.schema.encode()
    name = ch.schema_name if ch.schema_encoding else ""
    return Schema(name, ch.schema_encoding, data, ch.encoding, "advertisement")


def _flavour(ch: Any) -> str:
    if ch.encoding == "cdr" and ch.schema_encoding in _ROS2:
        return "ros2"
    if ch.encoding == "ros1" and ch.schema_encoding == "ros1msg":
        return "ros1"
    return ""


def profile_of(channels: list[Any]) -> str:
    """``ros2``, ``ros1`` or "" for a file of these channels (see the module docstring)."""
    kinds = {_flavour(ch) for ch in channels}
    return kinds.pop() if len(kinds) == 1 else ""


async def wait_profile(client: Any, topics: list[str] | None = None, wait: float = ADVERTISE_WAIT) -> str:
    """The profile of a recording of ``client``: of ``topics`` (None: every channel it advertises).  On a
    connected Foxglove link waits up to ``wait`` s for the advertisement (of every named topic); a link not
    up yet gives "" (any encoding fits)."""
    session = client.session
    if not getattr(client, "connected", False):
        return ""

    def known() -> bool:
        return all(t in session.by_topic for t in topics) if topics else bool(session.channels)

    if not known():
        changed = asyncio.Event()

        def on_event(kind: str) -> None:
            if kind == "catalog":
                changed.set()

        session.listeners.append(on_event)
        deadline = time.monotonic() + wait
        try:
            while not known() and (left := deadline - time.monotonic()) > 0:
                changed.clear()
                try:
                    await asyncio.wait_for(changed.wait(), left)
                except TimeoutError:
                    break
        finally:
            session.listeners.remove(on_event)
    chans = [session.by_topic[t] for t in topics if t in session.by_topic] if topics else list(
        session.channels.values())
    return profile_of(chans) if chans else ""


def recorder_for(client: Any, sink: Any, **options: Any) -> RobotRecorder:
    """The recorder for ``client``'s protocol (``RobotRecorder`` on rosbridge, :class:`FoxgloveRecorder`
    on Foxglove); ``options`` as ``RobotRecorder`` takes them (``ros2`` is the flavour of RCON's own
    channels: on Foxglove it follows the sink's profile)."""
    if is_foxglove(client):
        options["ros2"] = sink.profile != "ros1"
        return FoxgloveRecorder(client, sink, **options)
    return RobotRecorder(client, sink, **options)


class FoxgloveRecorder(RobotRecorder):
    """``RobotRecorder`` for a Foxglove link (see the module docstring)."""

    _discovering: asyncio.Task[Any] | None = None

    async def start(self) -> None:
        session = self.client.session
        session.listeners.append(self._catalog_changed)
        self._undo.append(lambda: session.listeners.remove(self._catalog_changed)
                          if self._catalog_changed in session.listeners else None)
        await super().start()

    def stop(self) -> None:
        if self._discovering is not None:
            self._discovering.cancel()
            self._discovering = None
        super().stop()

    def _catalog_changed(self, kind: str) -> None:
        """New channels: record the wanted ones now (loop thread; one discovery at a time)."""
        if kind != "catalog" or self._node is None:
            return
        if self._discovering is None or self._discovering.done():
            self._discovering = asyncio.get_running_loop().create_task(self.discover())

    async def _listing(self) -> dict[str, str]:
        """The advertised topics, and the wanted ones not advertised yet (never asked of rosapi: there is
        none; ``_add_topic`` waits for their advertisement)."""
        listing = {topic: ch.type for topic, ch in self.client.session.by_topic.items()}
        for name in self.wanted:
            listing.setdefault(name, NOT_ADVERTISED)
        return listing

    async def _add_topic(self, name: str, type_name: str) -> None:
        ch = self.client.session.by_topic.get(name)
        if ch is None or self._node is None:
            self._say(f"{name}: not advertised by the robot yet; recorded once it is")
            return
        profile = self.sink.profile
        if profile and _flavour(ch) != profile:
            self.topics[name] = _Topic(name, ch.type)  # known, not recorded: said once
            self._say(f"{name}: not recorded: its messages are {ch.encoding} with a {ch.schema_encoding or 'no'} "
                      f"schema, and this file was started as a {profile} recording (its profile); record it "
                      "into a file of its own")
            return
        try:
            schema = channel_schema(ch)
        except ValueError as exc:
            self.topics[name] = _Topic(name, ch.type)
            self._say(f"{name}: not recorded: {exc}")
            return
        t = _Topic(name, ch.type)
        t.schema = schema
        t.stamp = self._stamp_reader(ch)
        self.topics[name] = t
        self.sink.add_channel(name, schema.name, schema.encoding, schema.data, schema.message_encoding,
                              {"rcon.robot": self.robot} if self.robot else {})
        self._subs[name] = self._node.subscribe(name, self._payload_receiver(t, ch.schema_name), raw=True)

    def _stamp_reader(self, ch: Any) -> Any:
        flavour = _flavour(ch)
        if flavour == "" or ch.schema_encoding == "ros2idl":
            return None
        codecs = self.client.session.codecs
        try:
            type_name = codecs.learn(ch.schema_name, ch.schema_encoding, ch.schema)
        except ValueError:
            return None
        return stamp_reader(type_name, codecs.ros2 if flavour == "ros2" else codecs.ros1, flavour == "ros2")

    def _payload_receiver(self, t: _Topic, schema_name: str) -> Any:
        write = self.sink.write
        name, stamp = t.name, t.stamp

        def received(msg: Any) -> None:
            now = time.time_ns()
            if msg.__class__ is not RawPayload or msg.type != schema_name:
                t.failed += 1
                if t.failed == 1:
                    what = (f"advertised again as {msg.type}" if isinstance(msg, RawPayload) else
                            "delivered decoded")
                    self._say(f"{name}: messages left out: the channel was {what}, and the file's channel has "
                              f"the schema {schema_name}")
                return
            data = msg.data
            write(name, now, (stamp(data) or now) if stamp is not None else now, data)

        return received
