"""Async helpers over the ``/rosapi/*`` services (ROS 1 rosapi 0.11 and ROS 2 rosapi).

Quirks handled (``rosapi.jsonl:47-49``): parameter values travel as JSON text inside strings (``get_param``
returns ``"7"``, ``"\\"hi\\""``; ``set_param`` needs JSON text); unknown names give empty results, not
failures (``topic_type`` of an unknown topic is ``""``, returned here as ``None``).
"""

from __future__ import annotations

import asyncio
import json
from typing import TYPE_CHECKING, Any

from .errors import ServiceError
from .safety import bounded_repr, json_text_value

if TYPE_CHECKING:
    from .host import ServiceCaller


class Rosapi:
    def __init__(self, client: ServiceCaller) -> None:
        self._client = client

    async def _call(self, name: str, args: dict[str, Any] | None = None, timeout: float | None = None) -> Any:
        values = await self._client.call_service(f"/rosapi/{name}", args or {}, timeout=timeout)
        if not isinstance(values, dict):
            raise ServiceError(f"unexpected answer {values!r}", f"/rosapi/{name}")
        return values

    # ------------------------------------------------------------------ graph

    async def topics(self) -> dict[str, str]:
        """``{topic: type}`` for every topic the server knows."""
        v = await self._call("topics")
        topics = _listed(v.get("topics"))
        types = _listed(v.get("types")) or [""] * len(topics)
        return {t: (ty if isinstance(ty, str) else "") for t, ty in zip(topics, types, strict=False)
                if isinstance(t, str)}

    async def services(self) -> list[str]:
        return [s for s in _listed((await self._call("services")).get("services")) if isinstance(s, str)]

    async def services_with_types(self) -> dict[str, str]:
        """``{service: type}``; types are asked for concurrently (rosapi has no combined call)."""
        names = await self.services()
        types = await asyncio.gather(*(self.service_type(n) for n in names), return_exceptions=True)
        return {n: (t if isinstance(t, str) else "") for n, t in zip(names, types, strict=True)}

    async def topic_type(self, topic: str) -> str | None:
        return (await self._call("topic_type", {"topic": topic})).get("type") or None

    async def service_type(self, service: str) -> str | None:
        return (await self._call("service_type", {"service": service})).get("type") or None

    async def message_details(self, type_name: str) -> list[dict[str, Any]]:
        return list((await self._call("message_details", {"type": type_name})).get("typedefs", []))

    async def service_request_details(self, type_name: str) -> list[dict[str, Any]]:
        return list((await self._call("service_request_details", {"type": type_name})).get("typedefs", []))

    async def service_response_details(self, type_name: str, timeout: float | None = None) -> list[dict[str, Any]]:
        v = await self._call("service_response_details", {"type": type_name}, timeout=timeout)
        return list(v.get("typedefs", []))

    async def nodes(self) -> list[str]:
        return list((await self._call("nodes")).get("nodes", []))

    async def node_details(self, node: str) -> dict[str, list[str]]:
        v = await self._call("node_details", {"node": node})
        return {k: list(v.get(k, [])) for k in ("subscribing", "publishing", "services")}

    async def publishers(self, topic: str) -> list[str]:
        return list((await self._call("publishers", {"topic": topic})).get("publishers", []))

    async def subscribers(self, topic: str) -> list[str]:
        return list((await self._call("subscribers", {"topic": topic})).get("subscribers", []))

    async def action_servers(self) -> list[str]:
        return list((await self._call("action_servers")).get("action_servers", []))

    async def action_type(self, action: str) -> str | None:
        """``pkg/action/X`` of a ROS 2 action from rosapi's ``action_type`` (added after rosapi 2.1.0); None
        when the action has no server or the rosapi is older (2.1.0 cannot tell an action's type at all:
        ``topic_type`` ignores the hidden ``<action>/_action/*`` topics)."""
        try:
            answer = await self._call("action_type", {"action": action})
        except ServiceError:
            return None
        return str(answer.get("type") or "") or None

    async def action_servers_with_types(self) -> dict[str, str]:
        """``{action: type}`` of every action server (``""`` where the type cannot be found)."""
        names = await self.action_servers()
        types = await asyncio.gather(*(self.action_type(n) for n in names), return_exceptions=True)
        return {n: (t if isinstance(t, str) else "") for n, t in zip(names, types, strict=True)}

    async def get_time(self) -> dict[str, int]:
        """The server's ROS time: ``{"secs", "nsecs"}`` (ROS 1) or ``{"sec", "nanosec"}`` (ROS 2)."""
        return dict((await self._call("get_time")).get("time", {}))

    async def ros_version(self) -> dict[str, Any] | None:
        """``{"version": 1|2, "distro": str}`` when the server tells, else None."""
        try:
            v = await self._call("get_ros_version")
            return {"version": int(v.get("version", 0)), "distro": v.get("distro", "")}
        except ServiceError:
            pass
        try:
            version = await self.get_param("/rosversion")
            distro = await self.get_param("/rosdistro")
        except ServiceError:
            return None
        if version is None:
            return None
        return {"version": int(str(version).split(".")[0]), "distro": str(distro or "").strip()}

    # ------------------------------------------------------------------ parameters (JSON text in strings)

    async def get_param(self, name: str, default: Any = None) -> Any:
        args = {"name": name}
        if default is not None:
            args["default"] = json.dumps(default)
        text = (await self._call("get_param", args)).get("value", "null")
        try:
            value = json_text_value(text) if text else None
        except ValueError as exc:
            raise ServiceError(f"parameter {name} is not valid JSON text ({exc}): {bounded_repr(text, 80)}",
                               "/rosapi/get_param") from None
        return default if value is None else value

    async def set_param(self, name: str, value: Any) -> None:
        await self._call("set_param", {"name": name, "value": json.dumps(value)})

    async def has_param(self, name: str) -> bool:
        return bool((await self._call("has_param", {"name": name})).get("exists", False))

    async def delete_param(self, name: str) -> None:
        await self._call("delete_param", {"name": name})

    async def param_names(self) -> list[str]:
        return list((await self._call("get_param_names")).get("names", []))


def _listed(value: Any) -> list[Any]:
    """A list the server sent, or an empty one when it sent something else (names are checked by the
    caller: a server's answer is never trusted to have the documented shape)."""
    return value if isinstance(value, list) else []
