"""TypeRegistry: lookup in every spelling, bundled definitions, defaults, learning, definition text."""

import time

import pytest

from rcon_core.msgs import FieldDef, TypeRegistry, UnknownTypeError

ROSAPI_SERVICES = [
    "topics", "topics_for_type", "topics_and_raw_types", "services", "services_for_type", "nodes",
    "node_details", "action_servers", "topic_type", "service_type", "publishers", "subscribers",
    "service_providers", "service_node", "service_host", "message_details", "service_request_details",
    "service_response_details", "set_param", "get_param", "has_param", "search_param", "delete_param",
    "get_param_names", "get_time",
]
ROSAPI_TYPES = {
    "topics": "Topics", "topics_for_type": "TopicsForType", "topics_and_raw_types": "TopicsAndRawTypes",
    "services": "Services", "services_for_type": "ServicesForType", "nodes": "Nodes",
    "node_details": "NodeDetails", "action_servers": "GetActionServers", "topic_type": "TopicType",
    "service_type": "ServiceType", "publishers": "Publishers", "subscribers": "Subscribers",
    "service_providers": "ServiceProviders", "service_node": "ServiceNode", "service_host": "ServiceHost",
    "message_details": "MessageDetails", "service_request_details": "ServiceRequestDetails",
    "service_response_details": "ServiceResponseDetails", "set_param": "SetParam", "get_param": "GetParam",
    "has_param": "HasParam", "search_param": "SearchParam", "delete_param": "DeleteParam",
    "get_param_names": "GetParamNames", "get_time": "GetTime",
}


@pytest.fixture(scope="module")
def reg():
    return TypeRegistry.standard()


@pytest.mark.parametrize("spelling", ["geometry_msgs/Twist", "geometry_msgs/msg/Twist", "/geometry_msgs/Twist"])
def test_either_spelling(reg, spelling):
    assert reg.has(spelling)
    assert reg.resolve(spelling) == "geometry_msgs/msg/Twist"
    assert [f.name for f in reg.fields(spelling)] == ["linear", "angular"]


def test_fielddefs(reg):
    imu = {f.name: f for f in reg.fields("sensor_msgs/Imu")}
    assert imu["header"] == FieldDef("header", "std_msgs/msg/Header", "std_msgs/msg/Header", None, False)
    assert imu["orientation_covariance"] == FieldDef(
        "orientation_covariance", "float64[9]", "float64", 9, True
    )
    scan = {f.name: f for f in reg.fields("sensor_msgs/LaserScan")}
    assert (scan["ranges"].base, scan["ranges"].array_len, scan["ranges"].type) == ("float32", 0, "float32[]")
    header = {f.name: f for f in reg.fields("std_msgs/Header")}
    assert header["stamp"] == FieldDef("stamp", "time", "time", None, True)
    log = {f.name: f for f in reg.fields("rosgraph_msgs/Log")}
    assert log["level"].base == "byte" and log["topics"].type == "string[]"


def test_constants(reg):
    assert reg.constants("rosgraph_msgs/Log") == {"DEBUG": 1, "INFO": 2, "WARN": 4, "ERROR": 8, "FATAL": 16}
    assert reg.constants("sensor_msgs/NavSatStatus")["STATUS_FIX"] == 0
    assert reg.constants("geometry_msgs/Twist") == {}


def test_bundled_std_srvs(reg):
    for srv in ("std_srvs/Empty", "std_srvs/SetBool", "std_srvs/Trigger"):
        assert reg.has(srv) and reg.has_service(srv)
    assert reg.default(reg.service_part_name("std_srvs/SetBool", "request")) == {"data": False}
    assert reg.default("std_srvs/TriggerResponse") == {"success": False, "message": ""}
    assert reg.default("std_srvs/srv/Empty_Request") == {}


