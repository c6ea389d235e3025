"""Parameters over rosapi, ROS 1 and ROS 2 alike: ``client.params`` (a :class:`Params`).

ROS 1 has one parameter server with slash-separated names (``/kingfisher/max_speed``; a namespace reads
back as a dict).  ROS 2 has none: each node owns its parameters and rosapi 2.x names one
``<node>:<param>`` (``/kingfisher:max_speed``, nested ones with dots: ``/kingfisher:gps.origin_lat``).
On ROS 1 values travel as JSON text inside strings through rosapi's parameter calls.  On ROS 2 the
nodes are asked directly through their own parameter services (``params_ros2.py`` says why: rosapi
2.1.0's parameter calls die, hang or lie); what this module adds:

* a name that is not ``<node>:<param>`` is refused here with ``ValueError``;
* ``set`` raises :class:`ParamRejectedError` with the node's own reason when the node did not take the
  value (undeclared parameter, other type: an integer for a double too); with ``verify`` the value is
  also read back;
* ``delete`` undeclares the parameter (the node may refuse: :class:`ParamRejectedError`).

Which shape applies comes from ``client.detect_ros()`` (done on first use).  Helpers for editors:
:func:`split` / :func:`join` names, :func:`kind` names a value's type (bool, int, float, string, list),
:func:`parse_like` reads text typed by a person as YAML and checks it has the current value's kind.
"""

from __future__ import annotations

import json
from typing import TYPE_CHECKING, Any

from .errors import BridgeError, ServiceError
from .params_ros2 import NodeParams
from .safety import bounded_repr, json_text_value

if TYPE_CHECKING:
    from .host import RosClient

MISSING: Any = object()


class ParamNotFoundError(BridgeError, KeyError):
    """The parameter does not exist (and no default was given)."""

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else "parameter not found"


class ParamRejectedError(BridgeError):
    """The node did not take the value (ROS 2: undeclared parameter or a value of another type)."""


def split(name: str, ros2: bool) -> tuple[str, str]:
    """``(node, param)`` on ROS 2 (``"/n:p"``); ``(namespace, leaf)`` on ROS 1 (``"/a/b/c"`` -> ``("/a/b", "c")``)."""
    if ros2:
        parts = name.split(":")
        if len(parts) != 2 or not parts[0] or not parts[1]:
            raise ValueError(f"a ROS 2 parameter is named <node>:<param>, e.g. /kingfisher:max_speed; got {name!r}")
        node = parts[0] if parts[0].startswith("/") else "/" + parts[0]
        return node, parts[1]
    stripped = "/" + name.strip("/")
    ns, _, leaf = stripped.rpartition("/")
    return ns or "/", leaf


def join(owner: str, param: str, ros2: bool) -> str:
    """The inverse of :func:`split`."""
    if ros2:
        return f"{owner}:{param}"
    return f"{owner.rstrip('/')}/{param}"


def kind(value: Any) -> str:
    """bool, int, float, string, list or dict: what an editor checks a new value against."""
    if isinstance(value, bool):
        return "bool"
    if isinstance(value, int):
        return "int"
    if isinstance(value, float):
        return "float"
    if isinstance(value, str):
        return "string"
    if isinstance(value, list):
        return "list"
    if isinstance(value, dict):
        return "dict"
    return type(value).__name__


def parse_like(text: str, current: Any) -> Any:
    """``text`` (YAML, as a person types it) as a value of ``current``'s kind; ValueError when it is not.

    An int is accepted where a float is expected (and becomes a float); a string needs no quotes."""
    want = kind(current)
    if want == "string":
        return text
    if not text.strip():
        raise ValueError("nothing typed")
    # YAML as a person types numbers: 1e5 is a float (plain YAML 1.1 reads it as a string), and a number
    # too large to be one (1.0e+400) is refused instead of becoming infinity without a word
    from rcon_core.msgs.text import parse_text

    value = parse_text(text)  # MessageTextError (a ValueError) says what is wrong
    got = kind(value)
    if want == "float" and got == "int":
        return float(value)
    if got != want:
        raise ValueError(f"expected a {want}, got a {got}: {text!r}")
    if want == "list" and isinstance(current, list) and current:
        inner = kind(current[0])
        for item in value:
            if kind(item) != inner and not (inner == "float" and kind(item) == "int"):
                raise ValueError(f"expected a list of {inner}, got {item!r} in it")
        if inner == "float":
            value = [float(v) for v in value]
    return value


