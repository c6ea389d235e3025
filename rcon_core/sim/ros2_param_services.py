"""Every ROS 2 node's own parameter services, on the sim's nodes in --ros2 mode.

A ROS 2 node serves ``<node>/describe_parameters``, ``get_parameter_types``, ``get_parameters``,
``list_parameters``, ``set_parameters`` and ``set_parameters_atomically`` (``rcl_interfaces/srv/*``), so
they are in ``/rosapi/services`` and callable through rosbridge like any service (rosbridge_suite's own
tests read ``/rosbridge_websocket/get_parameters`` with ``names: ["actual_port"]`` to find the port).
Unlike rosapi's ``set_param``, ``set_parameters`` says whether the node took each value and why not.
They work on the same parameters as rosapi (``ros2_params.NodeParameters``).

Values are ``rcl_interfaces/msg/ParameterValue``: ``type`` (0 not set, 1 bool, 2 integer, 3 double,
4 string, 5 byte array, 6 bool array, 7 integer array, 8 double array, 9 string array) and the one field
of that type; a name the node lacks reads back as type 0.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from .ros2_params import kind_of

if TYPE_CHECKING:
    from .ros2_params import NodeParameters
    from .server import SimServer

_TYPES = {"bool": 1, "integer": 2, "double": 3, "string": 4, "bool_array": 6, "integer_array": 7,
          "double_array": 8, "string_array": 9}
_FIELDS = {1: "bool_value", 2: "integer_value", 3: "double_value", 4: "string_value", 5: "byte_array_value",
           6: "bool_array_value", 7: "integer_array_value", 8: "double_array_value", 9: "string_array_value"}
_EMPTY = {"type": 0, "bool_value": False, "integer_value": 0, "double_value": 0.0, "string_value": "",
          "byte_array_value": [], "bool_array_value": [], "integer_array_value": [], "double_array_value": [],
          "string_array_value": []}
SERVICES = ("describe_parameters", "get_parameter_types", "get_parameters", "list_parameters", "set_parameters",
            "set_parameters_atomically")


def to_parameter_value(value: Any) -> dict[str, Any]:
    """A Python value as ``rcl_interfaces/msg/ParameterValue`` (``None``: not set)."""
    out = dict(_EMPTY)
    if value is None:
        return out
    code = _TYPES[kind_of(value)]
    out["type"] = code
    out[_FIELDS[code]] = value
    return out


def from_parameter_value(pv: Any) -> tuple[bool, Any]:
    """``(True, value)`` from a ParameterValue dict; ``(False, None)`` for type 0 (not set) or a bad one."""
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


class NodeParameterServices:
    """The six services of one node."""

    def __init__(self, params: NodeParameters, node: str) -> None:
        self.params = params
        self.node = node

    def _names(self) -> list[str]:
        return [n.split(":", 1)[1] for n in self.params.names(self.node)]

    def get_parameters(self, args: dict[str, Any]) -> dict[str, Any]:
        values = []
        for name in args.get("names") or []:
            found, value = self.params.get(self.node, str(name))
            values.append(to_parameter_value(value if found else None))
        return {"values": values}

    def get_parameter_types(self, args: dict[str, Any]) -> dict[str, Any]:
        return {"types": [v["type"] for v in self.get_parameters(args)["values"]]}

    def describe_parameters(self, args: dict[str, Any]) -> dict[str, Any]:
        out = []
        for name, pv in zip(args.get("names") or [], self.get_parameters(args)["values"], strict=True):
            out.append({"name": str(name), "type": pv["type"], "description": "", "additional_constraints": "",
                        "read_only": False, "dynamic_typing": False, "floating_point_range": [],
                        "integer_range": []})
        return {"descriptors": out}

    def list_parameters(self, args: dict[str, Any]) -> dict[str, Any]:
        prefixes = [str(p) for p in args.get("prefixes") or []]
        names = [n for n in self._names()
                 if not prefixes or any(n == p or n.startswith(p + ".") for p in prefixes)]
        groups = sorted({n.rsplit(".", 1)[0] for n in names if "." in n})
        return {"result": {"names": names, "prefixes": groups}}

    def _set_one(self, parameter: Any) -> dict[str, Any]:
        if not isinstance(parameter, dict) or not isinstance(parameter.get("name"), str):
            return {"successful": False, "reason": "a parameter needs a name"}
        name = parameter["name"]
        ok, value = from_parameter_value(parameter.get("value"))
        if not ok:
            if self.params.delete(self.node, name):
                return {"successful": True, "reason": ""}
            return {"successful": False, "reason": f"parameter {name} is not declared"}
        problem = self.params.set(self.node, name, value)
        return {"successful": problem is None, "reason": problem or ""}

    def set_parameters(self, args: dict[str, Any]) -> dict[str, Any]:
        return {"results": [self._set_one(p) for p in args.get("parameters") or []]}

    def set_parameters_atomically(self, args: dict[str, Any]) -> dict[str, Any]:
        parameters = args.get("parameters") or []
        for p in parameters:  # check every one first: all or nothing
            ok, value = from_parameter_value(p.get("value") if isinstance(p, dict) else None)
            name = p.get("name") if isinstance(p, dict) else None
            found, current = self.params.get(self.node, str(name))
            if not found or (ok and kind_of(current) != kind_of(value)):
                return {"result": {"successful": False, "reason": f"cannot set {name}: not declared or another type"}}
        for p in parameters:
            self._set_one(p)
        return {"result": {"successful": True, "reason": ""}}


def add_parameter_services(server: SimServer, node: str) -> None:
    """Register ``node``'s six parameter services (the ROS 2 counterpart of the ROS 1 logger services)."""
    params = getattr(server.rosapi, "node_params", None)
    if params is None:
        return
    services = NodeParameterServices(params, node)
    types = {"describe_parameters": "DescribeParameters", "get_parameter_types": "GetParameterTypes",
             "get_parameters": "GetParameters", "list_parameters": "ListParameters",
             "set_parameters": "SetParameters", "set_parameters_atomically": "SetParametersAtomically"}
    for name in SERVICES:
        server.add_service(f"{node}/{name}", f"rcl_interfaces/srv/{types[name]}", node, getattr(services, name))
