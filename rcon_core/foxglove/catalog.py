"""What a Foxglove robot offers, in the robot-link interface's terms: ``client.catalog`` and ``client.params``.

Decision: the catalogue from advertisements and the graph, not from rosapi
    The rosbridge link learns topics, services and types by asking rosapi; a Foxglove server tells them
    unasked.  :class:`FoxgloveCatalog` answers the same questions (``topics``, ``services_with_types``,
    ``topic_type``, ``message_details``, ``nodes``, ``publishers``...) from the session's channels,
    services, learned schemas and connection graph, with the same return shapes as
    ``rcon_core.bridge.rosapi.Rosapi``, so discovery, the side panel, ``rcon topics`` and type lookups are
    written once.  ``nodes`` are the graph's publisher, subscriber and provider ids.  Actions: none, the
    protocol has none (``action_servers`` returns an empty list; sending a goal says so in words).

Decision: parameters
    :class:`FoxgloveParams` has ``client.params``' interface over ``getParameters``/``setParameters``:
    names are the server's own (foxglove_bridge: ``/node.param``), grouped by the part before the first
    ``.`` (or by namespace, for ROS 1 names such as ``/kingfisher/max_speed``); ``set`` sends the value (a whole float with the ``float64`` type hint) and, with ``verify``,
    compares the value the server answers with, raising ``ParamRejectedError`` when it did not take it;
    ``watch(names, fn)`` subscribes to updates (restored after a reconnect).
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from typing import Any

from rcon_core.bridge.errors import BridgeError, ServiceTimeoutError
from rcon_core.bridge.params import MISSING, ParamNotFoundError, ParamRejectedError, kind, split
from rcon_core.msgs import names as type_names

from .session import CANNOT

#: what the catalogue and the parameters need of their client (``client.py``'s ``FoxgloveClient``, not imported:
#: no cycle even for annotations): ``session``, ``call_timeout``, ``server_time``, ``await wait_connected()``
FoxgloveHost = Any


class FoxgloveCatalog:
    """The robot's topics, services, types and graph (see the module docstring); coroutines on the loop."""

    def __init__(self, client: FoxgloveHost) -> None:
        self._client = client

    @property
    def _s(self) -> Any:
        return self._client.session

    async def _ready(self) -> None:
        await self._client.wait_connected()

    async def topics(self) -> dict[str, str]:
        await self._ready()
        return {topic: ch.type for topic, ch in sorted(self._s.by_topic.items())}

    async def services(self) -> list[str]:
        await self._ready()
        return sorted(self._s.service_by_name)

    async def services_with_types(self, known: dict[str, str] | None = None,
                                  listed: Callable[[list[str]], None] | None = None) -> dict[str, str]:
        """As ``Rosapi.services_with_types``: the advertisements carry every type, so nothing is asked;
        ``known`` is updated in place and ``listed(names)`` told, as the side panel's discovery expects."""
        await self._ready()
        found = {name: srv.type for name, srv in sorted(self._s.service_by_name.items())}
        if known is not None:
            known.clear()
            known.update(found)
        if listed is not None:
            listed(list(found))
        return found

    async def topic_type(self, topic: str) -> str | None:
        await self._ready()
        ch = self._s.by_topic.get(topic)
        return ch.type if ch is not None else None

    async def service_type(self, service: str) -> str | None:
        await self._ready()
        srv = self._s.service_by_name.get(service)
        return srv.type if srv is not None else None

    def channel(self, topic: str) -> Any:
        """The channel a topic is read from (encoding, schema name, schema encoding), or None."""
        return self._s.by_topic.get(topic)

    def _learn_channel_of(self, type_name: str) -> Any:
        for ch in self._s.channels.values():
            if ch.type == type_name or ch.schema_name == type_name:
                if ch.schema_encoding in ("ros2msg", "ros1msg"):
                    self._s.codecs.learn(ch.schema_name, ch.schema_encoding, ch.schema)
                    return self._s.codecs.ros2 if ch.schema_encoding == "ros2msg" else self._s.codecs.ros1
        return None

    async def message_details(self, type_name: str) -> list[dict[str, Any]]:
        """rosapi-shaped typedefs of a ROS type the robot's schemas (or RCON's standard types) define."""
        name = type_names.normalize(type_name) if "/" in type_name else type_name
        reg = self._learn_channel_of(name) or self._s.codecs.ros2
        if not reg.has(name):
            raise BridgeError(f"the robot's schemas do not define {type_name}")
        return reg.typedefs(name)

    async def service_request_details(self, type_name: str) -> list[dict[str, Any]]:
        return self._service_details(type_name, "Request")

    async def service_response_details(self, type_name: str, timeout: float | None = None) -> list[dict[str, Any]]:
        return self._service_details(type_name, "Response")

    def _service_details(self, type_name: str, part: str) -> list[dict[str, Any]]:
        """The typedefs of one half of a ROS service type; [] for a type no schema or standard type defines
        (a JSON service: the request is sent as typed)."""
        try:
            pkg, _kind, short = type_names.split(type_name)
            name = f"{pkg}/srv/{short}_{part}"
            reg = self._s.codecs.ros2
            return reg.typedefs(name) if reg.has(name) else []
        except (ValueError, KeyError):
            return []

    async def nodes(self) -> list[str]:
        await self._ready()
        g = self._s.graph
        ids = {i for key in g for ids in g[key].values() for i in ids}
        return sorted(ids)

    async def node_details(self, node: str) -> dict[str, list[str]]:
        g = self._s.graph
        return {"publishing": sorted(t for t, ids in g["published"].items() if node in ids),
                "subscribing": sorted(t for t, ids in g["subscribed"].items() if node in ids),
                "services": sorted(s for s, ids in g["services"].items() if node in ids)}

    async def publishers(self, topic: str) -> list[str]:
        return list(self._s.graph["published"].get(topic, []))

    async def subscribers(self, topic: str) -> list[str]:
        return list(self._s.graph["subscribed"].get(topic, []))

    async def service_providers(self, service: str) -> list[str]:
        return list(self._s.graph["services"].get(service, []))

    async def action_servers(self) -> list[str]:
        return []

    async def action_servers_with_types(self) -> dict[str, str]:
        return {}

    async def action_type(self, action: str) -> str | None:
        raise BridgeError(CANNOT["actions"])

    async def get_time(self) -> dict[str, int]:
        ns = self._client.server_time
        if ns is None:
            raise BridgeError("this Foxglove server sends no time (no 'time' capability)")
        return {"sec": ns // 1_000_000_000, "nanosec": ns % 1_000_000_000}


def _wire_value(value: Any) -> dict[str, Any]:
    if isinstance(value, float):
        return {"value": value, "type": "float64"}
    if isinstance(value, list) and value and all(isinstance(v, float) for v in value):
        return {"value": value, "type": "float64_array"}
    return {"value": value}


class FoxgloveParams:
    """``client.params`` over the Foxglove protocol (see the module docstring)."""

    def __init__(self, client: FoxgloveHost) -> None:
        self._client = client

    async def ros2(self) -> bool:
        return False  # names are the server's own, grouped as a namespace is (params.split(name, False))

    async def _ask(self, start: Callable[[Callable[[list[dict[str, Any]]], None]], str]) -> list[dict[str, Any]]:
        client = self._client
        budget = client.call_timeout
        fut: asyncio.Future[list[dict[str, Any]]] = asyncio.get_running_loop().create_future()

        def done(params: list[dict[str, Any]]) -> None:
            if not fut.done():
                fut.set_result(params)

        try:
            async with asyncio.timeout(budget):
                await client.wait_connected()
                if "parameters" not in client.session.capabilities:
                    raise BridgeError("this Foxglove server has no parameters (no 'parameters' capability)")
                rid = start(done)
                try:
                    return await fut
                finally:
                    client.session.requests.param_requests.pop(rid, None)
        except TimeoutError:
            raise ServiceTimeoutError(f"no parameter answer within {budget:g} s", "getParameters") from None

    async def names(self) -> list[str]:
        got = await self._ask(lambda done: self._client.session.requests.request_params([], done))
        return sorted(p["name"] for p in got)

    async def by_owner(self) -> dict[str, list[str]]:
        groups: dict[str, list[str]] = {}
        for name in await self.names():
            owner = name.split(".", 1)[0] if "." in name else split(name, False)[0]
            groups.setdefault(owner, []).append(name)
        return {k: sorted(v) for k, v in sorted(groups.items())}

    async def has(self, name: str) -> bool:
        return (await self.get(name, default=MISSING if False else None)) is not None

    async def get(self, name: str, default: Any = MISSING) -> Any:
        got = await self._ask(lambda done: self._client.session.requests.request_params([name], done))
        for p in got:
            if p["name"] == name and p.get("value") is not None:
                return p["value"]
        if default is MISSING:
            raise ParamNotFoundError(f"no parameter {name}")
        return default

    async def set(self, name: str, value: Any, verify: bool = True) -> None:
        """Set ``name`` (see the module docstring); told to the operator tap as on rosbridge (``bridge/tap.py``:
        the flight recorder writes it on ``/rcon/operator/param``)."""
        tap = self._client.session.tap
        if not tap.listeners:
            return await self._set(name, value, verify)
        try:
            await self._set(name, value, verify)
        except Exception as exc:
            tap.emit("param", "params", name, "", value, f"error: {exc}")
            raise
        tap.emit("param", "params", name, "", value, "ok" if verify else "sent")

    async def _set(self, name: str, value: Any, verify: bool) -> None:
        item = {"name": name, **_wire_value(value)}
        got = await self._ask(lambda done: self._client.session.requests.set_params([item], done))
        if not verify:
            return
        now = next((p.get("value") for p in got if p["name"] == name), None)
        if now is None:
            now = await self.get(name, default=None)
        if now != value or (kind(now) != kind(value) and not (kind(value) == "float" and kind(now) == "int")):
            reason = "the server has no such parameter" if now is None else f"it holds {kind(now)} {now!r}"
            raise ParamRejectedError(f"{name} was not set to {value!r}: {reason}")

    async def delete(self, name: str) -> None:
        raise BridgeError(CANNOT["delete_param"])

    def watch(self, names: list[str], fn: Callable[[str, Any], None]) -> Callable[[], None]:
        """``fn(name, value)`` on every update of these parameters (loop thread); returns a remover."""
        return self._client.session.requests.watch_params(list(names), fn)
