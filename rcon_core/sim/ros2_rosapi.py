"""The /rosapi services of the sim in ROS 2 mode, in the shapes of rosapi 2.x (rosbridge_suite 2.1.0).

Differences from the ROS 1 rosapi (``rosapi.py``), as the ros2 branch's ``rosapi_node`` has them:

* services are typed ``rosapi_msgs/srv/<Name>`` (not ``rosapi/<Name>``); there is no ``search_param`` and no
  ``service_host``; ``get_ros_version`` answers ``{"version": 2, "distro": "<ROS_DISTRO>"}``;
* parameters belong to nodes and are named ``<node>:<param>`` (``ros2_params.py``); ``get_param``'s request
  field is ``default_value``;
* ``message_details`` of a type it cannot load answers an empty ``typedefs`` list (rosapi logs the error);
  that includes an action's parts (``pkg/action/<Name>_Goal``, ``_Result``, ``_Feedback``): rosapi looks
  for them as attributes of the package's ``action`` module, which exports only ``<Name>``;
* ``action_servers`` lists every action with a server: the sim's own and those clients advertised
  (rosapi finds them from the hidden ``<action>/_action/{feedback,status}`` topics, which ``topic_type``
  ignores);
* like rosapi after 2.1.0 (its ros2 branch now), ``action_type`` (``action`` -> ``type``) and
  ``action_{goal,result,feedback}_details`` (``type`` -> ``typedefs``) tell an action's type and layout;
  a 2.1.0 server has neither, and a client falls back (``Rosapi.action_type`` answers None);
* no ``get_loggers``/``set_logger_level`` services (those are ROS 1 node services); every node has its
  ROS 2 parameter services instead (``ros2_param_services.py``).
"""

from __future__ import annotations

import re
from typing import TYPE_CHECKING, Any

from rcon_core.msgs.names import pkg_type

from .graph import BRIDGE_NODE, ROSAPI_NODE, ROSOUT_NODE
from .ros2_params import NodeParameters, get_param_value, set_param_value, split_name
from .rosapi import SEPARATOR, Rosapi, fail

if TYPE_CHECKING:
    from .server import SimServer

_MSG_SPELLING = re.compile(r"\b([A-Za-z][A-Za-z0-9_]*)/msg/")
_TIME_MSGS = {"time": "builtin_interfaces/Time", "duration": "builtin_interfaces/Duration"}
_TIME_TEXT = {"builtin_interfaces/Time": "int32 sec\nuint32 nanosec\n",
              "builtin_interfaces/Duration": "int32 sec\nuint32 nanosec\n"}


#: what ``get_ros_version`` reports as ``distro`` (the ROS_DISTRO of the machine running rosapi)
DISTRO = "jazzy"

_SERVICES: list[tuple[str, str]] = [
    ("topics", "Topics"), ("topics_for_type", "TopicsForType"), ("topics_and_raw_types", "TopicsAndRawTypes"),
    ("services", "Services"), ("services_for_type", "ServicesForType"), ("nodes", "Nodes"),
    ("node_details", "NodeDetails"), ("action_servers", "GetActionServers"), ("topic_type", "TopicType"),
    ("service_type", "ServiceType"), ("publishers", "Publishers"), ("subscribers", "Subscribers"),
    ("service_providers", "ServiceProviders"), ("service_node", "ServiceNode"),
    ("message_details", "MessageDetails"), ("service_request_details", "ServiceRequestDetails"),
    ("service_response_details", "ServiceResponseDetails"), ("set_param", "SetParam"),
    ("get_param", "GetParam"), ("has_param", "HasParam"), ("delete_param", "DeleteParam"),
    ("get_param_names", "GetParamNames"), ("get_time", "GetTime"), ("get_ros_version", "GetROSVersion"),
    # added to rosapi after 2.1.0 (its ros2 branch now): how a client learns an action's type and layout
    ("action_type", "ActionType"), ("action_goal_details", "ActionGoalDetails"),
    ("action_result_details", "ActionResultDetails"), ("action_feedback_details", "ActionFeedbackDetails"),
]


def _bridge_parameters(server: SimServer) -> dict[str, Any]:
    """The parameters rosbridge_websocket 2.1.0 declares (with the sim's values)."""
    return {"port": 9090, "address": "", "url_path": "/", "retry_startup_delay": 2.0,
            "websocket_ping_interval": 0, "websocket_ping_timeout": 30, "certfile": "", "keyfile": "",
            "actual_port": server.port, "use_compression": False, "call_services_in_new_thread": False,
            "send_action_goals_in_new_thread": False, "fragment_timeout": 600, "delay_between_messages": 0.0,
            "max_message_size": 10_000_000, "unregister_timeout": 10.0, "bson_only_mode": False,
            "topics_glob": "", "services_glob": "", "params_glob": ""}


def _is_action_part(registry: Any, type_name: str) -> bool:
    """True when ``type_name`` (any spelling) names a part of an action (``<Name>_Goal`` ...)."""
    if registry is None:
        return "/action/" in type_name
    from rcon_core.msgs import names

    try:
        return names.action_part(registry.resolve(type_name)) is not None
    except (KeyError, ValueError):
        return False


