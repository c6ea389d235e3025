"""``cbor-raw`` payloads: the message serialized by the server's ROS, decoded by the one type system.

A cbor-raw frame's ``msg`` is ``{secs, nsecs, bytes}``: ``bytes`` is the serialized message -- ROS 1
serialization (little-endian, no 4-byte length prefix) from a ROS 1 server, CDR from a ROS 2 one
(``cdrdecode.py`` says which).  The server's own ``/rosapi/message_details`` typedefs describe exactly what
it serialized, so a :class:`RawDecoder` learns them into a :class:`~rcon_core.msgs.TypeRegistry` of its own
(it works for any type the server knows, including types no local registry has) and decodes with the
registry's ``deserialize_ros1`` / ``deserialize_cdr`` (``msgs/ros1_wire.py``, ``msgs/cdr.py``; the bridge
has no decoder of its own).  Given the application's registry (``RawDecoder.over(registry)``) it decodes
with that one.  Output is the same dict shape as the JSON path (``uint8[]``/``char[]`` as ``bytes``, times
as ``{"secs", "nsecs"}`` on ROS 1), with real NaN/Inf.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from rcon_core.msgs import TypeRegistry, UnknownTypeError, names
from rcon_core.msgs.ros1_wire import Ros1Codec

from .errors import ProtocolError


def has_fixed_arrays(type_name: str, typedefs: list[dict[str, Any]]) -> bool:
    """True when the type (or any nested type) has a fixed-size array field (``fieldarraylen`` > 0)."""
    return any(any(n > 0 for n in td.get("fieldarraylen", [])) for td in typedefs)


class RawDecoder:
    """Decodes cbor-raw payloads of the types it learned: ``decode(type_name, data) -> dict``."""

    __slots__ = ("registry", "ros2", "_known", "_own", "_readers", "_codec")

    def __init__(self, ros2: bool = False, registry: Any = None) -> None:
        self.ros2 = ros2
        self.registry: Any = registry  # created on the first typedefs when not given
        self._own = registry is None  # the registry is this decoder's: only it changes it
        self._known: set[str] = set()
        #: per type name, ``read(data) -> dict`` compiled once (own ROS 1 registry only: it changes only here)
        self._readers: dict[str, Callable[[Any], dict[str, Any]]] = {}
        self._codec: Ros1Codec | None = None

    @classmethod
    def over(cls, registry: Any) -> RawDecoder:
        """A decoder that uses ``registry`` (which knows its types already) as it is."""
        return cls(bool(getattr(registry, "ros2", False)), registry)

    def knows(self, type_name: str) -> bool:
        return names.pkg_type(type_name) in self._known

    def add_typedefs(self, typedefs: list[dict[str, Any]]) -> None:
        """Learn rosapi typedefs (raises ProtocolError when they describe no message)."""
        if self.registry is None:
            self.registry = TypeRegistry.empty(ros2=self.ros2)
        try:
            learned = self.registry.add_typedefs(typedefs)
        except ValueError as exc:
            raise ProtocolError(f"typedefs the decoder cannot use: {exc}") from None
        self._readers.clear()
        self._codec = None
        self._known.update(names.pkg_type(n) for n in learned)
        self._known.update(names.pkg_type(td["type"]) for td in typedefs if isinstance(td.get("type"), str))

    def decode(self, type_name: str, data: bytes | bytearray | memoryview) -> dict[str, Any]:
        try:
            read = self._readers.get(type_name)
            if read is not None:
                return read(data)
            reg = self.registry
            if reg is None:
                raise UnknownTypeError(type_name)
            if self.ros2:
                return reg.deserialize_cdr(type_name, data)
            if not self._own:
                return reg.deserialize_ros1(type_name, data)
            if self._codec is None:
                self._codec = Ros1Codec(reg)
            read = self._readers[type_name] = self._codec.reader(reg.resolve(type_name))
            return read(data)
        except UnknownTypeError:
            raise ProtocolError(f"cbor-raw {type_name}: no typedef for {type_name}") from None
        except (ValueError, RecursionError) as exc:
            raise ProtocolError(f"cbor-raw {type_name}: cannot deserialize {len(data)} bytes ({exc})") from None
