"""A Foxglove channel's bytes to RCON's message dicts and back, by the channel's encoding and schema.

Decision: which encodings and schemas
    ``cdr`` with a ``ros2msg`` schema and ``ros1`` with a ``ros1msg`` schema are read with RCON's own
    codecs (``rcon_core.msgs.cdr``, ``ros1_wire``) after the schema text -- the server's own ``.msg`` text,
    each nested type after a line of ``=`` and ``MSG: pkg/Type`` -- is learned into the client's
    registry (the server is right about its types); the dicts have the same shape as rosbridge's
    ``cbor-raw`` path gives, so every widget reads them unchanged.  ``json`` is parsed with ``orjson``
    (the schema, ``jsonschema`` or none, is kept for the topic list).  ``protobuf`` schemas (a binary
    ``FileDescriptorSet``, base64 in the advertisement: Foxglove's own types such as
    ``foxglove.CompressedImage``) are read with the ``protobuf`` package: fields by their proto names,
    ``bytes`` fields as ``bytes``, ``google.protobuf.Timestamp`` as ``{"sec", "nsec"}``.  ``flatbuffer``
    messages of Foxglove's own schemas are read with the classes Foxglove publishes
    (``foxglove-schemas-flatbuffer``: ``flatbuf.py``) into the same dicts as the protobuf ones; any other
    flatbuffer schema and any other encoding are listed with their type and refused at subscribe time in
    words (:class:`CodecError`), never delivered as garbage.

Decision: publishing and calling
    A client channel uses ``cdr`` (with the type's ``ros2msg`` text) when the server supports it and the
    type is known, else ``ros1``, else ``json``; a service request uses the encoding its advertisement
    names (or the server's first supported encoding).
"""

from __future__ import annotations

import base64
from collections.abc import Callable
from typing import Any

import orjson

from rcon_core.msgs import TypeRegistry, foreign, names
from rcon_core.msgs.cdr import frame_reader
from rcon_core.msgs.parse import parse_msg, split_full_text

Decode = Callable[[Any], dict[str, Any]]
Encode = Callable[[dict[str, Any]], bytes]


class CodecError(ValueError):
    """A channel or service whose encoding or schema RCON cannot read; the text says which and why."""


def type_name(schema_name: str, schema_encoding: str) -> str:
    """The type as RCON names it: ROS schemas in the canonical ``pkg/msg/Type`` spelling; a JSON channel's
    as ``rcon_core.msgs.foreign.json_type_name`` says; others (protobuf full names) as sent."""
    if schema_encoding in ("ros2msg", "ros1msg", "ros2idl") and schema_name:
        try:
            return names.normalize(schema_name)
        except ValueError:
            return schema_name
    if schema_encoding in ("jsonschema", ""):
        return foreign.json_type_name(schema_name)
    return schema_name


