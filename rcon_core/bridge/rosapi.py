"""Async helpers over the ``/rosapi/*`` services (ROS 1 rosapi 0.11 and ROS 2 rosapi).

Quirks handled (``rosapi.jsonl:47-49``): parameter values travel as JSON text inside strings (``get_param``
returns ``"7"``, ``"\\"hi\\""``; ``set_param`` needs JSON text); unknown names give empty results, not
failures (``topic_type`` of an unknown topic is ``""``, returned here as ``None``).

Decision: asking a type per service, in bounded batches
    rosapi has no call that lists services with their types, so :meth:`Rosapi.services_with_types` asks
    ``service_type`` once per name. A robot with 10^5 services got 10^5 calls at once (a 22 s stall of the
    loop, the link cut by the stall watchdog): now at most ``TYPE_CALLS_IN_FLIGHT`` are in flight and
    ``TYPE_CALLS_PER_S`` start per second, and with ``known`` (the types learned before, kept by the
    caller between refreshes) only the names not seen yet are asked. ``calls`` counts the calls made, by
    rosapi service.

Decision: ask only for services the server lists
    A service rosapi does not have is not "no answer": rosbridge answers ``result: false`` ("Service
    /rosapi/action_type does not exist") *and logs an ERROR into the robot's own /rosout* for every call
    (``rosbridge-ros2-2.1.0/rosapi.jsonl:62-63``).  So the optional services -- ``action_type``, the action
    details -- are asked only when ``/rosapi/services`` lists them (learned once per connection,
    ``client.rosapi_profile()``); otherwise the helpers answer what they would for "unknown" (None, ``""``)
    quietly, with no call at all.  Calls that would kill a 2.x rosapi are refused by the client itself
    (``rosapi_guard.py``); ``message_details`` then reads the type's ``.msg`` text from
    ``topics_and_raw_types`` when a topic carries it.  Typedefs keep only real constants
    (``msgs.typedefs.clean_typedefs``: rosapi 2.1.0 lists ``SLOT_TYPES`` and every field as "constants").
"""

from __future__ import annotations

import asyncio
import json
import logging
from collections import Counter
from collections.abc import Callable, Iterable
from typing import TYPE_CHECKING, Any

from rcon_core.msgs.names import normalize, pkg_type

from . import rosapi_guard
from .errors import BridgeError, ConnectionLostError, RosapiRefusedError, ServiceError
from .safety import bounded_repr, json_text_value

if TYPE_CHECKING:
    from .host import ServiceCaller
    from .rosinfo import RosInfo


log = logging.getLogger(__name__)

#: ``service_type`` calls in flight at once, and started per second, while listing services' types
TYPE_CALLS_IN_FLIGHT = 8
TYPE_CALLS_PER_S = 2000.0


