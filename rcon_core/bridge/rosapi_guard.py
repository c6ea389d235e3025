"""Which rosapi calls RCON may send to a server, and which would hurt it.

Decision: never kill rosapi
    Some rosapi calls make ``rosapi_node`` of rosbridge_suite 2.1.0 raise inside its service handler; the
    exception escapes ``rclpy.spin`` and the node **exits**.  The calling connection never gets an answer
    and, since rosbridge 2.1.0 runs one call at a time per connection with no timeout, stays wedged; every
    other client loses rosapi too (``rosbridge-ros2-2.1.0/rosapi.jsonl:64-77``: each followed by a probe that
    finds ``/rosapi/*`` gone).  RCON never sends one of them to a ROS 2 server that is not known to be fixed;
    :func:`refusal` says why, and the client raises :class:`~rcon_core.bridge.errors.RosapiRefusedError`
    before anything is written.  The calls, and what RCON does instead:

    * ``has_param`` of a parameter the node lacks (``rosapi.jsonl:64``): never needed -- ``client.params``
      reads parameters from the nodes' own services (``params.py``);
    * ``node_details`` of a node that does not exist (``:66``): asked only for a node ``/rosapi/nodes`` lists;
    * every ``delete_param`` (``:68``; the handler reads a field ``DeleteParam`` does not have);
    * ``set_param`` whose value is not JSON text (``:70``): RCON always sends JSON text;
    * ``message_details`` of a name without ``/`` (``:72``);
    * ``service_request_details`` / ``service_response_details`` of a type no listed service has (``:74``:
      an import error rosapi does not catch; fixed in 2.7.0, #1239);
    * ``get_param`` (and the other parameter calls) on rosapi's own node (``:76``): a deadlock, not an exit,
      but rosapi answers nobody afterwards (fixed in 2.2.0, #978);
    * on Jazzy (and later distros), ``message_details`` and the service details at all: a stock 2.1.0 rosapi
      dies on the ``_check_fields`` slot of every Jazzy message class (upstream #976, fixed in 2.3.0 by
      #1031; the recorded server carries that fix as a patch, which a client cannot see).  RCON reads the
      ``.msg`` text from ``topics_and_raw_types`` instead, or uses its own definitions;
    * ``get_param_names``: a stock 2.1.0 dies or hangs on it (reworked in 2.2.0, #978/#1001); RCON lists
      parameters through the nodes' ``list_parameters`` services instead;
    * ``action_type``: it has never answered in any release (2.4.0 added it, #1046, and it raises inside
      rosapi, taking the node down; fixed upstream by #1307 after 2.7.1), so RCON does not ask a
      rosbridge_suite server for it (see :func:`action_type_works`).

Decision: how RCON tells 2.1.0 from a fixed server
    rosapi has no version call (``get_ros_version`` names the ROS distro, not rosbridge's release), so RCON
    reads the release from the **services rosapi lists** (``/rosapi/services``, asked once per connection;
    ``rosinfo.py``): ``/rosapi/interfaces`` appeared in 2.2.0 (#988), ``/rosapi/action_goal_details``
    (with the result and feedback ones) in 2.3.0 (#1021), ``/rosapi/action_type`` in 2.4.0 (#1046).  A
    listing without any of them is treated as 2.1.0 *as shipped*.  A hazard is lifted only from the release
    that fixed it on (the table in ``docs/protocols.md``).  The fix of ``action_type`` (#1307) shows nothing
    on the wire, so a listing that has ``action_type`` *and* the 2.2.0+ ``interfaces`` (every release that
    has the broken one) is trusted with nothing; a rosapi listing ``action_type`` without ``interfaces`` is
    not one of those releases (``rcon sim --ros2`` plays such a rosapi), and its ``action_type`` is used.

Decision: a rosapi service the server does not list is not asked
    Asking for one is not harmless either: rosbridge answers "Service /rosapi/x does not exist" and logs an
    ERROR into the robot's own ``/rosout`` every time (``rosapi.jsonl:62-63``).  Once ``/rosapi/services``
    answered on a connection, a ``/rosapi/*`` call it does not list is refused here too, on any ROS.

ROS 1 rosapi (0.11) has none of the other hazards; nothing else is refused there, nor before the server's
ROS is known (a rosapi call waits for the listing, asked once per connection: ``client.rosapi_profile``).
"""

from __future__ import annotations

import json
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .rosinfo import RosInfo

#: rosapi services whose arguments can hurt a 2.x rosapi: the only calls the guard looks at
GUARDED = frozenset({"has_param", "node_details", "delete_param", "set_param", "get_param", "message_details",
                     "service_request_details", "service_response_details", "get_param_names", "action_type"})
#: distros whose message classes have no ``_check_fields`` slot (#976 cannot happen there)
_OLD_DISTROS = ("humble", "iron", "galactic", "foxy", "eloquent", "dashing")


