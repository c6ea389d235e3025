"""The safety envelope (rcon_core/bridge/envelope.py): the value, clamp vs refuse, and the bridge's hook.

Found by a person (issue 21.4): a Compound slider's maximum typed as 999999999999 published
``linear.x: 43099999999.96`` to ``/cmd_vel``. With an envelope on the client nothing above the limit
leaves, whoever publishes: these tests publish from a raw node of the client (no widget, no port) and read
what the sim received.
"""

from __future__ import annotations

import math

import pytest

from rcon_core.bridge.envelope import (
    NO_LIMITS,
    Envelope,
    EnvelopeRefused,
    enforce,
    is_command,
    motion_path,
)
from rcon_core.bridge.stats import BridgeStats


def twist(lx=0.0, az=0.0, **more):
    msg = {"linear": {"x": lx, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": az}}
    msg.update(more)
    return msg


ENV = Envelope(max_linear=1.0, max_angular=0.5)


# -- the value ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["geometry_msgs/Twist", "geometry_msgs/msg/Twist", "/geometry_msgs/Twist",
                                  "geometry_msgs/TwistStamped", "geometry_msgs/msg/TwistStamped"])
def test_both_spellings_of_twist_and_twist_stamped_are_commands(name):
    assert is_command(name)


@pytest.mark.parametrize("name", ["std_msgs/Float64", "geometry_msgs/Vector3", "nav_msgs/Odometry", "", "x"])
def test_other_types_are_not_commands_and_pass_untouched(name):
    msg = {"linear": {"x": 1e12}}
    assert not is_command(name)
    assert ENV.apply(name, msg) is msg


def test_clamps_each_component_to_its_limit_and_keeps_the_sign():
    sent = ENV.apply("geometry_msgs/Twist", twist(43099999999.96, -3.0))
    assert sent["linear"] == {"x": 1.0, "y": 0.0, "z": 0.0}
    assert sent["angular"] == {"x": 0.0, "y": 0.0, "z": -0.5}


def test_a_command_within_the_envelope_is_sent_as_it_is_and_the_callers_dict_is_never_changed():
    within = twist(0.9, 0.5)
    assert ENV.apply("geometry_msgs/Twist", within) is within
    beyond = twist(2.0, 0.1)
    ENV.apply("geometry_msgs/Twist", beyond)
    assert beyond["linear"]["x"] == 2.0  # a copy was clamped


def test_twist_stamped_is_held_in_its_twist_and_the_verdict_says_what_changed():
    msg = {"header": {"stamp": {"sec": 1, "nanosec": 2}, "frame_id": "base"}, "twist": twist(-7.5)}
    v = ENV.judge("geometry_msgs/msg/TwistStamped", msg)
    assert v.msg is not None and v.msg["twist"]["linear"]["x"] == -1.0 and v.msg["header"] == msg["header"]
    assert v.clamped == (("twist.linear.x", -7.5, -1.0),)
    assert v.sentence == "held to the safety envelope: twist.linear.x -7.5 → -1"


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf, None, "5", True])
def test_not_a_finite_number_is_refused_even_with_no_envelope(bad):
    msg = twist()
    msg["angular"]["z"] = bad
    for env in (ENV, NO_LIMITS):
        with pytest.raises(EnvelopeRefused, match=r"not sent: angular\.z is"):
            env.apply("geometry_msgs/Twist", msg)


def test_a_twist_whose_vector_is_not_a_mapping_is_refused():
    with pytest.raises(EnvelopeRefused, match="linear is not a vector"):
        ENV.apply("geometry_msgs/Twist", {"linear": [1, 2, 3]})
    with pytest.raises(EnvelopeRefused, match="twist is not a twist"):
        ENV.apply("geometry_msgs/TwistStamped", {"twist": 5})


def test_numpy_numbers_are_numbers():
    np = pytest.importorskip("numpy")
    sent = ENV.apply("geometry_msgs/Twist", {"linear": {"x": np.float32(3.0), "y": np.int64(0)}})
    assert sent["linear"] == {"x": 1.0, "y": 0}


def test_missing_fields_are_left_to_rosbridge():
    assert ENV.apply("geometry_msgs/Twist", {"linear": {"x": 3}}) == {"linear": {"x": 1.0}}
    assert ENV.apply("geometry_msgs/Twist", {}) == {}


