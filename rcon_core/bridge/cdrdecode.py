"""``cbor-raw`` from a ROS 2 rosbridge: the payload is CDR (``rcon_core.msgs.cdr``), not ROS 1 serialization.

The decoder learns the server's own ``message_details`` typedefs (rosapi 2.x spelling: ``pkg/Type``, IDL
base names, ``builtin_interfaces/Time``) into a private ROS 2 :class:`~rcon_core.msgs.TypeRegistry`, so it
decodes any type the server knows, as the ROS 1 ``RawDecoder`` does.  :func:`flavour_from_typedefs` tells
from typedefs alone which ROS wrote them when the field types give it away (``double`` and
``builtin_interfaces/Time`` are ROS 2 spellings; ``float64`` and ``time`` are ROS 1 ones).  When neither
the typedefs nor ``client.ros_version`` tell (``std_msgs/String`` has only a ``string``), no question is
sent to the server: :class:`SniffingDecoder` reads each payload as CDR when it starts with a CDR header and
decodes as such, else as ROS 1.
"""

from __future__ import annotations

from typing import Any

from .errors import ProtocolError

_ROS2_BASES = {"double", "float", "boolean", "octet", "wstring"}
_ROS1_BASES = {"float64", "float32", "bool", "time", "duration"}


def flavour_from_typedefs(typedefs: list[dict[str, Any]]) -> int | None:
    """2 or 1 when the typedefs' field types show which ROS described them, else None."""
    for td in typedefs:
        for ftype in td.get("fieldtypes", []):
            if not isinstance(ftype, str):
                continue
            if ftype in _ROS2_BASES or ftype.startswith("builtin_interfaces/"):
                return 2
            if ftype in _ROS1_BASES:
                return 1
    return None


class CdrDecoder:
    """Decodes cbor-raw CDR payloads of the types whose typedefs it was given."""

    def __init__(self) -> None:
        self._registry: Any = None
        self._known: set[str] = set()
        self.uncertain: set[str] = set()  # types whose server flavour is not known (see SniffingDecoder)

    @staticmethod
    def _short(name: str) -> str:
        parts = name.split("/")
        return f"{parts[0]}/{parts[-1]}" if len(parts) == 3 else name

    def knows(self, type_name: str) -> bool:
        return self._short(type_name) in self._known

    def add_typedefs(self, typedefs: list[dict[str, Any]]) -> None:
        if self._registry is None:
            from rcon_core.msgs import TypeRegistry

            self._registry = TypeRegistry.empty(ros2=True)
        for name in self._registry.add_typedefs(typedefs):
            self._known.add(self._short(name))
        for td in typedefs:
            if isinstance(td.get("type"), str):
                self._known.add(self._short(td["type"]))

    def decode(self, type_name: str, data: bytes | bytearray | memoryview) -> dict[str, Any]:
        if self._registry is None:
            raise ProtocolError(f"cbor-raw {type_name}: no typedefs for CDR decoding")
        try:
            return self._registry.deserialize_cdr(type_name, data)
        except ValueError as exc:
            raise ProtocolError(f"cbor-raw {type_name}: {exc}") from None


class SniffingDecoder:
    """For a type whose server flavour is unknown: CDR when the payload has a CDR header and decodes as
    CDR, else the ROS 1 decoder."""

    __slots__ = ("cdr", "ros1")

    def __init__(self, cdr: CdrDecoder, ros1: Any) -> None:
        self.cdr = cdr
        self.ros1 = ros1

    def decode(self, type_name: str, data: bytes | bytearray | memoryview) -> dict[str, Any]:
        head = bytes(data[:4])
        if head in (b"\x00\x01\x00\x00", b"\x00\x00\x00\x00"):
            try:
                return self.cdr.decode(type_name, data)
            except ProtocolError:
                pass
        return self.ros1.decode(type_name, data)
