"""TypeRegistry: every message, service and action type a connection knows, in one place.

A registry starts from the shared standard definitions (rosbags' store for the flavour plus the bundled
``defs/``) and learns more from ``.msg`` text (:meth:`TypeRegistry.add_msg_text`) or from a server's
rosapi answers (:meth:`TypeRegistry.add_typedefs`). What one registry learns never leaks into another.
"""

from __future__ import annotations

import base64
from collections.abc import Callable
from typing import Any

from . import names
from . import text as msg_text
from .actions import actionlib_wrappers
from .cdr import CdrCodec
from .cdr import serializer as cdr_serializer
from .deftext import definition_text
from .fielddefs import TIME_TYPES, Constant, FieldDef, MsgDef, is_binary, primitive
from .parse import parse_interface
from .ros1_wire import Ros1Codec
from .sources import standard_defs, standard_interfaces
from .typed import TypedFactory
from .typedefs import build_typedefs, parse_typedefs

__all__ = ["TypeRegistry", "UnknownTypeError"]


class UnknownTypeError(KeyError, ValueError):
    """A type the registry does not know."""

    def __str__(self) -> str:  # KeyError quotes its argument; we want plain text
        return str(self.args[0]) if self.args else "unknown type"


class TypeRegistry:
    """Message types for one ROS flavour (``ros2=False``: ROS 1 wire conventions)."""

    def __init__(self, ros2: bool = False, *, empty: bool = False) -> None:
        self.ros2 = ros2
        self._defs: dict[str, MsgDef] = {} if empty else dict(standard_defs(ros2))
        self._interfaces: set[str] = set() if empty else set(standard_interfaces(ros2))
        self._cache: dict[Any, Any] = {}  # resolve() answers
        self._typed: Any = None
        self._codecs: dict[str, Any] = {}  # "ros1" / "cdr" -> a codec with its own per-type cache

    # ------------------------------------------------------------------ construction
    @classmethod
    def standard(cls, ros2: bool = False) -> TypeRegistry:
        """rosbags' standard types for the flavour plus the bundled definitions (std_srvs, rosapi, ...)."""
        return cls(ros2)

    @classmethod
    def empty(cls, ros2: bool = False) -> TypeRegistry:
        """A registry that knows nothing yet (learns through add_typedefs / add_msg_text)."""
        return cls(ros2, empty=True)

    @property
    def time_fields(self) -> tuple[str, str]:
        """The two keys of a time value on the wire: ``secs, nsecs`` (ROS 1) or ``sec, nanosec``."""
        return ("sec", "nanosec") if self.ros2 else ("secs", "nsecs")

    def _changed(self) -> None:
        self._cache.clear()
        self._typed = None
        self._codecs.clear()

    def _ros1(self) -> Ros1Codec:
        codec = self._codecs.get("ros1")
        if codec is None:
            codec = self._codecs["ros1"] = Ros1Codec(self)
        return codec

    def _cdr(self) -> CdrCodec:
        codec = self._codecs.get("cdr")
        if codec is None:
            codec = self._codecs["cdr"] = CdrCodec(self)
        return codec

    def add(self, md: MsgDef) -> None:
        """Add (or replace) one message definition."""
        self._defs[md.name] = md
        part = names.service_part(md.name) or names.action_part(md.name)
        if part:
            parent = part[0]
            suffixes = names.SERVICE_PARTS if "/srv/" in parent else names.ACTION_PARTS
            if all(f"{parent}_{s}" in self._defs for s in suffixes):
                self._interfaces.add(parent)
        self._changed()

    def add_msg_text(self, name: str, text: str) -> list[str]:
        """Register a definition from its text: ``.msg``, or ``.srv``/``.action`` when ``name`` says so.

        Returns the canonical names added (the parts, for a service or action).
        """
        canonical = names.normalize(name)
        defs = parse_interface(canonical, text)
        if "/action/" in canonical and not self.ros2:
            defs += actionlib_wrappers(canonical)
        for md in defs:
            self._defs[md.name] = md
        if "/msg/" not in canonical:
            self._interfaces.add(canonical)
        self._changed()
        return [md.name for md in defs]

    def add_typedefs(self, typedefs: Any, root: str | None = None) -> list[str]:
        """Learn the types in a rosapi ``message_details`` (or service details) answer.

        ``typedefs`` is the list (or the whole ``{"typedefs": [...]}`` answer). ``root`` gives the
        canonical name for the first entry, e.g. ``"pkg/srv/Foo_Request"`` for a ROS 1
        ``service_request_details`` answer, whose first entry is spelled ``pkg/FooRequest``.
        Returns the canonical names learned. Existing definitions are replaced: the server is right.
        """
        root = names.normalize(root) if root else None
        defs = parse_typedefs(typedefs, root)
        for md in defs:
            self._defs[md.name] = md
            part = names.service_part(md.name) or names.action_part(md.name)
            if part:
                parent = part[0]
                suffixes = names.SERVICE_PARTS if "/srv/" in parent else names.ACTION_PARTS
                if all(f"{parent}_{s}" in self._defs for s in suffixes):
                    self._interfaces.add(parent)
        self._changed()
        return [md.name for md in defs]

    # ------------------------------------------------------------------ lookup
    def resolve(self, name: str) -> str:
        """The canonical name of a known message type (any spelling); raises :class:`UnknownTypeError`."""
        key = ("resolve", name)
        hit = self._cache.get(key)
        if hit is not None:
            return hit
        for cand in names.candidates(name):
            if cand in self._defs:
                self._cache[key] = cand
                return cand
        for cand in names.candidates(name):
            if cand in self._interfaces:
                raise UnknownTypeError(
                    f"{name!r} is a {'service' if '/srv/' in cand else 'action'}, not a message; "
                    f"ask for one of its parts (e.g. {names.part_name(cand, 'request' if '/srv/' in cand else 'goal')!r})"
                )
        raise UnknownTypeError(f"unknown message type {name!r}")

    def resolve_interface(self, name: str) -> str:
        """Canonical name of a known service or action (``std_srvs/SetBool`` -> ``std_srvs/srv/SetBool``)."""
        for cand in names.candidates(name):
            if cand in self._interfaces:
                return cand
        raise UnknownTypeError(f"unknown service or action type {name!r}")

    def has(self, name: str) -> bool:
        """True when ``name`` (any spelling) is a known message, service part, service or action."""
        try:
            cands = names.candidates(name)
        except ValueError:
            return False
        return any(c in self._defs or c in self._interfaces for c in cands)

    def has_service(self, name: str) -> bool:
        try:
            return any(c in self._interfaces and "/srv/" in c for c in names.candidates(name))
        except ValueError:
            return False

    def msgdef(self, name: str) -> MsgDef:
        """The :class:`MsgDef` of a message type."""
        return self._defs[self.resolve(name)]

    def fields(self, name: str) -> list[FieldDef]:
        """The fields of a message type, in order."""
        return list(self.msgdef(name).fields)

    def constants(self, name: str) -> dict[str, Any]:
        """``{NAME: value}`` of the message's constants, in definition order."""
        return {c.name: c.value for c in self.msgdef(name).constants}

    def constant_defs(self, name: str) -> list[Constant]:
        return list(self.msgdef(name).constants)

    def names(self) -> list[str]:
        """Canonical names of every known message (including service and action parts)."""
        return sorted(self._defs)

    def interfaces(self) -> list[str]:
        """Canonical names of every known service and action."""
        return sorted(self._interfaces)

    def service_part_name(self, name: str, part: str) -> str:
        """Canonical name of ``part`` ("request"|"response") of the service ``name``."""
        if part not in ("request", "response"):
            raise ValueError(f"part must be 'request' or 'response', got {part!r}")
        srv = self.resolve_interface(name)
        return names.part_name(srv, part)

    def action_part_name(self, name: str, part: str) -> str:
        """Canonical name of ``part`` ("goal"|"result"|"feedback") of the action ``name``."""
        if part not in ("goal", "result", "feedback"):
            raise ValueError(f"part must be 'goal', 'result' or 'feedback', got {part!r}")
        act = self.resolve_interface(name)
        return names.part_name(act, part)

    def dependencies(self, name: str) -> list[str]:
        """Every message type ``name`` uses, depth first, each once (not including ``name``)."""
        out: list[str] = []
        root = self.resolve(name)
        seen = {root}

        def visit(n: str) -> None:
            for f in self._defs[n].fields:
                if not f.is_builtin and f.base not in seen:
                    seen.add(f.base)
                    if f.base not in self._defs:
                        raise UnknownTypeError(f"{n} uses {f.base}, which is unknown")
                    out.append(f.base)
                    visit(f.base)

        visit(root)
        return out

    def wire_name(self, name: str) -> str:
        """How this flavour's server spells a type (``pkg/Type`` on ROS 1, canonical on ROS 2)."""
        canonical = names.normalize(name)
        return canonical if self.ros2 else names.to_ros1(canonical)

    # ------------------------------------------------------------------ rosapi typedefs
    def typedefs(self, name: str) -> list[dict[str, Any]]:
        """rosapi ``message_details`` answer for ``name``: the list of typedef dicts."""
        return build_typedefs(self, self.resolve(name))

    def service_typedefs(self, name: str, part: str) -> list[dict[str, Any]]:
        """rosapi ``service_request_details`` / ``service_response_details`` for the service ``name``."""
        return build_typedefs(self, self.service_part_name(name, part))

    # ------------------------------------------------------------------ defaults
    def default_value(self, f: FieldDef) -> Any:
        """The zero value of one field, in the wire shape."""
        if f.array_len is not None:
            if is_binary(f.base, f.array_len):
                return base64.b64encode(bytes(f.array_len)).decode("ascii")
            if f.array_len == 0:
                return []
            return [self._scalar_default(f.base) for _ in range(f.array_len)]
        return self._scalar_default(f.base)

    def _scalar_default(self, base: str) -> Any:
        if base in TIME_TYPES:
            a, b = self.time_fields
            return {a: 0, b: 0}
        p = primitive(base, self.ros2)
        if p is not None:
            return {"bool": False, "int": 0, "float": 0.0, "string": ""}[p.kind]
        return self.default(base)

    def default(self, name: str) -> dict[str, Any]:
        """An all-zero message in the wire shape.

        Numbers are 0 / 0.0, bools False, strings "", time ``{secs: 0, nsecs: 0}`` (ROS 1) or
        ``{sec: 0, nanosec: 0}`` (ROS 2), variable arrays ``[]``, fixed arrays filled with zeros.
        ``uint8``/``char`` arrays are base64 text as on the JSON wire: ``""`` when variable, N zero
        bytes encoded when fixed (``values.as_bytes`` turns either into bytes).
        """
        md = self.msgdef(name)
        return {f.name: self.default_value(f) for f in md.fields}

    # ------------------------------------------------------------------ definition text
    def definition_text(self, name: str, dependencies: bool = False) -> str:
        """``.msg``-style text of a message, or of a service/action (parts separated by ``---``).

        With ``dependencies=True`` every type it uses follows, each once, after a ``====`` line and
        ``MSG: pkg/Type`` (like ``gendeps --cat`` and rosapi's ``typedefs_full_text``).
        """
        return definition_text(self, name, dependencies)

    # ------------------------------------------------------------------ typed objects, text, wire
    def _typed_factory(self) -> Any:
        if self._typed is None:
            self._typed = TypedFactory(self)
        return self._typed

    def typed(self, name: str) -> type:
        """An attrs class for the message, built at run time and cached."""
        return self._typed_factory().cls(self.resolve(name))

    def structure(self, msg: dict[str, Any], name: str) -> Any:
        """A wire-shape dict -> an instance of :meth:`typed` (missing fields take defaults)."""
        return self._typed_factory().structure(msg, self.resolve(name))

    def unstructure(self, obj: Any) -> dict[str, Any]:
        """An instance of a :meth:`typed` class -> a wire-shape dict."""
        return self._typed_factory().unstructure(obj)

    def from_text(self, name: str, text: str, *, finite: bool = True) -> dict[str, Any]:
        """YAML or JSON typed by a person -> a complete wire-shape message; raises MessageTextError.
        NaN and infinity are refused unless ``finite=False``."""
        return msg_text.from_text(self, name, text, finite=finite)

    def to_text(self, msg: dict[str, Any]) -> str:
        """A message as YAML for a person to edit; :meth:`from_text` reads it back unchanged."""
        return msg_text.to_text(msg)

    def complete(self, name: str, msg: Any, *, finite: bool = False) -> dict[str, Any]:
        """Check and fill a (partial) message dict; raises MessageTextError at the first problem.
        ``finite``: refuse NaN and infinity too."""
        return msg_text.complete(self, name, msg, finite=finite)

    def validate(self, name: str, msg: Any, *, finite: bool = False) -> list[Any]:
        """Every problem in a message dict, as :class:`~rcon_core.msgs.text.Problem` (empty when fine)."""
        return msg_text.validate(self, name, msg, finite=finite)

    def serialize_ros1(self, name: str, msg: dict[str, Any]) -> bytes:
        """ROS 1 binary serialization (no 4-byte length prefix)."""
        return self._ros1().serialize(self.resolve(name), msg)

    def serializer(self, name: str, ros2: bool) -> Callable[[dict[str, Any]], bytes]:
        """``serialize(msg) -> bytes`` of the message ``name`` compiled once: CDR (``ros2``) or ROS 1, for a
        caller that writes many messages of one type (the flight recorder). Made with the definitions known
        now; it keeps them when the registry learns others."""
        resolved = self.resolve(name)
        if ros2:
            return cdr_serializer(self._cdr(), resolved)
        return self._ros1().serializer(resolved)

    def deserialize_ros1(self, name: str, data: bytes | bytearray | memoryview) -> dict[str, Any]:
        """ROS 1 binary -> wire-shape dict (``uint8[]`` as bytes, NaN stays NaN)."""
        return self._ros1().deserialize(self.resolve(name), data)

    def serialize_cdr(self, name: str, msg: dict[str, Any]) -> bytes:
        """ROS 2 CDR (with its 4-byte header), as rosbridge 2.x sends ``cbor-raw``; see ``cdr.py``."""
        return self._cdr().serialize(self.resolve(name), msg)

    def cdr_codec(self) -> CdrCodec:
        """The CDR codec of this registry's current definitions (``cdr.frame_reader`` compiles readers on it)."""
        return self._cdr()

    def deserialize_cdr(self, name: str, data: bytes | bytearray | memoryview) -> dict[str, Any]:
        """ROS 2 CDR -> wire-shape dict (``uint8[]`` as bytes, NaN stays NaN)."""
        return self._cdr().deserialize(self.resolve(name), data)

    def __contains__(self, name: object) -> bool:
        return isinstance(name, str) and self.has(name)

    def __repr__(self) -> str:
        return f"TypeRegistry(ros2={self.ros2}, {len(self._defs)} messages, {len(self._interfaces)} interfaces)"