def rosapi_name(service: str) -> str | None:
    """``"has_param"`` for ``"/rosapi/has_param"`` (a leading namespace allowed), else None."""
    parts = service.rstrip("/").split("/")
    if len(parts) >= 3 and parts[-2] == "rosapi" and parts[-1]:
        return parts[-1]
    return None


def at_least(info: RosInfo, release: str) -> bool:
    """True when the server's rosapi listing shows it is at least ``release`` ("2.2.0", "2.3.0", "2.4.0")."""
    listed = set(info.rosapi_services)
    markers = {"2.2.0": ("interfaces", "action_goal_details", "action_type"),
               "2.3.0": ("action_goal_details", "action_result_details", "action_feedback_details",
                         "action_type"),
               "2.4.0": ("action_type",)}[release]
    return any(f"/rosapi/{m}" in listed for m in markers)


def action_type_works(info: RosInfo) -> bool:
    """Whether ``/rosapi/action_type`` may be asked (see "how RCON tells 2.1.0 from a fixed server")."""
    listed = set(info.rosapi_services)
    return "/rosapi/action_type" in listed and "/rosapi/interfaces" not in listed


def _jazzy_or_later(info: RosInfo) -> bool:
    distro = (info.distro or "").lower()
    return not distro.startswith(_OLD_DISTROS)


def refusal(service: str, args: Any, info: RosInfo | None, *, node_listed: bool | None = None,
            type_listed: bool | None = None) -> str | None:
    """Why ``call_service(service, args)`` must not reach this server (None: it may).

    ``node_listed``: whether ``/rosapi/nodes`` lists the node ``node_details`` asks about; ``type_listed``:
    whether a listed service has the type the service details ask about (None: not known; see
    :func:`needs`)."""
    name = rosapi_name(service)
    if name is None or info is None:
        return None
    if info.rosapi_services and service not in info.rosapi_services and f"/rosapi/{name}" not in \
            info.rosapi_services:
        return f"the robot's rosapi does not list {service} (asking would only log an error on the robot)"
    if name not in GUARDED or info.version != 2:
        return None
    args = args if isinstance(args, dict) else {}
    stock = "a rosbridge 2.1.0 rosapi"
    if name == "has_param" and not at_least(info, "2.2.0"):
        return f"has_param of a parameter the node lacks kills {stock} (rosapi.jsonl:64); RCON reads parameters " \
               "from the node's own get_parameters service instead"
    if name == "delete_param" and not at_least(info, "2.2.0"):
        return f"delete_param kills {stock} (it reads a field DeleteParam does not have, rosapi.jsonl:68)"
    if name == "get_param_names" and not at_least(info, "2.2.0"):
        return f"get_param_names kills or hangs {stock} as shipped; RCON lists parameters through each node's " \
               "list_parameters service instead"
    if name in ("get_param", "set_param", "has_param", "delete_param") and not at_least(info, "2.2.0"):
        node = str(args.get("name", "")).split(":", 1)[0]
        if node.rstrip("/").rsplit("/", 1)[-1] in ("rosapi", "rosapi_params"):
            return f"a parameter of rosapi's own node deadlocks {stock} (rosapi.jsonl:76)"
    if name == "set_param" and not _is_json_text(args.get("value")):
        return f"set_param needs the value as JSON text; anything else kills {stock} (rosapi.jsonl:70)"
    if name == "message_details":
        type_name = args.get("type")
        if not isinstance(type_name, str) or "/" not in type_name:
            return f"message_details of a name without '/' kills {stock} (rosapi.jsonl:72)"
    if name in ("message_details", "service_request_details", "service_response_details") \
            and _jazzy_or_later(info) and not at_least(info, "2.3.0"):
        return f"{name} kills {stock} on {info.distro or 'Jazzy'} (the _check_fields slot, fixed in 2.3.0); " \
               "the type is read from topics_and_raw_types or RCON's own definitions instead"
    if name in ("service_request_details", "service_response_details") and type_listed is False:
        return f"{name} of a type no service on the robot has kills {stock} (rosapi.jsonl:74)"
    if name == "node_details" and node_listed is False:
        return f"node_details of a node that does not exist kills {stock} (rosapi.jsonl:66)"
    if name == "action_type" and not action_type_works(info):
        return "/rosapi/action_type is not answered by this rosapi (2.1.0 lacks it; 2.4.0-2.7.1 crash on it, #1307)"
    return None


def needs(service: str, info: RosInfo | None) -> str | None:
    """What the client must look up before :func:`refusal` can judge this call on this server:
    ``"node"`` (is the node listed?), ``"type"`` (does a listed service have the type?) or None."""
    name = rosapi_name(service)
    if info is None or info.version != 2:
        return None
    if name == "node_details":
        return "node"
    if name in ("service_request_details", "service_response_details"):
        return "type"
    return None


def _is_json_text(value: Any) -> bool:
    if not isinstance(value, str):
        return False
    try:
        json.loads(value)
    except ValueError:
        return False
    return True
