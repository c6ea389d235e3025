"""The Foxglove WebSocket protocol's frames, both ways, as plain data: no I/O, no state.

Text frames are JSON objects with an ``op``; binary frames start with a one-byte opcode and carry
little-endian integers (``struct``).  :func:`parse_text` and :func:`parse_binary` turn a server frame into a
small tuple or dict, or raise :class:`WireError` with a sentence saying what was wrong (the caller counts
it and goes on); the ``*_frame`` functions build the client's frames.

Decision: what is checked on the way in
    Every field RCON reads is checked for its JSON type before use (a wrong type is a :class:`WireError`,
    never a ``KeyError`` deep in the state machine), lists are bounded by what a frame could carry, and a
    binary frame shorter than its fixed header is refused.  Fields RCON does not read are not checked: a
    newer server may add them.

Decision: two subprotocols
    ``foxglove.sdk.v1`` (the SDK's server, foxglove_bridge 3.x) and ``foxglove.websocket.v1`` (the older
    ws-protocol servers) share these frames; the SDK's names a service's schemas ``request``/``response``
    objects (``encoding``, ``schemaName``, ``schemaEncoding``, ``schema``) where the older servers give
    ``requestSchema``/``responseSchema`` text and let the encoding follow the server's
    ``supportedEncodings``.  :func:`service_schemas` reads both.
"""

from __future__ import annotations

import struct
from typing import Any

import orjson

#: the subprotocols RCON offers, preferred first; a server that picks neither speaks rosbridge
SUBPROTOCOLS = ("foxglove.sdk.v1", "foxglove.websocket.v1")

# server -> client binary opcodes
MESSAGE_DATA = 0x01
TIME = 0x02
SERVICE_CALL_RESPONSE = 0x03
FETCH_ASSET_RESPONSE = 0x04
# client -> server binary opcodes
CLIENT_MESSAGE_DATA = 0x01
SERVICE_CALL_REQUEST = 0x02

_U32 = struct.Struct("<I")
_MSG_HEAD = struct.Struct("<BIQ")  # opcode, subscription id, receive timestamp (ns)
_TIME = struct.Struct("<BQ")
_CALL_HEAD = struct.Struct("<BIII")  # opcode, service id, call id, encoding length
_CLIENT_MSG_HEAD = struct.Struct("<BI")
MAX_ID = 0xFFFFFFFF


class WireError(ValueError):
    """A frame from the server that does not follow the protocol; the text says how."""


# ============================================================================== server -> client

def parse_text(text: str | bytes) -> dict[str, Any]:
    """One JSON frame: a dict with a string ``op``."""
    try:
        m = orjson.loads(text)
    except orjson.JSONDecodeError as exc:
        raise WireError(f"text frame is not JSON ({exc})") from None
    if not isinstance(m, dict):
        raise WireError(f"text frame is a JSON {type(m).__name__}, not an object")
    if not isinstance(m.get("op"), str):
        raise WireError("text frame has no string 'op'")
    return m


def parse_binary(data: bytes | bytearray | memoryview) -> tuple[Any, ...]:
    """One binary frame: ``("message", sub_id, time_ns, payload, frame)``, ``("time", ns)``,
    ``("service_response", service_id, call_id, encoding, payload)`` or ``("asset", ...)``."""
    n = len(data)
    if n == 0:
        raise WireError("empty binary frame")
    op = data[0]
    if op == MESSAGE_DATA:
        if n < _MSG_HEAD.size:
            raise WireError(f"message data frame of {n} bytes is shorter than its 13-byte header")
        _, sub, stamp = _MSG_HEAD.unpack_from(data)
        return ("message", sub, stamp, memoryview(data)[_MSG_HEAD.size:], data)
    if op == TIME:
        if n < _TIME.size:
            raise WireError(f"time frame of {n} bytes (needs 9)")
        return ("time", _TIME.unpack_from(data)[1])
    if op == SERVICE_CALL_RESPONSE:
        if n < _CALL_HEAD.size:
            raise WireError(f"service call response of {n} bytes is shorter than its 13-byte header")
        _, sid, cid, elen = _CALL_HEAD.unpack_from(data)
        end = _CALL_HEAD.size + elen
        if end > n:
            raise WireError(f"service call response says its encoding is {elen} bytes; the frame has {n - 13}")
        try:
            encoding = bytes(data[_CALL_HEAD.size:end]).decode()
        except UnicodeDecodeError:
            raise WireError("service call response's encoding is not UTF-8") from None
        return ("service_response", sid, cid, encoding, bytes(data[end:]))
    if op == FETCH_ASSET_RESPONSE:
        return ("asset",)
    raise WireError(f"unknown binary opcode 0x{op:02x}")


def ident(value: Any, what: str) -> int:
    """A channel, subscription, service or call id: an integer in 0..2**32-1."""
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= MAX_ID:
        raise WireError(f"{what} must be an unsigned 32-bit integer, got {str(value)[:40]!r}")
    return value