class Params:
    """Parameter access for one client; every method is a coroutine on the client's loop."""

    def __init__(self, client: RosClient) -> None:
        self._client = client
        self._nodes = NodeParams(client)

    async def ros2(self) -> bool:
        return (await self._client.detect_ros()).version == 2

    async def _call(self, service: str, args: dict[str, Any]) -> dict[str, Any]:
        values = await self._client.call_service(f"/rosapi/{service}", args)
        if not isinstance(values, dict):
            raise ServiceError(f"unexpected answer {values!r}", f"/rosapi/{service}")
        return values

    async def names(self) -> list[str]:
        """Every parameter name (ROS 2: ``<node>:<param>`` of every node with parameter services)."""
        if await self.ros2():
            return await self._nodes.names()
        return list((await self._call("get_param_names", {})).get("names", []))

    async def by_owner(self) -> dict[str, list[str]]:
        """Names grouped by node (ROS 2) or namespace (ROS 1), both sorted."""
        ros2 = await self.ros2()
        groups: dict[str, list[str]] = {}
        for name in await self.names():
            try:
                owner, _ = split(name, ros2)
            except ValueError:
                continue
            groups.setdefault(owner, []).append(name)
        return {k: sorted(v) for k, v in sorted(groups.items())}

    async def has(self, name: str) -> bool:
        if await self.ros2():
            return (await self._nodes.get(*split(name, True)))[0]
        return bool((await self._call("has_param", {"name": name})).get("exists", False))

    async def get(self, name: str, default: Any = MISSING) -> Any:
        """The value; ``default`` when missing, else :class:`ParamNotFoundError`."""
        if await self.ros2():
            found, value = await self._nodes.get(*split(name, True))
        else:
            text = (await self._call("get_param", {"name": name})).get("value", "")
            try:
                value = json_text_value(text) if text else None
            except ValueError as exc:
                raise ServiceError(f"parameter {name} is not JSON text ({exc}): {bounded_repr(text, 80)}",
                                   "/rosapi/get_param") from None
            found = value is not None
        if not found:
            if default is MISSING:
                raise ParamNotFoundError(f"no parameter {name}")
            return default
        return value

    async def set(self, name: str, value: Any, verify: bool = True) -> None:
        """Set ``name`` to ``value``; with ``verify`` read it back and raise :class:`ParamRejectedError`
        when the node did not take it (ROS 2 nodes refuse undeclared names and other types silently)."""
        tap = getattr(getattr(self._client, "session", None), "tap", None)  # the operator tap (tap.py)
        if tap is None or not tap.listeners:
            return await self._set(name, value, verify)
        try:
            await self._set(name, value, verify)
        except Exception as exc:
            tap.emit("param", "params", name, "", value, f"error: {exc}")
            raise
        tap.emit("param", "params", name, "", value, "ok" if verify else "sent")

    async def _set(self, name: str, value: Any, verify: bool) -> None:
        ros2 = await self.ros2()
        if ros2:
            node, param = split(name, True)
            try:
                taken, why = await self._nodes.set(node, param, value)
            except LookupError as exc:
                raise ParamRejectedError(f"{name} was not set to {value!r}: {exc}") from None
            if not taken:
                found, now = await self._nodes.get(node, param)
                reason = "the parameter is not declared by the node" if not found else \
                    f"it holds {kind(now)} {now!r}, so the node refused a {kind(value)}"
                raise ParamRejectedError(f"{name} was not set to {value!r}: {reason}" + (f" ({why})" if why else ""))
        else:
            await self._call("set_param", {"name": name, "value": json.dumps(value)})
        if not verify:
            return
        now = await self.get(name, default=MISSING if not ros2 else None)
        if now != value or kind(now) != kind(value):
            reason = "the parameter is not declared by the node" if now is None else \
                f"it holds {kind(now)} {now!r}, so the node refused a {kind(value)}"
            raise ParamRejectedError(f"{name} was not set to {value!r}: {reason}")

    async def delete(self, name: str) -> None:
        """Remove the parameter (ROS 2: undeclare it; the node may refuse, :class:`ParamRejectedError`)."""
        if await self.ros2():
            node, param = split(name, True)
            try:
                taken, why = await self._nodes.set(node, param, None)
            except LookupError as exc:
                raise ParamRejectedError(f"{name} was not deleted: {exc}") from None
            if not taken:
                raise ParamRejectedError(f"{name} was not deleted: {why or 'the node refused'}")
            return
        await self._call("delete_param", {"name": name})
