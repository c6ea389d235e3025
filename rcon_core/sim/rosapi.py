"""The /rosapi services of the sim, answering in the real rosapi's shapes (rosbridge_suite 0.11.17).

ROS 2 mode uses the subclass in ``ros2_rosapi.py`` (rosapi 2.x: ``rosapi_msgs`` types, node parameters).
"""

from __future__ import annotations

import json
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from rcon_core.msgs.names import pkg_type

from .graph import BRIDGE_NODE, ROSAPI_NODE, ROSOUT_NODE, ServiceFailure
from .params import ParamTree

if TYPE_CHECKING:
    from .server import SimServer

_LOGGER_NAMES = ["rosgraph", "rospy", "rospy.core", "rospy.internal", "rospy.service", "rospy.tcpros",
                 "rospy.topics", "rosout", "rospy.client", "rospy.registration", "rospy.init", "rospy.rosout",
                 "rospy.simtime", "xmlrpc"]
_LEVELS = {"debug": "DEBUG", "info": "INFO", "warn": "WARN", "warning": "WARN", "error": "ERROR",
           "fatal": "FATAL"}
SEPARATOR = "=" * 80


def fail(text: str) -> ServiceFailure:
    """A service failure in the words rosapi uses (``error processing request: ...``)."""
    return ServiceFailure(f"error processing request: {text}")