def text_field(m: dict[str, Any], key: str, *, required: bool = True, default: str = "") -> str:
    value = m.get(key)
    if value is None and not required:
        return default
    if not isinstance(value, str):
        raise WireError(f"{m.get('op')}: {key!r} must be a string, got {type(value).__name__}")
    return value


def items(m: dict[str, Any], key: str, *, required: bool = True) -> list[Any]:
    value = m.get(key)
    if value is None and not required:
        return []
    if not isinstance(value, list):
        raise WireError(f"{m.get('op')}: {key!r} must be a list, got {type(value).__name__}")
    return value


def channel(c: Any) -> dict[str, Any]:
    """One entry of ``advertise``: id, topic, encoding, schemaName, schema, schemaEncoding (may be '')."""
    if not isinstance(c, dict):
        raise WireError(f"advertise: a channel is a JSON {type(c).__name__}, not an object")
    schema = c.get("schema", "")
    if not isinstance(schema, str):
        raise WireError("advertise: a channel's 'schema' must be a string")
    return {"id": ident(c.get("id"), "advertise: channel id"), "topic": text_field(c, "topic"),
            "encoding": text_field(c, "encoding"), "schemaName": text_field(c, "schemaName", required=False),
            "schemaEncoding": text_field(c, "schemaEncoding", required=False), "schema": schema}


def service_schemas(s: dict[str, Any], encodings: list[str]) -> dict[str, dict[str, str] | None]:
    """``{"request": {encoding, schemaName, schemaEncoding, schema} | None, "response": ...}`` of one
    advertised service, from either subprotocol's shape (see the module docstring)."""
    out: dict[str, dict[str, str] | None] = {}
    for part in ("request", "response"):
        obj = s.get(part)
        if isinstance(obj, dict):
            out[part] = {"encoding": text_field(obj, "encoding", required=False),
                         "schemaName": text_field(obj, "schemaName", required=False),
                         "schemaEncoding": text_field(obj, "schemaEncoding", required=False),
                         "schema": text_field(obj, "schema", required=False)}
            continue
        legacy = s.get(f"{part}Schema")
        if isinstance(legacy, str) and legacy:
            enc = encodings[0] if encodings else ""
            schema_encoding = {"ros1": "ros1msg", "cdr": "ros2msg", "json": "jsonschema"}.get(enc, "")
            stype = str(s.get("type")) if isinstance(s.get("type"), str) else ""
            name = f"{stype}_{part.capitalize()}" if "/srv/" in stype else f"{stype}{part.capitalize()}" if stype else ""
            out[part] = {"encoding": enc, "schemaName": name, "schemaEncoding": schema_encoding, "schema": legacy}
        else:
            out[part] = None
    return out


# ============================================================================== client -> server

def _json(op: dict[str, Any]) -> str:
    return orjson.dumps(op).decode()


def subscribe_frame(pairs: list[tuple[int, int]]) -> str:
    return _json({"op": "subscribe", "subscriptions": [{"id": s, "channelId": c} for s, c in pairs]})


def unsubscribe_frame(sub_ids: list[int]) -> str:
    return _json({"op": "unsubscribe", "subscriptionIds": sub_ids})


def advertise_frame(channels: list[dict[str, Any]]) -> str:
    return _json({"op": "advertise", "channels": channels})


def unadvertise_frame(channel_ids: list[int]) -> str:
    return _json({"op": "unadvertise", "channelIds": channel_ids})


def get_parameters_frame(names: list[str], request_id: str) -> str:
    return _json({"op": "getParameters", "parameterNames": names, "id": request_id})


def set_parameters_frame(params: list[dict[str, Any]], request_id: str) -> str:
    return _json({"op": "setParameters", "parameters": params, "id": request_id})


def subscribe_parameters_frame(names: list[str], subscribe: bool = True) -> str:
    op = "subscribeParameterUpdates" if subscribe else "unsubscribeParameterUpdates"
    return _json({"op": op, "parameterNames": names})


def graph_frame(subscribe: bool = True) -> str:
    return _json({"op": "subscribeConnectionGraph" if subscribe else "unsubscribeConnectionGraph"})


def message_head(channel_id: int) -> bytes:
    """The first five bytes of every client message on ``channel_id`` (the payload follows)."""
    return _CLIENT_MSG_HEAD.pack(CLIENT_MESSAGE_DATA, channel_id)


def call_frame(service_id: int, call_id: int, encoding: str, payload: bytes) -> bytes:
    enc = encoding.encode()
    return _CALL_HEAD.pack(SERVICE_CALL_REQUEST, service_id, call_id, len(enc)) + enc + payload


def message_frame(sub_id: int, stamp: int, payload: bytes) -> bytes:
    """A server's message data frame (what the tests' fake servers and the fuzz test send)."""
    return _MSG_HEAD.pack(MESSAGE_DATA, sub_id, stamp) + payload


def time_frame(stamp: int) -> bytes:
    return _TIME.pack(TIME, stamp)


def response_frame(service_id: int, call_id: int, encoding: str, payload: bytes) -> bytes:
    enc = encoding.encode()
    return _CALL_HEAD.pack(SERVICE_CALL_RESPONSE, service_id, call_id, len(enc)) + enc + payload