class Ros2Rosapi(Rosapi):
    """rosapi 2.x handlers; graph queries are shared with the ROS 1 flavour."""

    distro = DISTRO

    def __init__(self, server: SimServer) -> None:
        super().__init__(server)
        self.node_params = NodeParameters(self._initial_parameters)

    def _initial_parameters(self, node: str) -> dict[str, Any] | None:
        if node == BRIDGE_NODE:
            return _bridge_parameters(self.server)
        if node == ROSAPI_NODE:
            return {"topics_glob": "[*]", "services_glob": "[*]", "params_glob": "[*]"}
        tree = self.server.params_tree.get(node)
        if isinstance(tree, dict):
            return tree
        return {} if node in self._node_names() else None

    def _param_nodes(self) -> list[str]:
        nodes = self._node_names()
        if BRIDGE_NODE not in nodes:
            nodes.append(BRIDGE_NODE)
        # rosapi leaves itself out; /rosout is the sim's stand-in publisher of /rosout, no ROS 2 node
        return [n for n in nodes if n not in (ROSAPI_NODE, ROSOUT_NODE)]

    # -- versions and types ---------------------------------------------------------------------------

    def get_ros_version(self, args: dict[str, Any]) -> dict[str, Any]:
        return {"version": 2, "distro": self.distro}

    def message_details(self, args: dict[str, Any]) -> dict[str, Any]:
        type_name = args.get("type", "")
        if _is_action_part(self.server.types.registry, type_name):
            return {"typedefs": []}  # rosapi looks for <Name>_Goal where the package does not export it
        return {"typedefs": self.server.types.typedefs(type_name) or []}

    def _action_part_details(self, args: dict[str, Any], part: str) -> dict[str, Any]:
        """rosapi 2.x's ``action_{goal,result,feedback}_details``: the typedefs of one part of the action
        type ``type`` (``pkg/action/X``), empty for a type it cannot load."""
        parts = str(args.get("type", "")).strip("/").split("/")
        if len(parts) not in (2, 3) or not all(parts):
            return {"typedefs": []}
        return {"typedefs": self.server.types.typedefs(f"{parts[0]}/action/{parts[-1]}_{part}") or []}

    def action_goal_details(self, args: dict[str, Any]) -> dict[str, Any]:
        return self._action_part_details(args, "Goal")

    def action_result_details(self, args: dict[str, Any]) -> dict[str, Any]:
        return self._action_part_details(args, "Result")

    def action_feedback_details(self, args: dict[str, Any]) -> dict[str, Any]:
        return self._action_part_details(args, "Feedback")

    def action_servers(self, args: dict[str, Any]) -> dict[str, Any]:
        hub = self.server.action_hub
        return {"action_servers": hub.names() if hub is not None else []}

    def action_type(self, args: dict[str, Any]) -> dict[str, Any]:
        """rosapi's ``action_type`` (after 2.1.0): the type of the action named ``action``, ``""`` when none."""
        hub = self.server.action_hub
        provider = hub.providers.get(str(args.get("action", ""))) if hub is not None else None
        if provider is None:
            return {"type": ""}
        parts = str(provider.type).strip("/").split("/")
        return {"type": f"{parts[0]}/action/{parts[-1]}"}

    def _full_text(self, type_name: str) -> str:
        """rosapi 2.x's ``typedefs_full_text``: the root's definition, then each message type it uses once,
        depth first from the *last* field (rosapi walks a stack), each after a ``====`` line and
        ``MSG: pkg/Type``; types are written ``pkg/Type`` and the time types are
        ``builtin_interfaces/Time``/``Duration`` messages.  (A real server sends the .msg files' text,
        comments included; the sim has no comments to give.)"""
        reg = self.server.types.registry
        if reg is None:
            return ""
        try:
            out, seen, stack, first = [], set(), [type_name], True
            while stack:
                name = stack.pop()
                if not first:
                    out.append(f"\n{SEPARATOR}\nMSG: {pkg_type(name)}\n")
                first = False
                if name in _TIME_TEXT:
                    out.append(_TIME_TEXT[name])
                    continue
                out.append(_MSG_SPELLING.sub(r"\1/", reg.definition_text(name)))
                for f in reg.fields(name):
                    dep = _TIME_MSGS.get(f.base) or (f.base if not f.is_builtin else None)
                    if dep is not None and pkg_type(dep) not in seen:
                        seen.add(pkg_type(dep))
                        stack.append(dep)
            return "".join(out)
        except Exception:  # noqa: BLE001 - a type without text still lists
            return ""

    # -- parameters -----------------------------------------------------------------------------------

    def get_param(self, args: dict[str, Any]) -> dict[str, Any]:
        return {"value": get_param_value(self.node_params, args.get("name", ""), args.get("default_value", ""))}

    def set_param(self, args: dict[str, Any]) -> dict[str, Any]:
        try:
            set_param_value(self.node_params, args.get("name", ""), args.get("value", ""))
        except ValueError as exc:
            raise fail(str(exc)) from exc
        return {}

    def has_param(self, args: dict[str, Any]) -> dict[str, Any]:
        where = split_name(args.get("name", ""))
        return {"exists": where is not None and self.node_params.get(*where)[0]}

    def delete_param(self, args: dict[str, Any]) -> dict[str, Any]:
        where = split_name(args.get("name", ""))
        if where is not None:
            self.node_params.delete(*where)
        return {}

    def get_param_names(self, args: dict[str, Any]) -> dict[str, Any]:
        names: list[str] = []
        for node in self._param_nodes():
            names.extend(self.node_params.names(node))
        return {"names": names}


def install(server: SimServer) -> Ros2Rosapi:
    """Register the rosapi 2.x services on ``server``."""
    api = Ros2Rosapi(server)
    for name, type_base in _SERVICES:
        server.add_service(f"/rosapi/{name}", f"rosapi_msgs/srv/{type_base}", ROSAPI_NODE, getattr(api, name))
    server.rosapi = api
    from .ros2_param_services import add_parameter_services

    for node in (BRIDGE_NODE, ROSAPI_NODE):
        add_parameter_services(server, node)
    server.log(ROSAPI_NODE, "info", "Rosapi started", function="<module>")
    return api