class Codecs:
    """The client's decoders and encoders, one registry per ROS flavour, protobuf descriptors per schema."""

    def __init__(self) -> None:
        self.ros2 = TypeRegistry.standard(ros2=True)
        self.ros1 = TypeRegistry.standard(ros2=False)
        self._learned: dict[tuple[str, str], str] = {}  # (schema name, text) -> canonical name
        self._proto: dict[tuple[str, str], Any] = {}

    def learn(self, schema_name: str, schema_encoding: str, schema: str) -> str:
        """Learn a ``ros2msg``/``ros1msg`` schema text; returns the canonical type name."""
        key = (schema_name, schema)
        known = self._learned.get(key)
        if known is not None:
            return known
        name = type_name(schema_name, schema_encoding)
        reg = self.ros2 if schema_encoding == "ros2msg" else self.ros1
        if schema.strip() or not reg.has(name):  # an empty text is an empty message, unless RCON knows the type
            try:
                for part, text in split_full_text(name, schema):
                    reg.add(parse_msg(names.normalize(part), text))  # every block is a message (or a service half)
            except ValueError as exc:
                raise CodecError(f"cannot read the {schema_encoding} schema of {schema_name}: {exc}") from None
        self._learned[key] = name
        return name

    def decoder(self, encoding: str, schema_name: str, schema_encoding: str, schema: str, offset: int = 0) -> Decode:
        """``decode(data) -> dict`` for one channel, of the message that starts ``offset`` bytes into
        ``data`` (the session passes whole MessageData frames: 13); raises :class:`CodecError` for what RCON
        cannot read."""
        if encoding == "cdr" and schema_encoding in ("ros2msg", ""):
            name = self.learn(schema_name, "ros2msg", schema)
            reg2 = self.ros2
            if not reg2.has(name):
                raise CodecError(f"{schema_name}: no ros2msg definition was sent and RCON does not know the type")
            return frame_reader(reg2.cdr_codec(), reg2.resolve(name), offset)  # the hot path: compiled once
        payload = self._payload_decoder(encoding, schema_name, schema_encoding, schema)
        if offset == 0:
            return payload
        if encoding == "json":
            return lambda data: _json_decode(memoryview(data)[offset:])
        return lambda data: payload(data[offset:])

    def _payload_decoder(self, encoding: str, schema_name: str, schema_encoding: str, schema: str) -> Decode:
        if encoding == "json":
            return _json_decode
        if encoding == "cdr" and schema_encoding in ("ros2msg", ""):
            return self.decoder(encoding, schema_name, schema_encoding, schema)
        if encoding == "ros1" and schema_encoding in ("ros1msg", ""):
            name = self.learn(schema_name, "ros1msg", schema)
            reg1 = self.ros1
            if not reg1.has(name):
                raise CodecError(f"{schema_name}: no ros1msg definition was sent and RCON does not know the type")
            return lambda data: reg1.deserialize_ros1(name, data)
        if encoding == "protobuf" and schema_encoding in ("protobuf", ""):
            cls = self._proto_class(schema_name, schema)
            if foreign.ros_equivalent(schema_name) is not None:  # matched as a ROS type: give its header too
                return lambda data: with_header(proto_to_dict(cls.FromString(bytes(data))))
            return lambda data: proto_to_dict(cls.FromString(bytes(data)))
        if encoding == "flatbuffer" and schema_encoding in ("flatbuffer", ""):
            from . import flatbuf  # Foxglove's own types only: foxglove-schemas-flatbuffer (flatbuf.py)

            fb = flatbuf.decoder(schema_name)
            if fb is None:
                raise CodecError(f"RCON reads flatbuffer messages of Foxglove's own schemas only (foxglove.*, "
                                 f"from foxglove-schemas-flatbuffer), not {schema_name or 'one without a name'}")
            if foreign.ros_equivalent(schema_name) is not None:
                return lambda data: with_header(fb(data))
            return fb
        raise CodecError(f"RCON cannot read {encoding!r} messages with a {schema_encoding or 'missing'!r} schema "
                         f"({schema_name or 'no schema name'})")

    def _proto_class(self, schema_name: str, schema: str) -> Any:
        key = (schema_name, schema)
        cls = self._proto.get(key)
        if cls is not None:
            return cls
        try:
            from google.protobuf import descriptor_pb2, descriptor_pool, message_factory

            fds = descriptor_pb2.FileDescriptorSet.FromString(base64.b64decode(schema))
            pool = descriptor_pool.DescriptorPool()
            for fd in fds.file:
                pool.Add(fd)
            cls = message_factory.GetMessageClass(pool.FindMessageTypeByName(schema_name))
        except Exception as exc:  # a bad descriptor set: one channel refused, in words
            raise CodecError(f"cannot read the protobuf schema of {schema_name}: {exc}") from None
        self._proto[key] = cls
        return cls

    # ------------------------------------------------------------------ out

    def publish_encoding(self, type_name_: str, supported: list[str]) -> tuple[str, str, str]:
        """``(encoding, schemaEncoding, schema)`` of a client channel for ``type_name_`` (see the docstring)."""
        name = names.normalize(type_name_) if "/" in type_name_ else type_name_
        if "cdr" in supported and self.ros2.has(name):
            return "cdr", "ros2msg", self.ros2.definition_text(name, dependencies=True)
        if "ros1" in supported and self.ros1.has(name):
            return "ros1", "ros1msg", self.ros1.definition_text(name, dependencies=True)
        return "json", "", ""

    def encoder(self, encoding: str, type_name_: str) -> Encode:
        if encoding == "json":
            return _json_encode
        name = names.normalize(type_name_)
        if encoding == "cdr":
            reg2 = self.ros2
            return lambda msg: reg2.serialize_cdr(name, reg2.complete(name, msg))
        if encoding == "ros1":
            reg1 = self.ros1
            return lambda msg: reg1.serialize_ros1(name, reg1.complete(name, msg))
        raise CodecError(f"RCON cannot write {encoding!r} messages")

    def request_codec(self, schema: dict[str, str] | None, default_encoding: str,
                      part: str) -> tuple[str, Encode | None, Decode | None]:
        """``(encoding, encode, decode)`` of one half of a service (``part``: Request or Response)."""
        encoding = (schema or {}).get("encoding") or default_encoding or "json"
        if schema is None or encoding == "json":
            return encoding, _json_encode, _json_decode
        sname, senc, text = schema["schemaName"], schema["schemaEncoding"], schema["schema"]
        if encoding in ("cdr", "ros1") and senc in ("ros2msg", "ros1msg"):
            name = self.learn(sname, senc, text)
            return encoding, self.encoder(encoding, name), self.decoder(encoding, sname, senc, text)
        return encoding, None, None


def _json_decode(data: Any) -> dict[str, Any]:
    value = orjson.loads(data)
    if not isinstance(value, dict):
        raise ValueError(f"a JSON message must be an object, got a JSON {type(value).__name__}")
    return value


def _json_encode(msg: dict[str, Any]) -> bytes:
    return orjson.dumps(msg, option=orjson.OPT_SERIALIZE_NUMPY)


def proto_to_dict(msg: Any) -> dict[str, Any]:
    """A protobuf message as a dict of its set and default fields (see the module docstring)."""
    out: dict[str, Any] = {}
    desc = msg.DESCRIPTOR
    if desc.full_name in ("google.protobuf.Timestamp", "google.protobuf.Duration"):
        return {"sec": msg.seconds, "nsec": msg.nanos}
    for field in desc.fields:
        value = getattr(msg, field.name)
        if field.message_type is not None:
            if field.message_type.GetOptions().map_entry:
                out[field.name] = {k: proto_to_dict(v) if hasattr(v, "DESCRIPTOR") else v for k, v in value.items()}
            elif _repeated(field):
                out[field.name] = [proto_to_dict(v) for v in value]
            else:
                out[field.name] = proto_to_dict(value)
        elif _repeated(field):
            out[field.name] = list(value)
        else:
            out[field.name] = value
    return out


def with_header(msg: dict[str, Any]) -> dict[str, Any]:
    """A Foxglove message with the ROS ``header`` its ROS equivalent has (from ``timestamp``, ``frame_id``)."""
    stamp = msg.get("timestamp") or {}
    msg["header"] = {"stamp": {"sec": stamp.get("sec", 0), "nanosec": stamp.get("nsec", 0)},
                     "frame_id": msg.get("frame_id", "")}
    return msg


def _repeated(field: Any) -> bool:
    flag = getattr(field, "is_repeated", None)
    if flag is not None:
        return bool(flag)
    return bool(field.label == field.LABEL_REPEATED)
