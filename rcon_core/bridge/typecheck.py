"""Does the robot know a message or service type?

Decision: ask, do not wait for a refusal. rosbridge 0.11 accepts a ``subscribe``, ``advertise`` or
``publish`` of a type it cannot load and says nothing on the wire: the error is only in the server's log
(recordings: ``client_publish.jsonl`` 15-17, ``malformed.jsonl`` 22; there is no ``status`` op). A widget
bound to such a type would show NO DATA for ever and ``rcon pub`` would report success. So for a type
that is not one of the standard definitions RCON ships (those every robot has), we ask the robot for its
definition (``/rosapi/message_details``, or ``service_request_details`` for a service type): a refusal
means the robot cannot load the type. Servers that do report failures with a ``status`` op (newer
rosbridge versions) are handled as well, by :func:`status_failure`.

Usage::

    checker = TypeChecker(client)                       # one per connection; caches what is known
    problem = await checker.problem("lab_msgs/Winch")   # None, or UNKNOWN_TYPE's sentence

``problem()`` returns None when the robot could not tell (no rosapi, a timeout, the link went down):
only a definite refusal becomes an error.
"""

from __future__ import annotations

import asyncio
import logging
from typing import Any

from .errors import BridgeError, ConnectionLostError, RosapiRefusedError, ServiceError, ServiceTimeoutError
from .safety import bounded_repr

__all__ = ["UNKNOWN_TYPE", "unknown_type_sentence", "is_standard", "robot_knows", "TypeChecker",
           "status_failure"]

log = logging.getLogger(__name__)

#: the sentence shown on the widget and printed by the CLI
UNKNOWN_TYPE = "the robot does not know {type} (is its package installed there?)"
#: seconds to wait for the robot's answer
ASK_TIMEOUT = 5.0

_STANDARD: dict[bool, Any] = {}


def unknown_type_sentence(type_name: str) -> str:
    return UNKNOWN_TYPE.format(type=type_name)


def _standard(ros2: bool) -> Any:
    if ros2 not in _STANDARD:
        from rcon_core.msgs import TypeRegistry

        _STANDARD[ros2] = TypeRegistry.standard(ros2=ros2)
    return _STANDARD[ros2]


def is_standard(type_name: str, service: bool = False) -> bool:
    """Whether ``type_name`` is one of the standard definitions (ROS 1 or ROS 2) RCON ships."""
    for ros2 in (False, True):
        try:
            reg = _standard(ros2)
            if reg.has_service(type_name) if service else reg.has(type_name):
                return True
        except Exception:  # noqa: BLE001 - a malformed name is not standard
            continue
    return False


def _no_rosapi(exc: ServiceError) -> bool:
    text = str(exc).lower()
    return "/rosapi/" in text and ("does not exist" in text or "not advertised" in text)


async def robot_knows(client: Any, type_name: str, service: bool = False,
                      timeout: float = ASK_TIMEOUT) -> bool | None:
    """True/False when the robot answered whether it can load the type; None when it could not tell."""
    rosapi = getattr(client, "rosapi", None)
    if rosapi is None:
        return None
    try:
        if service:
            typedefs = await asyncio.wait_for(rosapi.service_request_details(type_name), timeout)
        else:
            typedefs = await asyncio.wait_for(rosapi.message_details(type_name), timeout)
    except (ServiceTimeoutError, ConnectionLostError, RosapiRefusedError, TimeoutError):
        return None  # no answer, or not asked: rosapi_guard keeps the call from killing a 2.x rosapi
    except ServiceError as exc:
        if _no_rosapi(exc):
            return None
        log.info("the robot refused the definition of %s: %s", type_name, exc)
        return False
    except (BridgeError, OSError):
        return None
    if not typedefs:
        return service  # a service part may be empty (std_srvs/Empty); an empty message answer is a refusal
    first = typedefs[0] if isinstance(typedefs[0], dict) else {}
    return first.get("fieldnames") is not None


class TypeChecker:
    """Asks one connection's robot about non-standard types; a known type is asked once."""

    def __init__(self, client: Any) -> None:
        self.client = client
        self._known: set[tuple[str, bool]] = set()
        self._asking: dict[tuple[str, bool], asyncio.Future[bool | None]] = {}

    async def problem(self, type_name: str, service: bool = False) -> str | None:
        """The sentence to show when the robot does not know ``type_name``; None otherwise."""
        if not type_name:
            return None
        if len(_STANDARD) == 2:
            standard = is_standard(type_name, service)
        else:  # building the standard registries takes a few hundred ms: not on the bridge loop
            standard = await asyncio.get_running_loop().run_in_executor(None, is_standard, type_name, service)
        if standard:
            return None
        key = (type_name, service)
        if key in self._known:
            return None
        fut = self._asking.get(key)
        if fut is None:
            fut = self._asking[key] = asyncio.ensure_future(robot_knows(self.client, type_name, service))
            fut.add_done_callback(lambda _f: self._asking.pop(key, None))  # key is not rebound
        known = await asyncio.shield(fut)
        if known:
            self._known.add(key)
        return unknown_type_sentence(type_name) if known is False else None


def status_failure(frame: dict[str, Any]) -> tuple[str, str] | None:
    """(topic, text) when a ``status`` frame reports the failure of one of the client's topic ops.

    The client's subscribe ids are ``sub:<topic>:<n>`` and its advertise ids ``adv:<topic>``; a
    status of level ``error`` naming such an id says that op failed.
    """
    if not isinstance(frame, dict) or frame.get("level") != "error":
        return None
    sid = frame.get("id")
    if not isinstance(sid, str):
        return None
    msg = frame.get("msg", "")
    text = (msg[:300] if isinstance(msg, str) else bounded_repr(msg, 300)) or "the robot refused it"
    if sid.startswith("sub:"):
        return sid[4:].rsplit(":", 1)[0], text
    if sid.startswith("adv:"):
        return sid[4:], text
    return None
