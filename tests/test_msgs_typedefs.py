"""rosapi typedefs: byte-for-byte the real rosbridge 0.11.17 answers, and learning from them."""

import json
from pathlib import Path

import pytest

from rcon_core.msgs import TypeRegistry

RECORDINGS = Path(__file__).resolve().parent / "recordings" / "rosbridge-ros1"
ROSAPI = RECORDINGS / "rosapi.jsonl"


def _details_answers():
    out = []
    for lineno, line in enumerate(ROSAPI.read_text(encoding="utf-8").splitlines(), 1):
        rec = json.loads(line)
        sent, received = rec["sent"], rec["received"]
        service = sent["service"].rsplit("/", 1)[-1]
        if service in ("message_details", "service_request_details", "service_response_details"):
            out.append(pytest.param(service, sent["args"]["type"], received["values"]["typedefs"], id=f"{lineno}"))
    return out


ANSWERS = _details_answers()


@pytest.fixture(scope="module")
def reg():
    return TypeRegistry.standard()


@pytest.mark.recordings
def test_every_recorded_details_answer_is_present():
    # 18 message_details + 3 request + 3 response details in the recording
    assert len(ANSWERS) == 24


@pytest.mark.recordings
@pytest.mark.parametrize(("service", "type_name", "expected"), ANSWERS)
def test_typedefs_match_the_real_server(reg, service, type_name, expected):
    if service == "message_details":
        got = reg.typedefs(type_name)
    else:
        got = reg.service_typedefs(type_name, service.split("_")[1])
    assert got == expected
    # key order matters to anyone comparing text
    assert [list(td) for td in got] == [list(td) for td in expected]


@pytest.mark.recordings
@pytest.mark.parametrize(("service", "type_name", "expected"), ANSWERS)
def test_learning_from_the_real_answer_gives_the_same_fields(reg, service, type_name, expected):
    empty = TypeRegistry.empty()
    if service == "message_details":
        learned = empty.add_typedefs({"typedefs": expected})
        root = reg.resolve(type_name)
        assert learned[0] == root
        assert empty.fields(root) == reg.fields(root)
        assert empty.typedefs(type_name) == expected
    else:
        part = service.split("_")[1]
        root = reg.service_part_name(type_name, part)
        learned = empty.add_typedefs(expected, root=root)
        assert learned[0] == root
        assert empty.fields(root) == reg.fields(root)
        assert empty.typedefs(root) == expected


STANDARD = [
    "geometry_msgs/Twist", "sensor_msgs/Imu", "sensor_msgs/BatteryState", "nav_msgs/Odometry",
    "sensor_msgs/PointCloud2", "visualization_msgs/MarkerArray", "diagnostic_msgs/DiagnosticArray",
    "rosgraph_msgs/Log", "sensor_msgs/JointState", "actionlib_msgs/GoalStatusArray",
]


@pytest.mark.parametrize("ros2", [False, True], ids=["ros1", "ros2"])
@pytest.mark.parametrize("type_name", STANDARD)
def test_round_trip_through_an_empty_registry(ros2, type_name):
    reg = TypeRegistry.standard(ros2=ros2)
    if not reg.has(type_name):
        type_name = "rcl_interfaces/msg/Log" if "Log" in type_name else type_name
    typedefs = reg.typedefs(type_name)
    empty = TypeRegistry.empty(ros2=ros2)
    empty.add_typedefs(typedefs)
    root = reg.resolve(type_name)
    assert empty.fields(root) == reg.fields(root)
    for dep in reg.dependencies(root):
        assert empty.fields(dep) == reg.fields(dep)
    assert empty.constants(root) == reg.constants(root)
    assert empty.typedefs(type_name) == typedefs
    assert empty.default(root) == reg.default(root)


