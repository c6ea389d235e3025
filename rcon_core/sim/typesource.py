"""The sim's access to message definitions (``rcon_core.msgs.TypeRegistry``), with per-type caches.

With ``plugin_types=True`` the registry also holds the types installed widget plugins contribute
(``rcon_register_types``), so a lab's widget can be tested on its own message type against the sim; with
False the sim refuses them, like a robot that does not have the lab's package.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Any

from .convert import Converter

log = logging.getLogger(__name__)


class TypeSource:
    """Typedefs, converters and cbor-raw serialization (ROS 1 or CDR) for the sim, in the flavour's spelling."""

    def __init__(self, ros2: bool, now: Callable[[], dict[str, int]], plugin_types: bool = False) -> None:
        self.ros2 = ros2
        self.plugin_types = plugin_types
        #: the names of the types the installed plugins added (filled when the registry is first used)
        self.plugin_type_names: list[str] = []
        self._now = now
        self._registry: Any = None
        self._loaded = False
        self._converters: dict[tuple[str, str], Converter | None] = {}

    @property
    def registry(self) -> Any:
        if not self._loaded:
            self._loaded = True
            try:
                from rcon_core.msgs import TypeRegistry

                self._registry = TypeRegistry.standard(ros2=self.ros2)
                if self.plugin_types:
                    from rcon_core.plugins.manager import installed_plugin_types

                    self.plugin_type_names = installed_plugin_types(self._registry)
            except Exception as exc:  # noqa: BLE001 - the sim still runs, without type checks
                log.warning("message definitions unavailable (%s); client messages are not checked", exc)
        return self._registry

    def has(self, name: str) -> bool:
        reg = self.registry
        if reg is None:
            return True
        try:
            return bool(reg.has(name))
        except Exception:  # noqa: BLE001
            return False

    def typedefs(self, name: str) -> list[dict[str, Any]] | None:
        reg = self.registry
        if reg is None:
            return None
        try:
            return reg.typedefs(name)
        except Exception:  # noqa: BLE001 - unknown type
            return None

    def service_typedefs(self, name: str, part: str) -> list[dict[str, Any]] | None:
        reg = self.registry
        if reg is None:
            return None
        try:
            return reg.service_typedefs(name, part)
        except Exception:  # noqa: BLE001 - unknown type
            return None

    def converter(self, name: str, part: str = "message") -> Converter | None:
        """A converter for a message type, or for a service's ``request``/``response`` part."""
        key = (name, part)
        if key not in self._converters:
            defs = self.typedefs(name) if part == "message" else self.service_typedefs(name, part)
            self._converters[key] = Converter(defs, self._now) if defs else None
        return self._converters[key]

    def serialize(self, name: str, msg: dict[str, Any]) -> bytes:
        """The ``cbor-raw`` payload: CDR in ROS 2 mode (as rosbridge 2.x sends it), else ROS 1
        serialization; raises when the registry cannot do it."""
        reg = self.registry
        if reg is None:
            raise RuntimeError("message definitions unavailable")
        if self.ros2:
            return bytes(reg.serialize_cdr(name, msg))
        return bytes(reg.serialize_ros1(name, msg))
