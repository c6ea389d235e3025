"""Message definitions for recordings: the schema a channel is written with, and learning types back.

A recording is only as good as its definitions: Foxglove, Lichtblick and ``rosbags`` decode a channel
from its schema alone. Where each comes from, best first:

1. the robot's own text -- rosapi's ``topics_and_raw_types`` gives every topic's full definition
   (``typedefs_full_text``, ``gendeps --cat`` style, comments included; ``rosapi.jsonl:44``), written
   unchanged;
2. the robot's ``message_details`` typedefs, learned into a registry and written as text;
3. the standard definitions RCON knows (``rosbags``' store and the bundled ones).

A type with none of them cannot be written as ``ros1``/``cdr`` bytes: its channel is written as JSON
(``message_encoding`` ``json``, no schema) and the recorder says so.

Schema records follow the MCAP registry: profile ``ros1`` with ``ros1msg`` schemas named ``pkg/Type``,
``ros2`` with ``ros2msg`` schemas named ``pkg/msg/Type``; the text is the root definition followed by
each dependency after a line of 80 ``=`` and ``MSG: name``.
"""

from __future__ import annotations

import logging
import re
import struct
from typing import Any

from rcon_core.msgs import TypeRegistry, names

log = logging.getLogger(__name__)

__all__ = ["SEPARATOR", "Schema", "learn_full_text", "schema_for", "stamp_reader", "OPERATOR_TYPE",
           "OPERATOR_DEFINITION", "operator_type"]

SEPARATOR = "=" * 80
_BLOCK_RE = re.compile(r"^={10,}\s*\n\s*MSG:\s*(\S+)\s*\n", re.M)

#: the type of RCON's operator channels (``/rcon/operator/...``): what the operator's side sent
OPERATOR_TYPE = "rcon_msgs/OperatorEvent"
OPERATOR_DEFINITION = """\
# What the operator's side of RCON sent to a robot, or got back for it (the flight recorder).
string robot    # the robot's name in the workspace (its URL for rcon record)
string widget   # the widget instance id, or the panel, it came from
string kind     # publish, call, response, goal, feedback, result, cancel, param
string name     # the topic, service, action or parameter
string type     # its message, service or action type ("" when not known)
string outcome  # sent, dropped, refused: ..., ok, error: ..., or the goal's outcome
string data     # the message, request, answer, goal, feedback, result or value, as JSON
"""

_TIME_DEFS = {
    "builtin_interfaces/Time": "int32 sec\nuint32 nanosec\n",
    "builtin_interfaces/Duration": "int32 sec\nuint32 nanosec\n",
}


def operator_type(ros2: bool) -> str:
    return names.to_ros2(OPERATOR_TYPE) if ros2 else names.to_ros1(OPERATOR_TYPE)


class Schema:
    """What a channel is written with: ``name``, ``encoding`` (ros1msg / ros2msg / "" for JSON),
    ``data`` (the definition text) and the channel's ``message_encoding`` (ros1 / cdr / json)."""

    __slots__ = ("name", "encoding", "data", "message_encoding", "source")

    def __init__(self, name: str, encoding: str, data: bytes, message_encoding: str, source: str) -> None:
        self.name = name
        self.encoding = encoding
        self.data = data
        self.message_encoding = message_encoding
        self.source = source  #: "robot text", "robot typedefs", "standard" or "none"

    def __repr__(self) -> str:
        return f"<Schema {self.name} {self.encoding or 'json'} from {self.source}>"


def _with_time_defs(text: str) -> str:
    """ROS 2 text that uses ``builtin_interfaces/Time`` gets its definition appended (as rosbag2 does)."""
    for name, body in _TIME_DEFS.items():
        if re.search(rf"\b{re.escape(name)}\b", text) and f"MSG: {name}" not in text:
            text = text.rstrip("\n") + f"\n\n{SEPARATOR}\nMSG: {name}\n{body}"
    return text


