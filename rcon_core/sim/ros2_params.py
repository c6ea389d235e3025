"""ROS 2 parameters of the sim's nodes, as rosapi 2.x (rosbridge_suite 2.1.0) reaches them.

ROS 2 has no parameter server: every node owns its parameters, and rosapi names one as
``<node>:<param>`` (``/kingfisher:max_speed``; nested parameters use dots: ``/kingfisher:gps.origin_lat``).
What the sim copies from a real node and from rosapi's ``params.py``:

* A node has only the parameters it declared (every node has ``use_sim_time``).  Setting an undeclared
  parameter, or a value of another type than the declared one (an integer for a double too), is refused by
  the node -- and rosapi does not pass the refusal on: ``set_param`` answers an empty success either way.
* ``set_param`` takes JSON text (other text fails the call here; it raises inside rosapi 2.1.0); a JSON string is unwrapped first, then the text is typed the way
  ``ros2 param set`` types it (YAML: ``true`` is a bool, ``5`` an integer, ``5.0`` a double, ``[1, 2]`` an
  integer array, anything else a string).  So ``"\\"5\\""`` sets the integer 5, as on a real robot.
* ``get_param`` answers ``json.dumps(value)``; for a missing parameter or node ``json.dumps(default)``,
  where the default is the request's ``default_value`` read as JSON when it is JSON (else as text), and
  ``""`` when none was given -- so a missing parameter reads back as ``"\\"\\""``.
* A name without exactly one ``:`` is malformed: ``get_param`` answers ``value: ""`` (not JSON),
  ``has_param`` false, ``set_param`` does nothing; rosapi logs a warning.
* ``get_param_names`` lists ``<node>:<param>`` for every node except rosapi itself.

``delete_param`` takes ``<node>:<param>`` here.  (rosapi 2.1.0 reads a ``node_name`` request field that its
``DeleteParam.srv`` does not have, so on a real 2.1.0 server the call fails; the sim does what the service
definition promises: the node undeclares the parameter.)
"""

from __future__ import annotations

import copy
import json
import logging
from collections.abc import Callable
from typing import Any

import yaml

log = logging.getLogger("rcon.sim")

MALFORMED = object()


def split_name(name: str) -> tuple[str, str] | None:
    """``"/node:param"`` -> ``("/node", "param")``; None when the name is not ``<node>:<param>``."""
    parts = name.split(":")
    if len(parts) != 2:
        return None
    node, param = parts
    if not node.startswith("/"):
        node = "/" + node  # rclpy's get_absolute_node_name
    return node, param


def typed_from_text(text: str) -> Any:
    """The value ``ros2 param set`` would make of ``text`` (rclpy's ``get_parameter_value``)."""
    try:
        value = yaml.safe_load(text)
    except yaml.YAMLError:
        return text
    if isinstance(value, bool | int | float):
        return value
    if isinstance(value, list):
        for kind in (bool, int, float, str):
            if all(type(v) is kind for v in value):
                return value  # an empty list is a bool array, as in rclpy
    return text


def kind_of(value: Any) -> str:
    """The ROS 2 parameter type of a Python value: bool, integer, double, string or an array of one."""
    if isinstance(value, bool):
        return "bool"
    if isinstance(value, int):
        return "integer"
    if isinstance(value, float):
        return "double"
    if isinstance(value, list):
        inner = {kind_of(v) for v in value} or {"bool"}
        return f"{inner.pop()}_array" if len(inner) == 1 else "string_array"
    return "string"


def _flatten(prefix: str, tree: dict[str, Any], out: dict[str, Any]) -> None:
    for key, value in tree.items():
        name = f"{prefix}.{key}" if prefix else key
        if isinstance(value, dict):
            _flatten(name, value, out)
        else:
            out[name] = value


class NodeParameters:
    """The declared parameters of every node of the sim, created lazily from a source per node.

    ``source(node) -> dict | None`` gives a node's initial parameters (nested dicts become dotted names);
    it is asked once per node, the first time the node's parameters are used.
    """

    def __init__(self, source: Callable[[str], dict[str, Any] | None]) -> None:
        self._source = source
        self._nodes: dict[str, dict[str, Any]] = {}

    def _params(self, node: str) -> dict[str, Any] | None:
        params = self._nodes.get(node)
        if params is None:
            initial = self._source(node)
            if initial is None:
                return None
            params = {"use_sim_time": False}
            _flatten("", initial, params)
            self._nodes[node] = params
        return params

    def get(self, node: str, name: str) -> tuple[bool, Any]:
        params = self._params(node)
        if params is None or name not in params:
            return False, None
        return True, copy.deepcopy(params[name])

    def set(self, node: str, name: str, value: Any) -> str | None:
        """Set a declared parameter; the reason when the node refuses it (None when it took it)."""
        params = self._params(node)
        if params is None:
            return f"node {node} does not exist"
        if name not in params:
            return f"parameter {name} is not declared by {node}"
        old, new = kind_of(params[name]), kind_of(value)
        if old != new:
            return f"wrong parameter type: {name} is {old}, got {new}"
        params[name] = copy.deepcopy(value)
        return None

    def delete(self, node: str, name: str) -> bool:
        params = self._params(node)
        return params is not None and params.pop(name, MALFORMED) is not MALFORMED

    def names(self, node: str) -> list[str]:
        params = self._params(node)
        return [f"{node}:{n}" for n in params] if params is not None else []


def get_param_value(store: NodeParameters, name: str, default_text: str) -> str:
    """rosapi's ``get_param`` answer (see the module docstring)."""
    where = split_name(name)
    if where is None:
        log.warning("Malformed parameter name: %s; expecting <node_name>:<param_name>", name)
        return ""
    default: Any = default_text
    if default_text != "":
        try:
            default = json.loads(default_text)
        except ValueError:
            pass
    found, value = store.get(*where)
    return json.dumps(value if found else default)


def set_param_value(store: NodeParameters, name: str, value_text: str) -> None:
    """rosapi's ``set_param``: raises ValueError for text that is not JSON, else never fails."""
    where = split_name(name)
    if where is None:
        log.warning("Malformed parameter name: %s; expecting <node_name>:<param_name>", name)
        return
    try:
        decoded = json.loads(value_text)
    except ValueError:
        raise ValueError(f"set_param needs the value as JSON text, got {value_text[:80]!r}") from None
    text = decoded if isinstance(decoded, str) else value_text
    problem = store.set(*where, typed_from_text(text))
    if problem is not None:
        log.warning("set_param %s refused by the node: %s", name, problem)