class Rosapi:
    def __init__(self, client: ServiceCaller) -> None:
        self._client = client
        #: calls made, by rosapi service name (``"service_type"``...)
        self.calls: Counter[str] = Counter()

    async def profile(self) -> RosInfo | None:
        """What the server's rosapi lists (``client.rosapi_profile()``, once per connection); None when the
        client cannot say."""
        ask = getattr(self._client, "rosapi_profile", None)
        return await ask() if ask is not None else None

    async def lists(self, name: str) -> bool:
        """Whether the server's rosapi lists ``/rosapi/<name>`` (True when the client cannot say)."""
        info = await self.profile()
        return info is None or f"/rosapi/{name}" in info.rosapi_services

    async def _call(self, name: str, args: dict[str, Any] | None = None, timeout: float | None = None) -> Any:
        self.calls[name] += 1
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

    async def services_with_types(self, known: dict[str, str] | None = None,
                                  listed: Callable[[list[str]], None] | None = None) -> dict[str, str]:
        """``{service: type}`` in name order (``""`` where the type could not be had). rosapi has no combined
        call: one ``service_type`` per name, in bounded batches (see the module docstring). ``known``: types
        learned before, by name; only the other names are asked, and it is updated in place with the
        answers as they come (names no longer listed are dropped from it). ``listed(names)`` is called once
        the names are known, before their types are asked (a caller may show them meanwhile)."""
        names = sorted(await self.services())
        await asyncio.sleep(0)  # a long list: every step of it gives the loop a turn
        known = {} if known is None else known
        present = set(names)
        for gone in [n for n in known if n not in present]:
            del known[gone]
        await asyncio.sleep(0)
        todo = [n for n in names if n not in known]
        if listed is not None:
            listed(names)
        await asyncio.sleep(0)
        await self.ask_each(todo, self.service_type, known)
        return {n: known.get(n, "") for n in names}

    async def ask_each(self, names: Iterable[str], ask: Callable[[str], Any], into: dict[str, str]) -> None:
        """``into[name] = await ask(name)`` for every name, ``TYPE_CALLS_IN_FLIGHT`` at a time and at most
        ``TYPE_CALLS_PER_S`` started per second; a name whose call fails (``ServiceError``) is left out
        (asked again next time); a lost link ends it all (raised)."""
        names = list(names)
        if not names:
            return
        loop = asyncio.get_running_loop()
        todo = iter(names)
        gap = 1.0 / TYPE_CALLS_PER_S
        pace = {"next": loop.time()}
        failed: list[BaseException] = []

        async def worker() -> None:
            for name in todo:
                if failed:
                    return
                now = loop.time()
                wait, pace["next"] = pace["next"] - now, max(now, pace["next"]) + gap
                if wait > 0:
                    await asyncio.sleep(wait)
                try:
                    answer = await ask(name)
                except ConnectionLostError as exc:
                    failed.append(exc)
                    return
                except ServiceError as exc:  # this name only: asked again at the next refresh
                    log.debug("type of %s not known: %s", name, exc)
                    continue
                except BridgeError as exc:  # not connected: nothing more can be asked
                    failed.append(exc)
                    return
                into[name] = answer if isinstance(answer, str) else ""

        await asyncio.gather(*(worker() for _ in range(min(TYPE_CALLS_IN_FLIGHT, len(names)))))
        if failed:
            raise failed[0]

    async def topic_type(self, topic: str) -> str | None:
        return (await self._call("topic_type", {"topic": topic})).get("type") or None

    async def service_type(self, service: str) -> str | None:
        return (await self._call("service_type", {"service": service})).get("type") or None

    async def message_details(self, type_name: str) -> list[dict[str, Any]]:
        """The server's typedefs of a message type (real constants only); from ``topics_and_raw_types``
        when ``message_details`` may not be asked (``rosapi_guard``) and a topic carries the type."""
        from rcon_core.msgs.typedefs import clean_typedefs

        try:
            answer = await self._call("message_details", {"type": type_name})
        except RosapiRefusedError:
            found = await self.typedefs_from_text(type_name)
            if found:
                return found
            raise
        return clean_typedefs(list(answer.get("typedefs", [])))

    async def service_request_details(self, type_name: str) -> list[dict[str, Any]]:
        from rcon_core.msgs.typedefs import clean_typedefs

        return clean_typedefs(list((await self._call("service_request_details", {"type": type_name}))
                                   .get("typedefs", [])))

    async def service_response_details(self, type_name: str, timeout: float | None = None) -> list[dict[str, Any]]:
        from rcon_core.msgs.typedefs import clean_typedefs

        v = await self._call("service_response_details", {"type": type_name}, timeout=timeout)
        return clean_typedefs(list(v.get("typedefs", [])))

    async def raw_definition(self, type_name: str) -> tuple[str, str] | None:
        """``(type, full .msg text)`` of a message type some topic carries, from ``topics_and_raw_types``
        (what rosapi reads from the interface files; it never touches the crashing typedef code)."""
        if not await self.lists("topics_and_raw_types"):
            return None
        v = await self._call("topics_and_raw_types")
        key = pkg_type(type_name)
        for spelled, text in zip(v.get("types") or [], v.get("typedefs_full_text") or [], strict=False):
            if isinstance(spelled, str) and isinstance(text, str) and text and pkg_type(spelled) == key:
                return spelled, text
        return None

    async def typedefs_from_text(self, type_name: str) -> list[dict[str, Any]]:
        """rosapi-shaped typedefs built from the type's ``.msg`` text (:meth:`raw_definition`); [] when no
        topic carries the type or the text cannot be read."""
        from rcon_core.msgs import TypeRegistry
        from rcon_core.msgs.parse import TIME_TYPES, split_full_text

        found = await self.raw_definition(type_name)
        if found is None:
            return []
        spelled, text = found
        info = await self.profile()
        detect = getattr(self._client, "detect_ros", None)
        if (info is None or info.version is None) and detect is not None:
            info = await detect()  # the quick profile cannot tell ROS 1 (rosapi 0.11 has no get_ros_version)
        reg = TypeRegistry(ros2=info is None or info.version != 1, empty=True)
        try:
            for name, body in split_full_text(spelled, text):
                if normalize(name) not in TIME_TYPES and pkg_type(name) not in ("builtin_interfaces/Time",
                                                                                 "builtin_interfaces/Duration"):
                    reg.add_msg_text(name, body)
            return reg.typedefs(spelled)
        except Exception as exc:  # noqa: BLE001 - a text we cannot read: say so, fall back
            log.info("cannot read the definition text of %s from the robot: %s", type_name, exc)
            return []

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
        """``pkg/action/X`` of a ROS 2 action from rosapi's ``action_type``; None when the action has no
        server or the rosapi cannot tell -- and then without asking: 2.1.0 has no ``action_type`` (a call
        would log an ERROR on the robot) and the releases that list it crash on it
        (``rosapi_guard.action_type_works``).  2.1.0 cannot tell an action's type at all: ``topic_type``
        ignores the hidden ``<action>/_action/*`` topics."""
        info = await self.profile()
        if info is not None and not rosapi_guard.action_type_works(info):
            return None
        try:
            answer = await self._call("action_type", {"action": action})
        except ServiceError:
            return None
        return str(answer.get("type") or "") or None

    async def action_servers_with_types(self) -> dict[str, str]:
        """``{action: type}`` of every action server (``""`` where the type cannot be found; nothing is
        asked per action when this rosapi cannot tell types)."""
        names = await self.action_servers()
        info = await self.profile()
        if info is not None and not rosapi_guard.action_type_works(info):
            return dict.fromkeys(names, "")
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
