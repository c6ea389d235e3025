"""ROS 2 parameters through each node's own parameter services, not rosapi's parameter calls.

Decision: on ROS 2, ``client.params`` talks to the nodes
    Every ROS 2 node serves ``<node>/list_parameters``, ``get_parameters`` and ``set_parameters``
    (``rcl_interfaces/srv/*``), reachable through rosbridge like any service and listed by
    ``/rosapi/services`` (``rosbridge-ros2-2.1.0/rosapi.jsonl:1``, ``:34-38``).  rosapi 2.1.0's own
    parameter calls are what hurts: ``get_param_names`` dies or hangs on a stock 2.1.0, ``has_param`` of a
    missing name and every ``delete_param`` kill rosapi, ``get_param`` of a node that does not exist blocks
    every rosapi call for 5 s, and ``set_param`` answers success even when the node refused the value
    (``rosapi.jsonl:40-56``, ``:64-76``; ``rosapi_guard.py``).  The node's services answer typed values
    (``ParameterValue``: ``type`` 0 means "not set"), say whether a value was taken and why not, and work
    the same on every release.  Only services ``/rosapi/services`` lists are called, so a node without
    parameter services is never asked (a call to it would hold up the connection, ``services.jsonl:20-25``).

Values: ``ParameterValue`` types 1 bool, 2 integer, 3 double, 4 string, 5 byte array (a JSON list: byte[]
is octet, which rosbridge leaves a list, ``rosapi.jsonl:35``), 6-9 bool/integer/double/string arrays.
Deleting a parameter is setting it to type 0 (the node undeclares it, or says why it will not).
"""

from __future__ import annotations

import asyncio
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .host import RosClient

_FIELDS = {1: "bool_value", 2: "integer_value", 3: "double_value", 4: "string_value", 5: "byte_array_value",
           6: "bool_array_value", 7: "integer_array_value", 8: "double_array_value", 9: "string_array_value"}
#: at most this many nodes asked at once while listing
CONCURRENT_NODES = 8


def to_parameter_value(value: Any) -> dict[str, Any]:
    """A Python value as ``rcl_interfaces/msg/ParameterValue`` (None: type 0, not set)."""
    if value is None:
        return {"type": 0}
    if isinstance(value, bool):
        return {"type": 1, "bool_value": value}
    if isinstance(value, int):
        return {"type": 2, "integer_value": value}
    if isinstance(value, float):
        return {"type": 3, "double_value": value}
    if isinstance(value, str):
        return {"type": 4, "string_value": value}
    if isinstance(value, bytes | bytearray):
        return {"type": 5, "byte_array_value": list(value)}
    if isinstance(value, list | tuple):
        items = list(value)
        for code, kind in ((6, bool), (7, int), (8, float), (9, str)):
            if items and all(isinstance(v, kind) and (kind is bool or not isinstance(v, bool)) for v in items):
                return {"type": code, _FIELDS[code]: items}
        if items and all(isinstance(v, int | float) and not isinstance(v, bool) for v in items):
            return {"type": 8, "double_array_value": [float(v) for v in items]}
    raise ValueError(f"a ROS 2 parameter cannot hold {value!r}")


def from_parameter_value(pv: Any) -> tuple[bool, Any]:
    """``(True, value)`` from a ParameterValue; ``(False, None)`` for type 0 (not set) or a bad one."""
    if not isinstance(pv, dict):
        return False, None
    code = pv.get("type")
    field = _FIELDS.get(code) if isinstance(code, int) else None
    if field is None:
        return False, None
    value = pv.get(field)
    if code == 5 and isinstance(value, bytes | bytearray):
        value = list(value)
    return True, value


class NodeParams:
    """Parameter access through the nodes' services (see the module docstring)."""

    def __init__(self, client: RosClient) -> None:
        self._client = client

    async def _listed(self) -> set[str]:
        return set((await self._client.call_service("/rosapi/services", {})).get("services", []))

    async def _call(self, node: str, service: str, args: dict[str, Any], listed: set[str] | None = None) -> Any:
        name = f"{node}/{service}"
        if listed is None:
            listed = await self._listed()
        if name not in listed:
            raise LookupError(f"{node} has no parameter services (no {name} on the robot)")
        values = await self._client.call_service(name, args)
        if not isinstance(values, dict):
            raise ValueError(f"{name} answered {values!r:.80}")
        return values

    async def names(self) -> list[str]:
        """``<node>:<param>`` of every node that serves ``list_parameters``."""
        listed = await self._listed()
        nodes = sorted(s[: -len("/list_parameters")] for s in listed if s.endswith("/list_parameters"))
        gate = asyncio.Semaphore(CONCURRENT_NODES)

        async def one(node: str) -> list[str]:
            async with gate:
                try:
                    answer = await self._call(node, "list_parameters", {}, listed)
                except Exception:  # one node that does not answer hides nobody else
                    return []
            found = (answer.get("result") or {}).get("names") or []
            return [f"{node}:{n}" for n in found if isinstance(n, str)]

        out: list[str] = []
        for group in await asyncio.gather(*(one(n) for n in nodes)):
            out += group
        return out

    async def get(self, node: str, param: str) -> tuple[bool, Any]:
        """``(found, value)``; a node without parameter services has no parameters."""
        try:
            answer = await self._call(node, "get_parameters", {"names": [param]})
        except LookupError:
            return False, None
        values = answer.get("values") or []
        return from_parameter_value(values[0]) if values else (False, None)

    async def set(self, node: str, param: str, value: Any) -> tuple[bool, str]:
        """``(taken, the node's reason when not)``; ``value`` None deletes (undeclares) the parameter."""
        answer = await self._call(node, "set_parameters",
                                  {"parameters": [{"name": param, "value": to_parameter_value(value)}]})
        results = answer.get("results") or [{}]
        first = results[0] if isinstance(results[0], dict) else {}
        return bool(first.get("successful")), str(first.get("reason") or "")