def test_no_limit_on_a_part_leaves_it_alone():
    env = Envelope(max_linear=None, max_angular=0.2)
    sent = env.apply("geometry_msgs/Twist", twist(50.0, 1.0))
    assert sent["linear"]["x"] == 50.0 and sent["angular"]["z"] == 0.2


@pytest.mark.parametrize("data,problem", [
    ({"max_linear": 0}, "more than 0"),
    ({"max_linear": 1e12}, "at most 100 m/s"),
    ({"max_angular": 51}, "at most 50 rad/s"),
    ({"max_linear": "fast"}, "must be a number"),
    ({"max_linear": True}, "must be a number"),
    ({"max_linear": math.nan}, "must be a number"),
    ({"speed": 1}, "unknown keys speed"),
    ([1, 2], "must be an object"),
])
def test_an_envelope_itself_refuses_absurd_limits(data, problem):
    with pytest.raises(ValueError, match=problem):
        Envelope.from_dict(data)


def test_saved_form_round_trips_and_says_itself_in_words():
    env = Envelope.from_dict({"max_linear": 1, "max_angular": 0.5})
    assert env == Envelope(1.0, 0.5) and env.to_dict() == {"max_linear": 1.0, "max_angular": 0.5}
    assert Envelope.from_dict({}) == NO_LIMITS and NO_LIMITS.to_dict() == {}
    assert env.describe() == "at most 1 m/s and 0.5 rad/s"


@pytest.mark.parametrize("type_name,path,expected", [
    ("geometry_msgs/Twist", "linear.x", ("linear", "x")),
    ("geometry_msgs/Twist", "angular", ("angular", "")),
    ("geometry_msgs/msg/TwistStamped", "twist.angular.z", ("angular", "z")),
    ("geometry_msgs/TwistStamped", "linear.x", None),
    ("geometry_msgs/Twist", "", None),
    ("std_msgs/Float64", "data", None),
])
def test_motion_path_names_the_part_a_field_belongs_to(type_name, path, expected):
    assert motion_path(type_name, path) == expected
    assert ENV.limit_for(type_name, path) == (None if expected is None else ENV.limit(expected[0]))


def test_enforce_counts_clamps_and_refusals():
    stats = BridgeStats()
    enforce(ENV, "geometry_msgs/Twist", twist(5.0), stats)
    enforce(None, "geometry_msgs/Twist", twist(5.0), stats)  # no envelope: no limit
    with pytest.raises(EnvelopeRefused):
        enforce(None, "geometry_msgs/Twist", twist(math.nan), stats)
    assert (stats.envelope_clamped, stats.envelope_refused) == (1, 1)
    assert stats.as_dict() == {**BridgeStats().as_dict(), "envelope_clamped": 1, "envelope_refused": 1}


# -- the bridge: every publish of the client is held, a raw node's too ---------------------------------------
async def test_a_raw_node_of_the_client_never_gets_a_command_past_the_envelope_to_the_robot(sim, client):
    client.envelope = ENV
    pub = client.node("raw").advertise("/cmd_vel", "geometry_msgs/Twist")
    assert pub.publish(twist(43099999999.96, 9.0))
    got = await sim.wait_for_published("/cmd_vel")
    assert got["linear"]["x"] == 1.0 and got["angular"]["z"] == 0.5
    with pytest.raises(EnvelopeRefused, match="linear.x is nan"):
        pub.publish(twist(math.nan))
    pub.publish(twist(-0.25))
    # -0.25 went out after the refused one on the same connection: had that left, it would be here by now
    await sim.wait_for_published("/cmd_vel", lambda m: m["linear"]["x"] == -0.25)
    received = [m["linear"]["x"] for m in sim.published("/cmd_vel")]
    assert received == [1.0, -0.25]  # the refused one never left
    assert client.stats["envelope_clamped"] == 1 and client.stats["envelope_refused"] == 1


async def test_the_envelope_can_change_while_connected_and_holds_a_latched_command_too(sim, client):
    pub = client.node("raw").advertise("/cmd_vel", "geometry_msgs/Twist", latch=True)
    pub.publish(twist(3.0))
    await sim.wait_for_published("/cmd_vel", lambda m: m["linear"]["x"] == 3.0)  # no envelope yet
    client.envelope = Envelope(max_linear=0.4)
    pub.publish(twist(3.0))
    await sim.wait_for_published("/cmd_vel", lambda m: m["linear"]["x"] == 0.4)
    with pytest.raises(TypeError):
        client.envelope = {"max_linear": 1.0}  # type: ignore[assignment]
    assert client.envelope == Envelope(max_linear=0.4)
