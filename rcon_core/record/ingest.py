"""``RobotRecorder``: one robot's link into a recording -- its topics and what the operator sent.

Runs on the bridge loop thread (``start``/``stop``/callbacks); writing is the sink's thread
(``writer.py``). Decisions:

* **Nothing re-serialized when the robot offers raw bytes -- and the live view never disturbed.** Topics
  are subscribed with ``Node.subscribe(raw=True)``: on a topic only the recorder reads (``rcon record``,
  or a topic no widget shows) the ``cbor-raw`` payloads (ROS 1 bytes, or CDR on ROS 2) are written as they
  came. A topic a widget reads keeps the widget's encoding (``bridge/topics.py``: raw consumers choose the
  compression only when alone): pressing Record neither re-subscribes it nor sends its values through a
  slower decoder; the recorder serializes the messages as the widgets get them, with the robot's own
  definition (the same bytes for every ROS field type). The same when the server could not prepare
  ``cbor-raw``. A value that
  cannot be serialized is counted and said once per topic (``problems``).
* **Times.** ``log_time`` is when the recorder got the message (wall clock, ns); ``publish_time`` is the
  message's own header stamp when it has one, else ``log_time``.
* **Definitions** come from the robot first (``schema.py``); a topic whose type has none is recorded as
  JSON and said in ``problems``.
* **Which topics.** A list, or every topic the robot has (``all_topics``, minus ``exclude``), or
  (``follow_session``) every topic the client's other consumers subscribe to, looked for again every
  ``discover_every`` seconds so a topic that appears later is recorded too.
* **The operator.** The client's operator tap (``bridge/tap.py``) is written on ``/rcon/operator/<kind>``
  as ``rcon_msgs/OperatorEvent`` (robot, widget, name, type, outcome and the data as JSON); the app's own
  read-only rosapi queries (``canvas.port.READ_ONLY_SERVICES``) are not the operator's and are left out.
* **The link.** Every change of the link's state is written on ``/rcon/link`` (``std_msgs/String``:
  "connected", "reconnecting"...), so a gap in the topics is explained in the file; recording goes on
  across drops (the subscriptions are restored by the client).
"""

from __future__ import annotations

import asyncio
import logging
import re
import time
from typing import Any

import orjson

from rcon_core.bridge.tap import OperatorEvent
from rcon_core.bridge.topics import RawPayload
from rcon_core.canvas.port import READ_ONLY_SERVICES
from rcon_core.msgs import TypeRegistry, names

from .schema import (
    OPERATOR_DEFINITION,
    OPERATOR_TYPE,
    learn_full_text,
    operator_type,
    schema_for,
    stamp_reader,
)
from .writer import McapSink

log = logging.getLogger(__name__)

__all__ = ["RobotRecorder", "OPERATOR_PREFIX", "LINK_TOPIC", "operator_registry"]

OPERATOR_PREFIX = "/rcon/operator/"
LINK_TOPIC = "/rcon/link"
#: topics RCON itself writes: never subscribed on the robot
OWN_TOPICS = re.compile(r"^/rcon/(operator/|link$)")


def operator_registry(ros2: bool) -> TypeRegistry:
    reg = TypeRegistry.standard(ros2=ros2)
    reg.add_msg_text(OPERATOR_TYPE, OPERATOR_DEFINITION)
    return reg


def _json_default(value: Any) -> Any:
    if isinstance(value, bytes | bytearray | memoryview):
        import base64

        return base64.b64encode(bytes(value)).decode()
    return repr(value)[:200]


class _Topic:
    __slots__ = ("name", "type", "schema", "stamp", "encode", "failed")

    def __init__(self, name: str, type_name: str) -> None:
        self.name = name
        self.type = type_name
        self.schema: Any = None
        self.stamp: Any = None
        self.encode: Any = None
        self.failed = 0