class Rosapi:
    """Handlers for every /rosapi service, bound to one server."""

    def __init__(self, server: SimServer) -> None:
        self.server = server
        self.params: ParamTree = server.params_tree
        self.loggers: dict[str, dict[str, str]] = {}

    # -- graph --------------------------------------------------------------------------------------

    def _live_topics(self) -> list[Any]:
        return [t for t in self.server.topics.values() if t.is_alive()]

    def topics(self, args: dict[str, Any]) -> dict[str, Any]:
        live = self._live_topics()
        return {"topics": [t.name for t in live], "types": [t.type for t in live]}

    def topics_for_type(self, args: dict[str, Any]) -> dict[str, Any]:
        wanted = pkg_type(args.get("type", ""))
        return {"topics": [t.name for t in self._live_topics() if pkg_type(t.type) == wanted]}

    def topics_and_raw_types(self, args: dict[str, Any]) -> dict[str, Any]:
        live = self._live_topics()
        return {"topics": [t.name for t in live], "types": [t.type for t in live],
                "typedefs_full_text": [self._full_text(t.type) for t in live]}

    def _full_text(self, type_name: str) -> str:
        reg = self.server.types.registry
        if reg is None:
            return ""
        try:
            parts = [reg.definition_text(type_name)]
            for td in (self.server.types.typedefs(type_name) or [])[1:]:
                if td["type"] in ("time", "duration"):
                    continue
                parts.append(f"\n{SEPARATOR}\nMSG: {td['type']}\n{reg.definition_text(td['type'])}")
            return "".join(parts)
        except Exception:  # noqa: BLE001 - a type without text still lists
            return ""

    def topic_type(self, args: dict[str, Any]) -> dict[str, Any]:
        topic = self.server.topics.get(args.get("topic", ""))
        return {"type": topic.type if topic is not None and topic.is_alive() else ""}

    def publishers(self, args: dict[str, Any]) -> dict[str, Any]:
        topic = self.server.topics.get(args.get("topic", ""))
        return {"publishers": [n for n, c in topic.publishers.items() if c > 0] if topic else []}

    def subscribers(self, args: dict[str, Any]) -> dict[str, Any]:
        topic = self.server.topics.get(args.get("topic", ""))
        return {"subscribers": topic.subscriber_nodes() if topic else []}

    def services(self, args: dict[str, Any]) -> dict[str, Any]:
        return {"services": list(self.server.services)}

    def services_for_type(self, args: dict[str, Any]) -> dict[str, Any]:
        wanted = pkg_type(args.get("type", ""))
        return {"services": [s.name for s in self.server.services.values() if pkg_type(s.type) == wanted]}

    def service_type(self, args: dict[str, Any]) -> dict[str, Any]:
        svc = self.server.services.get(args.get("service", ""))
        return {"type": svc.type if svc else ""}

    def service_providers(self, args: dict[str, Any]) -> dict[str, Any]:
        # rosapi 0.11 matches the field named `service` against service TYPES
        wanted = pkg_type(args.get("service", ""))
        return {"providers": [s.node for s in self.server.services.values() if pkg_type(s.type) == wanted]}

    def service_node(self, args: dict[str, Any]) -> dict[str, Any]:
        svc = self.server.services.get(args.get("service", ""))
        return {"node": svc.node if svc else ""}

    def service_host(self, args: dict[str, Any]) -> dict[str, Any]:
        svc = self.server.services.get(args.get("service", ""))
        return {"host": self.server.host if svc else ""}

    def nodes(self, args: dict[str, Any]) -> dict[str, Any]:
        return {"nodes": self._node_names()}

    def _node_names(self) -> list[str]:
        seen: dict[str, None] = {}
        for topic in self.server.topics.values():
            for node, count in topic.publishers.items():
                if count > 0:
                    seen[node] = None
            for node in topic.subscriber_nodes():
                seen[node] = None
        for svc in self.server.services.values():
            seen[svc.node] = None
        return list(seen)

    def node_details(self, args: dict[str, Any]) -> dict[str, Any]:
        node = args.get("node", "")
        topics = self.server.topics.values()
        return {
            "subscribing": sorted(t.name for t in topics if node in t.subscriber_nodes()),
            "publishing": sorted(t.name for t in topics if t.publishers[node] > 0),
            "services": sorted(s.name for s in self.server.services.values() if s.node == node),
        }

    def action_servers(self, args: dict[str, Any]) -> dict[str, Any]:
        actions = self.server.navigate_action
        return {"action_servers": [actions.name] if actions is not None else []}

    # -- types --------------------------------------------------------------------------------------

    def message_details(self, args: dict[str, Any]) -> dict[str, Any]:
        type_name = args.get("type", "")
        typedefs = self.server.types.typedefs(type_name)
        if not typedefs:
            raise fail(f"Unable to load the type {type_name}: unknown message type")
        return {"typedefs": typedefs}

    def _service_details(self, args: dict[str, Any], part: str) -> dict[str, Any]:
        type_name = args.get("type", "")
        typedefs = self.server.types.service_typedefs(type_name, part)
        if typedefs is None:
            raise fail(f"Unable to load the service type {type_name}: unknown service type")
        return {"typedefs": typedefs}

    def service_request_details(self, args: dict[str, Any]) -> dict[str, Any]:
        return self._service_details(args, "request")

    def service_response_details(self, args: dict[str, Any]) -> dict[str, Any]:
        return self._service_details(args, "response")

    # -- params -------------------------------------------------------------------------------------

    def get_param(self, args: dict[str, Any]) -> dict[str, Any]:
        name = args.get("name", "")
        if self.params.has(name):
            return {"value": json.dumps(self.params.get(name))}
        default = args.get("default", "")
        if default:
            try:
                return {"value": json.dumps(json.loads(default))}
            except ValueError as exc:
                raise fail(f"the default for get_param must be JSON text: {exc}") from exc
        return {"value": "null"}

    def set_param(self, args: dict[str, Any]) -> dict[str, Any]:
        try:
            value = json.loads(args.get("value", ""))
        except ValueError as exc:
            raise fail("Due to the type flexibility of the ROS parameter server, the value argument to "
                        "set_param must be a JSON-formatted string.") from exc
        self.params.set(args.get("name", ""), value)
        return {}

    def has_param(self, args: dict[str, Any]) -> dict[str, Any]:
        return {"exists": self.params.has(args.get("name", ""))}

    def delete_param(self, args: dict[str, Any]) -> dict[str, Any]:
        self.params.delete(args.get("name", ""))
        return {}

    def search_param(self, args: dict[str, Any]) -> dict[str, Any]:
        name = args.get("name", "")
        if name.startswith("/"):
            return {"global_name": name if self.params.has(name) else ""}
        for candidate in (f"{ROSAPI_NODE}/{name}", f"/{name}"):
            if self.params.has(candidate):
                return {"global_name": candidate}
        return {"global_name": ""}

    def get_param_names(self, args: dict[str, Any]) -> dict[str, Any]:
        return {"names": self.params.names()}

    # -- misc ---------------------------------------------------------------------------------------

    def get_time(self, args: dict[str, Any]) -> dict[str, Any]:
        return {"time": self.server.flavour.time()}

    def get_loggers_for(self, node: str) -> Callable[[dict[str, Any]], dict[str, Any]]:
        table = self.loggers.setdefault(node, {name: "INFO" for name in _LOGGER_NAMES})

        def get_loggers(args: dict[str, Any]) -> dict[str, Any]:
            return {"loggers": [{"name": n, "level": lvl} for n, lvl in table.items()]}

        return get_loggers

    def set_logger_level_for(self, node: str) -> Callable[[dict[str, Any]], dict[str, Any]]:
        table = self.loggers.setdefault(node, {name: "INFO" for name in _LOGGER_NAMES})

        def set_logger_level(args: dict[str, Any]) -> dict[str, Any]:
            level = _LEVELS.get(str(args.get("level", "")).lower())
            if level is None:
                raise fail(f"unknown logger level {args.get('level')!r}: use debug, info, warn, error or fatal")
            table[args.get("logger", "")] = level
            return {}

        return set_logger_level