def test_every_rosapi_service_the_real_server_lists_is_bundled(reg):
    listed = {
        "/rosapi/" + s for s in ROSAPI_SERVICES
    }
    assert len(listed) == 25
    for service in ROSAPI_SERVICES:
        srv = "rosapi/" + ROSAPI_TYPES[service]
        assert reg.has_service(srv), srv
    # shapes the recording shows
    assert [f.name for f in reg.fields("rosapi/NodeDetailsResponse")] == ["subscribing", "publishing", "services"]
    assert [f.name for f in reg.fields("rosapi/GetParamRequest")] == ["name", "default"]
    assert reg.default("rosapi/GetTimeResponse") == {"time": {"secs": 0, "nsecs": 0}}
    assert reg.fields("rosapi/MessageDetailsResponse")[0].base == "rosapi/msg/TypeDef"
    assert [f.name for f in reg.fields("rosapi/TopicsAndRawTypesResponse")] == [
        "topics", "types", "typedefs_full_text"
    ]
    assert reg.has_service("roscpp/GetLoggers") and reg.has_service("roscpp/SetLoggerLevel")
    assert reg.default("roscpp/SetLoggerLevelRequest") == {"logger": "", "level": ""}


def test_log_types_for_both_flavours():
    assert TypeRegistry.standard().has("rosgraph_msgs/Log")
    ros2 = TypeRegistry.standard(ros2=True)
    assert ros2.has("rcl_interfaces/msg/Log")
    assert ros2.default("rcl_interfaces/msg/Log")["stamp"] == {"sec": 0, "nanosec": 0}


@pytest.mark.parametrize("ros2", [False, True])
def test_sim_action(ros2):
    reg = TypeRegistry.standard(ros2=ros2)
    assert reg.has("rcon_sim/action/NavigateToFix")
    goal = reg.default(reg.action_part_name("rcon_sim/NavigateToFix", "goal"))
    assert list(goal) == ["target"] and "latitude" in goal["target"]
    assert reg.default("rcon_sim/action/NavigateToFix_Result") == {"success": False, "message": "", "distance": 0.0}
    feedback = reg.fields("rcon_sim/action/NavigateToFix_Feedback")
    assert [(f.name, f.base) for f in feedback] == [
        ("distance_remaining", "float64"), ("current", "sensor_msgs/msg/NavSatFix")
    ]


def test_ros1_actionlib_wrappers(reg):
    goal = reg.default("rcon_sim/NavigateToFixActionGoal")
    assert list(goal) == ["header", "goal_id", "goal"] and "target" in goal["goal"]
    assert [f.name for f in reg.fields("rcon_sim/NavigateToFixActionFeedback")] == ["header", "status", "feedback"]


def test_defaults(reg):
    assert reg.default("std_msgs/Header") == {"seq": 0, "stamp": {"secs": 0, "nsecs": 0}, "frame_id": ""}
    imu = reg.default("sensor_msgs/Imu")
    assert imu["orientation_covariance"] == [0.0] * 9
    assert reg.default("sensor_msgs/Image")["data"] == ""
    assert reg.default("sensor_msgs/Image")["is_bigendian"] == 0
    assert reg.default("std_msgs/Bool") == {"data": False}
    uuid = TypeRegistry.standard(ros2=True).default("unique_identifier_msgs/msg/UUID")
    assert uuid == {"uuid": "AAAAAAAAAAAAAAAAAAAAAA=="}  # 16 zero bytes, base64
    assert reg.default("visualization_msgs/Marker")["lifetime"] == {"secs": 0, "nsecs": 0}
    # a fresh dict each time
    a = reg.default("geometry_msgs/Twist")
    a["linear"]["x"] = 5.0
    assert reg.default("geometry_msgs/Twist")["linear"]["x"] == 0.0


def test_unknown_and_garbage(reg):
    assert not reg.has("nope_msgs/Nothing")
    assert not reg.has("garbage name")
    with pytest.raises(UnknownTypeError, match="unknown message type 'nope_msgs/Nothing'"):
        reg.fields("nope_msgs/Nothing")
    with pytest.raises(ValueError, match="not a ROS type name"):
        reg.fields("not a type")
    with pytest.raises(UnknownTypeError, match="is a service, not a message"):
        reg.fields("std_srvs/SetBool")
    with pytest.raises(ValueError, match="part must be"):
        reg.service_typedefs("std_srvs/SetBool", "both")


