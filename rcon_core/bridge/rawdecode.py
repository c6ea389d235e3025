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

from typing import Any

from rcon_core.msgs import TypeRegistry, UnknownTypeError, names

from .errors import ProtocolError


def has_fixed_arrays(type_name: str, typedefs: list[dict[str, Any]]) -> bool:
    """True when the type (or any nested type) has a fixed-size array field (``fieldarraylen`` > 0)."""
    return any(any(n > 0 for n in td.get("fieldarraylen", [])) for td in typedefs)


class RawDecoder:
    """Decodes cbor-raw payloads of the types it learned: ``decode(type_name, data) -> dict``."""

    __slots__ = ("registry", "ros2", "_known")

    def __init__(self, ros2: bool = False, registry: Any = None) -> None:
        self.ros2 = ros2
        self.registry: Any = registry  # created on the first typedefs when not given
        self._known: set[str] = set()

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
        self._known.update(names.pkg_type(n) for n in learned)
        self._known.update(names.pkg_type(td["type"]) for td in typedefs if isinstance(td.get("type"), str))

    def decode(self, type_name: str, data: bytes | bytearray | memoryview) -> dict[str, Any]:
        reg = self.registry
        if reg is None:
            raise ProtocolError(f"cbor-raw {type_name}: no typedef for {type_name}")
        try:
            if self.ros2:
                return reg.deserialize_cdr(type_name, data)
            return reg.deserialize_ros1(type_name, data)
        except UnknownTypeError:
            raise ProtocolError(f"cbor-raw {type_name}: no typedef for {type_name}") from None
        except (ValueError, RecursionError) as exc:
            raise ProtocolError(f"cbor-raw {type_name}: cannot deserialize {len(data)} bytes ({exc})") from None