def schema_for(type_name: str, ros2: bool, registry: TypeRegistry, full_text: str = "",
               from_robot: bool = False) -> Schema:
    """The schema of ``type_name``: the robot's ``full_text`` when given, else the registry's text
    (``from_robot``: the registry learned it from the robot's typedefs), else a JSON channel."""
    name = names.to_ros2(type_name) if ros2 else names.to_ros1(type_name)
    enc, menc = ("ros2msg", "cdr") if ros2 else ("ros1msg", "ros1")
    if full_text.strip():
        text = _with_time_defs(full_text) if ros2 else full_text
        return Schema(name, enc, text.encode(), menc, "robot text")
    try:
        text = registry.definition_text(type_name, dependencies=True)
    except (KeyError, ValueError):
        return Schema(name, "", b"", "json", "none")
    if ros2:
        text = _with_time_defs(text)
    return Schema(name, enc, text.encode(), menc, "robot typedefs" if from_robot else "standard")


def split_full_text(root: str, text: str) -> list[tuple[str, str]]:
    """``[(name, text), ...]``: the root definition and each ``MSG:`` block of a full definition text."""
    parts: list[tuple[str, str]] = []
    matches = list(_BLOCK_RE.finditer(text))
    first_end = matches[0].start() if matches else len(text)
    parts.append((root, text[:first_end]))
    for i, m in enumerate(matches):
        end = matches[i + 1].start() if i + 1 < len(matches) else len(text)
        parts.append((m.group(1), text[m.end():end]))
    return parts


def learn_full_text(registry: TypeRegistry, root: str, text: str) -> list[str]:
    """Teach ``registry`` every type of a full definition text (a schema, a bag's ``msgdef``); the
    dependencies first so the root resolves. Returns the canonical names learned. Raises ValueError when
    a block cannot be read."""
    learned: list[str] = []
    for name, body in reversed(split_full_text(root, text)):
        if names.normalize(name) in ("builtin_interfaces/msg/Time", "builtin_interfaces/msg/Duration"):
            continue  # RCON's time base type, never a message of its own
        try:
            learned += registry.add_msg_text(name, body)
        except Exception as exc:
            raise ValueError(f"cannot read the definition of {name}: {exc}") from None
    return learned


def stamp_reader(type_name: str, registry: TypeRegistry, ros2: bool) -> Any:
    """A function ``data -> ns or 0``: the header stamp of a serialized message whose first field is a
    ``std_msgs/Header``, read from the bytes without decoding them (ROS 1: after ``seq``; CDR: after the
    4-byte encapsulation header); None for types without one."""
    try:
        fields = registry.fields(type_name)
    except (KeyError, ValueError):
        return None
    if not fields or fields[0].base != "std_msgs/msg/Header" or fields[0].array_len is not None:
        return None
    offset = 4  # ROS 1: uint32 seq; CDR: the encapsulation header
    unpack = struct.Struct("<iI").unpack_from

    def read(data: bytes) -> int:
        try:
            sec, nsec = unpack(data, offset)
        except struct.error:
            return 0
        if sec <= 0 or nsec >= 1_000_000_000:
            return 0
        return sec * 1_000_000_000 + nsec

    return read


def truncated(registry: TypeRegistry, type_name: str, text: str) -> bool:
    """Whether a file's definition of a type ``registry`` knows has only some of its fields (seen in real
    rosbag2 files, whose ``message_definitions`` table can hold a placeholder such as ``uint8 level`` for
    ``rcl_interfaces/msg/Log``): such a text would decode garbage, the known definition is used instead."""
    if not registry.has(type_name):
        return False
    from rcon_core.msgs.parse import parse_interface

    root = split_full_text(type_name, text)[0][1]
    try:
        mine = {f.name for f in parse_interface(names.normalize(type_name), root)[0].fields}
    except Exception:  # noqa: BLE001 - text that cannot be read is not to be trusted either
        return True
    known = {f.name for f in registry.fields(type_name)}
    return mine < known
