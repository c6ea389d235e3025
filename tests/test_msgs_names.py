"""Type-name spellings: canonical pkg/msg/Type, ROS 1 pkg/Type, service and action parts."""

import pytest

from rcon_core.msgs import names


@pytest.mark.parametrize(
    ("given", "canonical"),
    [
        ("geometry_msgs/Twist", "geometry_msgs/msg/Twist"),
        ("geometry_msgs/msg/Twist", "geometry_msgs/msg/Twist"),
        ("/geometry_msgs/Twist", "geometry_msgs/msg/Twist"),
        (" std_srvs/srv/SetBool ", "std_srvs/srv/SetBool"),
        ("std_srvs/srv/SetBoolRequest", "std_srvs/srv/SetBool_Request"),
        ("std_srvs/srv/SetBool_Response", "std_srvs/srv/SetBool_Response"),
        ("rcon_sim/action/NavigateToFixGoal", "rcon_sim/action/NavigateToFix_Goal"),
        ("Header", "std_msgs/msg/Header"),
    ],
)
def test_normalize(given, canonical):
    assert names.normalize(given) == canonical
    assert names.to_ros2(given) == canonical


@pytest.mark.parametrize(
    ("given", "ros1"),
    [
        ("geometry_msgs/msg/Twist", "geometry_msgs/Twist"),
        ("geometry_msgs/Twist", "geometry_msgs/Twist"),
        ("std_srvs/srv/SetBool", "std_srvs/SetBool"),
        ("std_srvs/srv/SetBool_Request", "std_srvs/SetBoolRequest"),
        ("std_srvs/srv/SetBool_Response", "std_srvs/SetBoolResponse"),
        ("rcon_sim/action/NavigateToFix_Feedback", "rcon_sim/NavigateToFixFeedback"),
    ],
)
def test_to_ros1(given, ros1):
    assert names.to_ros1(given) == ros1


@pytest.mark.parametrize(
    "garbage",
    ["", "Twist", "geometry_msgs/", "/", "a/b/c/d", "geometry_msgs/foo/Twist", "9pkg/Type", "pkg/Ty pe",
     "pkg/Type!", None, 42],
)
def test_garbage_is_a_clear_value_error(garbage):
    with pytest.raises(ValueError, match="not a ROS type name"):
        names.normalize(garbage)


def test_candidates_cover_ros1_service_and_action_parts():
    assert names.candidates("std_srvs/SetBoolRequest")[:2] == [
        "std_srvs/msg/SetBoolRequest",
        "std_srvs/srv/SetBool_Request",
    ]
    assert "rcon_sim/action/NavigateToFix_Goal" in names.candidates("rcon_sim/NavigateToFixGoal")
    assert names.candidates("std_srvs/srv/SetBool") == ["std_srvs/srv/SetBool"]
    assert names.candidates("std_srvs/SetBool") == [
        "std_srvs/msg/SetBool", "std_srvs/srv/SetBool", "std_srvs/action/SetBool"
    ]


def test_parts():
    assert names.service_part("std_srvs/srv/Trigger_Response") == ("std_srvs/srv/Trigger", "response")
    assert names.service_part("std_srvs/srv/TriggerRequest") == ("std_srvs/srv/Trigger", "request")
    assert names.service_part("std_msgs/msg/String") is None
    assert names.action_part("rcon_sim/action/NavigateToFix_Result") == ("rcon_sim/action/NavigateToFix", "result")
    assert names.part_name("std_srvs/SetBool", "request") == "std_srvs/srv/SetBool_Request"
    assert names.part_name("rcon_sim/action/NavigateToFix", "feedback") == "rcon_sim/action/NavigateToFix_Feedback"
    with pytest.raises(ValueError, match="no part"):
        names.part_name("std_srvs/srv/SetBool", "goal")


def test_pkg_type_is_the_one_lookup_key_of_both_spellings() -> None:
    from rcon_core.msgs.names import pkg_type

    assert pkg_type("geometry_msgs/msg/Twist") == pkg_type("geometry_msgs/Twist") == "geometry_msgs/Twist"
    assert pkg_type("std_srvs/srv/SetBool") == "std_srvs/SetBool"
    assert pkg_type("/rcon_sim/action/NavigateToFix/") == "rcon_sim/NavigateToFix"
    assert pkg_type("std_srvs/srv/SetBool_Request") == "std_srvs/SetBool_Request"  # suffixes are left alone
    assert pkg_type("not a name") == "not a name" and pkg_type("") == ""  # never raises
