"""Which ROS the server runs, and what it showed it can do: ``await client.detect_ros()`` -> :class:`RosInfo`.

Asked once per connection (the answer is kept in ``client.ros_info``; ``detect_ros(refresh=True)`` asks
again); the list of ``/rosapi/*`` services comes with it (``RosInfo.rosapi_services``), and RCON asks
rosapi only for services in that list (``rosapi.py``, ``rosapi_guard.py``):

1. ``/rosapi/get_ros_version`` (rosapi 2.x: ``{"version": 2, "distro": "jazzy"}``);
2. else the ROS 1 parameters ``/rosversion`` and ``/rosdistro``;
3. else what the answers look like: rosapi's own service types are ``rosapi_msgs/srv/Topics`` on ROS 2 and
   ``rosapi/Topics`` on ROS 1; topic types spelled ``pkg/msg/Type`` are ROS 2.

The shapes that differ and who picks them by ``client.ros_version``: parameter names and requests
(``params.py``), ``cbor-raw`` payloads (CDR on ROS 2, ROS 1 serialization otherwise), actions
(``send_action_goal`` exists on ROS 2 only).  ``version`` None means nothing answered (no rosapi).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from .errors import BridgeError
from .safety import json_text_value

if TYPE_CHECKING:
    from .host import ServiceCaller

log = logging.getLogger(__name__)

#: rosapi services whose presence is worth reporting (``rcon info``)
NOTABLE = ("get_ros_version", "action_servers", "topics_and_raw_types", "get_param_names", "search_param",
           "service_host", "message_details")


@dataclass(frozen=True)
class RosInfo:
    """What a server told about itself."""

    version: int | None  # 1, 2, or None when unknown
    distro: str = ""
    source: str = "unknown"  # how the version was learned
    rosapi_services: tuple[str, ...] = field(default_factory=tuple)  # the /rosapi/* services listed

    @property
    def ros2(self) -> bool:
        return self.version == 2

    @property
    def capabilities(self) -> list[str]:
        """A short list of what the server showed it can do, in words."""
        out: list[str] = []
        if self.rosapi_services:
            out.append(f"rosapi ({len(self.rosapi_services)} services)")
        out += [f"rosapi/{n}" for n in NOTABLE if f"/rosapi/{n}" in self.rosapi_services]
        if self.version == 2:
            out += ["actions (send_action_goal, advertise_action)", "parameters as <node>:<param>",
                    "cbor-raw as CDR"]
        elif self.version == 1:
            out += ["parameter server (/ns/param)", "cbor-raw as ROS 1 serialization"]
        return out


async def _ask(client: ServiceCaller, service: str, args: dict | None, timeout: float) -> dict | None:
    try:
        values = await client.call_service(service, args or {}, timeout=timeout)
    except (TimeoutError, BridgeError) as exc:
        log.debug("%s: %s", service, exc)
        return None
    return values if isinstance(values, dict) else None


def _json_text(value: object) -> str:
    """A rosapi 0.11 parameter value (JSON text of a string, e.g. ``"\\"noetic\\n\\""``) as plain text."""
    if not isinstance(value, str):
        return ""
    try:
        decoded = json_text_value(value)
    except ValueError:
        decoded = value
    if not isinstance(decoded, str | int | float):
        return ""
    return str(decoded).strip() if decoded is not None else ""


async def detect(client: ServiceCaller, timeout: float | None = None, quick: bool = False) -> RosInfo:
    """Ask the server which ROS it runs (see the module docstring).  ``quick``: only steps 1 and the rosapi
    listing -- enough for ``rosapi_guard`` (its hazards are rosapi 2.x's, which always has
    ``get_ros_version``); ``version`` stays None when those do not tell."""
    budget = min(client.call_timeout, 3.0) if timeout is None else timeout
    listing = await _ask(client, "/rosapi/services", None, budget)
    services = tuple(s for s in (listing or {}).get("services", []) if isinstance(s, str) and s.startswith("/rosapi/"))
    version = await _ask(client, "/rosapi/get_ros_version", None, budget) if listing is None or \
        "/rosapi/get_ros_version" in services else None
    if version is not None and version.get("version") in (1, 2):
        return RosInfo(int(version["version"]), str(version.get("distro", "")).strip(), "get_ros_version", services)
    if listing is None:
        return RosInfo(None, "", "no rosapi answered", services)
    if quick:
        return RosInfo(None, "", "rosapi listing (no get_ros_version)", services)
    topics_type = await _ask(client, "/rosapi/service_type", {"service": "/rosapi/topics"}, budget)
    spelled = str((topics_type or {}).get("type", ""))
    if spelled.startswith("rosapi_msgs/"):
        return RosInfo(2, "", "rosapi service types (rosapi_msgs)", services)
    rosversion = await _ask(client, "/rosapi/get_param", {"name": "/rosversion"}, budget)
    distro = await _ask(client, "/rosapi/get_param", {"name": "/rosdistro"}, budget)
    text = _json_text((rosversion or {}).get("value"))
    if text[:1] in ("1", "2"):
        return RosInfo(int(text[0]), _json_text((distro or {}).get("value")), "/rosversion parameter", services)
    if spelled.startswith("rosapi/"):
        return RosInfo(1, "", "rosapi service types (rosapi)", services)
    return RosInfo(None, "", "rosapi answered, version unclear", services)