class RobotRecorder:
    """Record one robot (see the module docstring). ``robot``: its name, written with each operator event."""

    def __init__(self, client: Any, sink: McapSink, *, ros2: bool, robot: str = "", topics: list[str] | None = None,
                 types: dict[str, str] | None = None, all_topics: bool = False, exclude: str | None = None,
                 operator: bool = True, discover_every: float = 2.0, registry: TypeRegistry | None = None,
                 follow_session: bool = False) -> None:
        self.client = client
        self.sink = sink
        self.ros2 = ros2
        self.robot = robot
        self.wanted = list(topics or [])
        self.known_types = dict(types or {})
        self.all_topics = all_topics
        self.exclude = re.compile(exclude) if exclude else None
        self.operator = operator
        self.discover_every = discover_every
        #: also record every topic the client's other nodes subscribe to (the app: what its widgets
        #: receive, the topics they read beside their binding included), looked for every discover_every s
        self.follow_session = follow_session
        self.registry = registry if registry is not None else operator_registry(ros2)
        if not self.registry.has(OPERATOR_TYPE):
            self.registry.add_msg_text(OPERATOR_TYPE, OPERATOR_DEFINITION)
        self.topics: dict[str, _Topic] = {}
        #: what went wrong, in words, once each (types without definitions, values not serializable)
        self.problems: list[str] = []
        self.events = 0  #: operator events written
        self._node: Any = None
        self._subs: dict[str, Any] = {}
        self._undo: list[Any] = []
        self._task: asyncio.Task[Any] | None = None
        self._full_texts: dict[str, str] = {}
        self._op_encode: Any = None

    # ------------------------------------------------------------------ lifecycle (loop thread)

    async def start(self) -> None:
        self._node = self.client.node(f"rcon-recorder-{id(self):x}")
        self._add_fixed_channels()
        state = getattr(self.client, "state", None)
        self._on_state(state)
        if hasattr(self.client, "add_state_listener"):
            self._undo.append(self.client.add_state_listener(self._on_state))
        if self.operator:
            self._undo.append(self.client.session.tap.add(self._on_operator))
        await self.discover()
        if (self.all_topics or self.follow_session) and self.discover_every > 0:
            self._task = asyncio.get_running_loop().create_task(self._rediscover())

    def stop(self) -> None:
        if self._task is not None:
            self._task.cancel()
            self._task = None
        for undo in self._undo:
            undo()
        self._undo.clear()
        if self._node is not None:
            self._node.close()
            self._node = None
        self._subs.clear()

    async def _rediscover(self) -> None:
        while True:
            await asyncio.sleep(self.discover_every)
            try:
                await self.discover()
            except Exception as exc:  # noqa: BLE001 - the link may be down; try again later
                log.debug("topic discovery failed: %s", exc)

    # ------------------------------------------------------------------ topics

    def add_topics(self, topics: dict[str, str]) -> None:
        """Record these topics too (``{name: type}``; type "" = ask the robot). Loop thread."""
        for name, type_name in topics.items():
            if name not in self.wanted:
                self.wanted.append(name)
            if type_name:
                self.known_types.setdefault(name, type_name)
        if self._node is not None:
            asyncio.get_running_loop().create_task(self.discover())

    async def discover(self) -> None:
        """Find the topics to record, their types and definitions, and subscribe to the new ones."""
        if self.follow_session:
            self._follow_session()
        listing = await self._listing()
        chosen: dict[str, str] = {}
        if self.all_topics:
            for name, type_name in listing.items():
                if OWN_TOPICS.match(name) or (self.exclude is not None and self.exclude.search(name)):
                    continue
                chosen[name] = type_name
        for name in self.wanted:
            type_name = listing.get(name) or self.known_types.get(name, "")
            if not type_name:
                try:
                    type_name = await self.client.rosapi.topic_type(name) or ""
                except Exception:  # noqa: BLE001
                    type_name = ""
            if type_name:
                chosen[name] = type_name
            elif f"no type for {name}" not in " ".join(self.problems):
                self._say(f"no type for {name} yet (the robot does not list it); waiting for it")
        for name, type_name in chosen.items():
            if name not in self.topics and self._node is not None:
                await self._add_topic(name, type_name)

    def _follow_session(self) -> None:
        mine = self._node.id if self._node is not None else None
        for name, entry in list(self.client.session.topics.items()):
            if name in self.topics or name in self.wanted or OWN_TOPICS.match(name):
                continue
            subs = [s for s in entry.subs if s.node.id != mine]
            if not subs:
                continue
            self.wanted.append(name)
            type_name = next((s.type for s in subs if s.type), "")
            if type_name:
                self.known_types.setdefault(name, type_name)

    async def _listing(self) -> dict[str, str]:
        """``{topic: type}`` of the robot, learning full definitions where rosapi gives them."""
        try:
            ans = await self.client.call_service("/rosapi/topics_and_raw_types", {})
            topics, types = ans.get("topics", []), ans.get("types", [])
            texts = ans.get("typedefs_full_text", [""] * len(topics))
            for type_name, text in zip(types, texts, strict=False):
                if isinstance(text, str) and text.strip():
                    self._full_texts[names.pkg_type(type_name)] = text
            return dict(zip(topics, types, strict=False))
        except Exception as exc:  # noqa: BLE001 - older rosapi, or none: the plain list
            log.debug("topics_and_raw_types unavailable (%s); using rosapi/topics", exc)
        try:
            return dict(await self.client.rosapi.topics())
        except Exception as exc:  # noqa: BLE001
            log.debug("rosapi/topics unavailable (%s)", exc)
            return {}

    async def _add_topic(self, name: str, type_name: str) -> None:
        t = _Topic(name, type_name)
        self.topics[name] = t
        reg = self.registry
        full = self._full_texts.get(names.pkg_type(type_name), "")
        from_robot = False
        if full:
            try:
                learn_full_text(reg, type_name, full)
            except ValueError as exc:
                self._say(f"{name}: the robot's definition of {type_name} cannot be read ({exc})")
                full = ""
        if not full:
            try:
                typedefs = await self.client.rosapi.message_details(type_name)
                if typedefs:
                    reg.add_typedefs(typedefs)
                    from_robot = True
            except Exception as exc:  # noqa: BLE001
                log.debug("message_details of %s failed: %s", type_name, exc)
        t.schema = schema_for(type_name, self.ros2, reg, full, from_robot)
        if t.schema.encoding == "":
            self._say(f"{name}: no definition of {type_name} (the robot gives none and RCON does not know it); "
                      "recorded as JSON")
            t.encode = self._json
        else:
            t.encode = reg.serializer(type_name, self.ros2)
            t.stamp = stamp_reader(type_name, reg, self.ros2)
        self.sink.add_channel(name, t.schema.name, t.schema.encoding, t.schema.data, t.schema.message_encoding,
                              {"rcon.robot": self.robot} if self.robot else {})
        raw = t.schema.encoding != ""
        cb = self._receiver(t)
        self._subs[name] = self._node.subscribe(name, cb, type=type_name, raw=raw)

    @staticmethod
    def _json(msg: Any) -> bytes:
        return orjson.dumps(msg, default=_json_default, option=orjson.OPT_SERIALIZE_NUMPY)

    def _receiver(self, t: _Topic) -> Any:
        write = self.sink.write
        name = t.name

        def received(msg: Any) -> None:
            now = time.time_ns()
            if isinstance(msg, RawPayload) and t.schema.encoding:
                data = msg.data
            else:
                try:
                    data = t.encode(msg)
                except Exception as exc:  # noqa: BLE001 - a value the type cannot carry
                    t.failed += 1
                    if t.failed == 1:
                        self._say(f"{name}: a message could not be serialized as {t.type} ({exc}); such "
                                  "messages are counted and left out")
                    return
            stamp = t.stamp(data) if t.stamp is not None else 0
            write(name, now, stamp or now, data)

        return received

    # ------------------------------------------------------------------ operator and link

    def _add_fixed_channels(self) -> None:
        op = schema_for(OPERATOR_TYPE, self.ros2, self.registry)
        self._op_schema = op
        ser = self.registry.serialize_cdr if self.ros2 else self.registry.serialize_ros1
        op_type = operator_type(self.ros2)
        self._op_encode = lambda msg: ser(op_type, msg)
        if self.operator:
            for kind in ("publish", "call", "response", "goal", "feedback", "result", "cancel", "param"):
                self.sink.add_channel(OPERATOR_PREFIX + kind, op.name, op.encoding, op.data, op.message_encoding)
        s = schema_for("std_msgs/String", self.ros2, self.registry)
        self._link_encode = lambda msg: ser("std_msgs/String", msg)
        self.sink.add_channel(LINK_TOPIC, s.name, s.encoding, s.data, s.message_encoding)

    def _on_state(self, state: Any) -> None:
        if state is None:
            return
        word = getattr(state, "value", str(state))
        now = time.time_ns()
        try:
            self.sink.write(LINK_TOPIC, now, now, self._link_encode({"data": f"{self.robot or 'robot'}: {word}"}))
        except Exception:  # noqa: BLE001
            log.exception("link state not recorded")

    def _on_operator(self, ev: OperatorEvent) -> None:
        if ev.kind in ("call", "response") and ev.name in READ_ONLY_SERVICES:
            return  # the app's own questions to rosapi, not the operator's commands
        try:
            data = orjson.dumps(ev.data, default=_json_default,
                                option=orjson.OPT_SERIALIZE_NUMPY | orjson.OPT_NON_STR_KEYS).decode()
        except Exception as exc:  # noqa: BLE001 - never lose the event for its data
            data = f'"not serializable: {type(exc).__name__}"'
        msg = {"robot": self.robot, "widget": ev.node, "kind": ev.kind, "name": ev.name, "type": ev.type,
               "outcome": ev.outcome, "data": data}
        if self.sink.write(OPERATOR_PREFIX + ev.kind, ev.time_ns, ev.time_ns, self._op_encode(msg)):
            self.events += 1

    def _say(self, text: str) -> None:
        if text not in self.problems:
            self.problems.append(text)
            log.warning("record: %s", text)