def test_ros2_shape():
    reg = TypeRegistry.standard(ros2=True)
    tds = reg.typedefs("std_msgs/msg/Header")
    assert tds[0] == {
        "type": "std_msgs/Header",
        "fieldnames": ["stamp", "frame_id"],
        "fieldtypes": ["builtin_interfaces/Time", "string"],
        "fieldarraylen": [-1, -1],
        "examples": ["{}", ""],
        "constnames": [],
        "constvalues": [],
    }
    assert tds[1]["type"] == "builtin_interfaces/Time"
    assert tds[1]["fieldnames"] == ["sec", "nanosec"]
    assert tds[1]["fieldtypes"] == ["int32", "uint32"]
    imu = reg.typedefs("sensor_msgs/msg/Imu")[0]
    assert imu["fieldtypes"][2] == "double" and imu["fieldarraylen"][2] == 9
    req = reg.service_typedefs("std_srvs/srv/SetBool", "request")
    assert req[0]["type"] == "std_srvs/SetBool_Request"
    assert req[0]["fieldtypes"] == ["boolean"] and req[0]["examples"] == ["False"]


def test_learning_a_ros2_answer_with_idl_names_and_noise():
    """A ROS 2 rosapi answer: IDL names, sequence<...>, and class attributes leaking in as constants."""
    answer = [
        {
            "type": "my_pkg/Sample_Request",
            "fieldnames": ["ranges", "flag", "raw", "stamp", "label", "cov"],
            "fieldtypes": ["sequence<float>", "boolean", "octet", "builtin_interfaces/Time", "string<10>", "double"],
            "fieldarraylen": [0, -1, -1, -1, -1, 4],
            "examples": ["[]", "False", "b'\\x00'", "{}", "", "[]"],
            "constnames": ["LIMIT", "SLOT_TYPES", "flag"],
            "constvalues": ["5", "(...)", "False"],
        },
        {
            "type": "builtin_interfaces/Time",
            "fieldnames": ["sec", "nanosec"],
            "fieldtypes": ["int32", "uint32"],
            "fieldarraylen": [-1, -1],
            "examples": ["0", "0"],
            "constnames": [],
            "constvalues": [],
        },
    ]
    reg = TypeRegistry.empty(ros2=True)
    assert reg.add_typedefs(answer) == ["my_pkg/srv/Sample_Request"]
    fields = {f.name: (f.base, f.array_len) for f in reg.fields("my_pkg/srv/Sample_Request")}
    assert fields == {
        "ranges": ("float32", 0), "flag": ("bool", None), "raw": ("byte", None), "stamp": ("time", None),
        "label": ("string", None), "cov": ("float64", 4),
    }
    assert reg.constants("my_pkg/srv/Sample_Request") == {"LIMIT": 5}
    assert reg.default("my_pkg/srv/Sample_Request")["stamp"] == {"sec": 0, "nanosec": 0}


@pytest.mark.parametrize(
    ("bad", "match"),
    [
        ("nope", "expected a list"),
        ([1], "expected an object"),
        ([{"type": "a/B"}], "missing"),
        ([{"type": "a/B", "fieldnames": ["x"], "fieldtypes": [], "fieldarraylen": [-1]}], "differ in length"),
        ([{"type": "not a name", "fieldnames": [], "fieldtypes": [], "fieldarraylen": []}], "not a ROS type"),
    ],
)
def test_bad_typedefs_are_rejected_clearly(bad, match):
    with pytest.raises(ValueError, match=match):
        TypeRegistry.empty().add_typedefs(bad)


def test_learned_type_overrides_and_clears_caches():
    reg = TypeRegistry.standard()
    assert reg.default("std_msgs/Int32") == {"data": 0}
    reg.add_typedefs([{"type": "std_msgs/Int32", "fieldnames": ["data", "extra"], "fieldtypes": ["int32", "string"],
                       "fieldarraylen": [-1, -1], "examples": ["0", ""], "constnames": [], "constvalues": []}])
    assert reg.default("std_msgs/Int32") == {"data": 0, "extra": ""}
    # another registry is not affected
    assert TypeRegistry.standard().default("std_msgs/Int32") == {"data": 0}