_SERVICES: list[tuple[str, str]] = [
    ("topics", "Topics"), ("topics_for_type", "TopicsForType"), ("services", "Services"),
    ("services_for_type", "ServicesForType"), ("nodes", "Nodes"), ("node_details", "NodeDetails"),
    ("action_servers", "GetActionServers"), ("topic_type", "TopicType"), ("service_type", "ServiceType"),
    ("publishers", "Publishers"), ("subscribers", "Subscribers"), ("service_providers", "ServiceProviders"),
    ("service_node", "ServiceNode"), ("service_host", "ServiceHost"), ("message_details", "MessageDetails"),
    ("service_request_details", "ServiceRequestDetails"),
    ("service_response_details", "ServiceResponseDetails"), ("set_param", "SetParam"),
    ("get_param", "GetParam"), ("has_param", "HasParam"), ("search_param", "SearchParam"),
    ("delete_param", "DeleteParam"), ("get_param_names", "GetParamNames"), ("get_time", "GetTime"),
    ("topics_and_raw_types", "TopicsAndRawTypes"),
]


def add_logger_services(server: SimServer, api: Rosapi, node: str) -> None:
    """``<node>/get_loggers`` and ``<node>/set_logger_level``, as every rospy node has; in ROS 2 mode the
    node's parameter services instead (``ros2_param_services.py``)."""
    if server.ros2:
        from .ros2_param_services import add_parameter_services

        add_parameter_services(server, node)
        return
    server.add_service(f"{node}/get_loggers", "roscpp/GetLoggers", node, api.get_loggers_for(node))
    server.add_service(f"{node}/set_logger_level", "roscpp/SetLoggerLevel", node, api.set_logger_level_for(node))


def install(server: SimServer) -> Rosapi:
    """Register the /rosapi services (and the bridge nodes' logger services) on a ROS 1 ``server`` (a ROS 2
    server gets the rosapi 2.x set of ``ros2_rosapi.py``)."""
    api = Rosapi(server)
    add_logger_services(server, api, ROSOUT_NODE)
    add_logger_services(server, api, ROSAPI_NODE)
    for name, type_base in _SERVICES:
        server.add_service(f"/rosapi/{name}", server.flavour.srv("rosapi", type_base), ROSAPI_NODE,
                           getattr(api, name))
    add_logger_services(server, api, BRIDGE_NODE)
    server.rosapi = api
    server.log(ROSAPI_NODE, "info", "Rosapi started", function="<module>")
    return api