def test_add_msg_text():
    reg = TypeRegistry.standard()
    added = reg.add_msg_text(
        "my_pkg/Reading",
        "# a comment\nuint8 OK=0\nstring GREETING=hello # world\nHeader header\nfloat32[4] values  # c\n"
        "Point2 where\ntime taken\nduration took\nbyte b\nchar c\n",
    )
    assert added == ["my_pkg/msg/Reading"]
    reg.add_msg_text("my_pkg/msg/Point2", "float64 x\nfloat64 y\n")
    assert reg.constants("my_pkg/Reading") == {"OK": 0, "GREETING": "hello # world"}
    assert reg.default("my_pkg/Reading") == {
        "header": {"seq": 0, "stamp": {"secs": 0, "nsecs": 0}, "frame_id": ""},
        "values": [0.0] * 4,
        "where": {"x": 0.0, "y": 0.0},
        "taken": {"secs": 0, "nsecs": 0},
        "took": {"secs": 0, "nsecs": 0},
        "b": 0,
        "c": 0,
    }
    assert reg.add_msg_text("my_pkg/srv/Ask", "string q\n---\nstring a\n") == [
        "my_pkg/srv/Ask_Request", "my_pkg/srv/Ask_Response"
    ]
    assert reg.has_service("my_pkg/Ask")
    td = reg.typedefs("my_pkg/Reading")
    assert td[0]["constnames"] == ["GREETING", "OK"] and td[0]["constvalues"] == ["hello # world", "0"]
    assert [t["type"] for t in td] == ["my_pkg/Reading", "std_msgs/Header", "time", "my_pkg/Point2", "duration"]


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("float64\n", "line 1"),
        ("float64 9x\n", "not a field name"),
        ("float64[x] y\n", "not a field type"),
        ("Header H=3\n", "primitive"),
        ("int32 N=abc\n", "line 1"),
    ],
)
def test_add_msg_text_errors(text, match):
    with pytest.raises(ValueError, match=match):
        TypeRegistry.standard().add_msg_text("my_pkg/Bad", text)


def test_service_text_needs_two_parts():
    with pytest.raises(ValueError, match="2 parts"):
        TypeRegistry.standard().add_msg_text("my_pkg/srv/Bad", "int32 a\n")


def test_definition_text(reg):
    assert reg.definition_text("geometry_msgs/TwistStamped") == "std_msgs/Header header\ngeometry_msgs/Twist twist\n"
    text = reg.definition_text("geometry_msgs/TwistStamped", dependencies=True)
    assert text.startswith("std_msgs/Header header\ngeometry_msgs/Twist twist\n")
    assert "\nMSG: std_msgs/Header\nuint32 seq\ntime stamp\nstring frame_id\n" in text
    assert text.count("MSG: geometry_msgs/Vector3") == 1
    assert reg.definition_text("std_srvs/SetBool") == "bool data\n---\nbool success\nstring message\n"
    assert "byte DEBUG=1" in reg.definition_text("rosgraph_msgs/Log")
    ros2 = TypeRegistry.standard(ros2=True).definition_text("std_msgs/msg/Header")
    assert ros2.startswith("builtin_interfaces/Time stamp\nstring frame_id\n")
    # the text parses back to the same fields
    again = TypeRegistry.standard()
    again.add_msg_text("check_pkg/Log", reg.definition_text("rosgraph_msgs/Log"))
    assert again.fields("check_pkg/Log") == reg.fields("rosgraph_msgs/Log")
    assert again.constants("check_pkg/Log") == reg.constants("rosgraph_msgs/Log")


def test_registries_are_independent_and_cheap():
    TypeRegistry.standard()  # warm the shared cache
    start = time.perf_counter()
    regs = [TypeRegistry.standard() for _ in range(20)]
    elapsed = time.perf_counter() - start
    regs[0].add_msg_text("only_here/Thing", "int32 a\n")
    assert regs[0].has("only_here/Thing") and not regs[1].has("only_here/Thing")
    assert elapsed < 2.0  # generous: about a millisecond each in practice


def test_wire_name():
    assert TypeRegistry.standard().wire_name("geometry_msgs/msg/Twist") == "geometry_msgs/Twist"
    assert TypeRegistry.standard(ros2=True).wire_name("geometry_msgs/Twist") == "geometry_msgs/msg/Twist"


@pytest.mark.parametrize("ros2", [False, True])
def test_empty_message_has_no_placeholder_field(ros2):
    # rosbags gives empty messages an IDL stand-in member; no rosbridge wire carries it
    reg = TypeRegistry.standard(ros2=ros2)
    assert reg.fields("std_msgs/Empty") == []
    assert reg.default("std_msgs/Empty") == {}
    assert reg.typedefs("std_msgs/Empty")[0]["fieldnames"] == []
