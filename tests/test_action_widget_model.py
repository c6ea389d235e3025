"""The ACTION role in the widget contract and the matcher, and the std Action widget's model (no Qt)
against the sim in ROS 2 mode: a goal form from the goal type, checked entries, feedback with progress,
the end in words, failures that are never a success."""

from __future__ import annotations

from collections.abc import AsyncIterator

import pytest
import pytest_asyncio

from rcon_core.bridge import BridgeClient
from rcon_core.matcher import Rank, candidate_paths, match
from rcon_core.msgs import MessageTextError, TypeRegistry
from rcon_core.plugins import Accepts, Binding, PluginManager, Role, WidgetSpec
from rcon_core.plugins.spec import SpecError
from rcon_core.sim import SimServer
from rcon_core.testing import until

pytest.importorskip("rcon_widgets_std")
from rcon_widgets_std import plugin as std_plugin  # noqa: E402
from rcon_widgets_std.action import ActionModel, ActionSettings, progress_of  # noqa: E402

NAV, NAV_TYPE = "/navigate_to_fix", "rcon_sim/action/NavigateToFix"
FIB, FIB_TYPE = "/fibonacci", "action_tutorials_interfaces/action/Fibonacci"


@pytest.fixture(scope="module")
def types() -> TypeRegistry:
    return TypeRegistry.standard(ros2=False)


@pytest.fixture(scope="module")
def pm() -> PluginManager:
    pm = PluginManager(environ={})
    pm.register(std_plugin, name="std")
    return pm


# -- the role and the matcher -----------------------------------------------------------------------

def test_role_action_is_parsed_and_named():
    assert Role.parse("action") is Role.ACTION and Role.ACTION.is_action and not Role.ACTION.is_service
    assert Binding(role="action").problems() == ["no action chosen"]
    assert Binding("/nav", "", "action").problems() == ["no action type set"]


def test_action_widget_matches_action_types_only(types, pm):
    found = [m.kind for m in match(NAV_TYPE, Role.ACTION, types, pm)]
    assert found == ["std.action"]
    assert [m.kind for m in match("rcon_sim/NavigateToFix", "action", types, pm)] == ["std.action"]  # ROS 1 spelling
    assert "std.action" not in [m.kind for m in match("std_msgs/Float64", Role.SUBSCRIBE, types, pm)]
    assert match("std_msgs/Float64", Role.ACTION, types, pm)[0].rank is Rank.GENERIC  # a name-only match


def test_action_parts_give_prefixed_paths_and_are_checked(types):
    spec = WidgetSpec(kind="t.progress", title="Progress", model="rcon_core.plugins.model:WidgetModel",
                      roles=["action"], accepts=Accepts(fields=["numeric"], action_parts=["feedback"]))
    assert candidate_paths(spec, Role.ACTION, NAV_TYPE, types)[0] == "feedback.distance_remaining"
    everything = WidgetSpec(kind="t.all", title="All", model="rcon_core.plugins.model:WidgetModel",
                            roles=["action"], accepts=Accepts(fields=["float"]))
    paths = candidate_paths(everything, Role.ACTION, NAV_TYPE, types)
    assert "goal.target.latitude" in paths and "result.distance" in paths
    with pytest.raises(SpecError, match="action_parts"):
        Accepts(action_parts=["request"])


# -- the model, offline -----------------------------------------------------------------------------

def test_goal_form_fields_and_checked_entries(types):
    model = ActionModel(ActionSettings(), Binding(NAV, NAV_TYPE, Role.ACTION), None, types=types)
    paths = [f.path for f in model.goal_fields()]
    assert paths[:3] == ["target.latitude", "target.longitude", "target.altitude"]
    assert "target.position_covariance" == paths[-1] and not any("header" in p for p in paths)
    goal = model.build_goal({"target.latitude": "43.5", "target.longitude": "-79", "target.altitude": ""})
    assert goal == {"target": {"latitude": 43.5, "longitude": -79.0}}  # converted; empty = the server's default
    with pytest.raises(MessageTextError) as err:
        model.build_goal({"target.latitude": "north"})
    assert err.value.path == "target.latitude"
    fib = ActionModel(ActionSettings(goal="order: 7"), Binding(FIB, FIB_TYPE, Role.ACTION), None, types=types)
    # every entry starts empty; its placeholder is what an empty entry sends (the settings' goal value)
    assert [(f.path, f.text, f.default, f.required) for f in fib.goal_fields()] == [("order", "", "7", False)]
    assert fib.build_goal({"order": ""}) == {"order": 7} and fib.build_goal({"order": "1e1"}) == {"order": 10}
    assert ActionSettings(goal="order: [").problems()


def test_the_goal_form_starts_empty_and_the_coordinates_of_a_place_are_required(types):
    """issue 21.5: latitude/longitude started as real zeros: one tap of Send goal sent the boat to 0°N 0°E."""
    model = ActionModel(ActionSettings(), Binding(NAV, NAV_TYPE, Role.ACTION), None, types=types)
    fields = {f.path: f for f in model.goal_fields()}
    assert all(f.text == "" for f in fields.values() if f.base != "bool")
    assert [p for p, f in fields.items() if f.required] == ["target.latitude", "target.longitude"]
    assert fields["target.altitude"].default == "0.0" and fields["target.latitude"].default == ""
    assert model.missing({p: "" for p in fields}) == ["target.latitude", "target.longitude"]
    assert model.missing({"target.latitude": "43.6", "target.longitude": " "}) == ["target.longitude"]
    with pytest.raises(MessageTextError) as err:
        model.build_goal({p: "" for p in fields})  # nothing typed: nothing sent, never 0°N 0°E
    assert err.value.path == "target.latitude" and "required" in err.value.problem
    # the settings may give the coordinates (a fixed station): then they are defaults, not required
    station = ActionModel(ActionSettings(goal="target: {latitude: 43.6, longitude: -79.4}"),
                          Binding(NAV, NAV_TYPE, Role.ACTION), None, types=types)
    assert not any(f.required for f in station.goal_fields())
    assert station.build_goal({"target.latitude": "", "target.longitude": ""}) == {
        "target": {"latitude": 43.6, "longitude": -79.4}}
    # or list exactly what is required
    listed = ActionModel(ActionSettings(required="target.altitude"), Binding(NAV, NAV_TYPE, Role.ACTION), None,
                         types=types)
    assert [f.path for f in listed.goal_fields() if f.required] == ["target.altitude"]
    none = ActionModel(ActionSettings(required=""), Binding(NAV, NAV_TYPE, Role.ACTION), None, types=types)
    assert not any(f.required for f in none.goal_fields())


def test_progress_from_feedback_fields():
    assert progress_of({"progress": 0.25}) == (0.25, "progress", None)
    assert progress_of({"percent_complete": 80}) == (0.8, "percent_complete", None)
    assert progress_of({"distance_remaining": 4.0}, "", 8.0) == (0.5, "distance_remaining", 8.0)
    assert progress_of({"partial_sequence": [0, 1, 1]}) == (None, "", None)


# -- the model against the sim (ROS 2) --------------------------------------------------------------

@pytest_asyncio.fixture
async def client() -> AsyncIterator[BridgeClient]:
    server = SimServer(ros2=True, rate_scale=4.0)
    await server.start()
    c = BridgeClient(server.url, call_timeout=3)
    await c.connect(timeout=5)
    try:
        yield c
    finally:
        await c.close()
        await server.stop()


async def test_fibonacci_goal_runs_to_success_with_feedback(client, types):
    model = ActionModel(ActionSettings(), Binding(FIB, FIB_TYPE, Role.ACTION), client.node("w1"), types=types)
    model.start()
    assert model.send({"order": "4"})
    await until(lambda: model.state.value is not None and model.state.value.final)
    st = model.state.value
    assert st.phase == "succeeded" and st.result == {"sequence": [0, 1, 1, 2, 3]}
    assert st.feedback_count >= 2 and st.feedback == {"partial_sequence": [0, 1, 1, 2, 3]}
    model.stop()


async def test_a_goal_sent_while_the_link_is_down_fails_at_once_and_is_not_kept(client, types):
    """As a service call tapped while the link is down (tests/test_call_while_link_down.py): the goal is
    not kept to reach the robot when the link comes back; sent again with the link up, it runs."""
    model = ActionModel(ActionSettings(), Binding(FIB, FIB_TYPE, Role.ACTION), client.node("w5"), types=types)
    model.start()
    model.set_link(False)  # the runtime says the robot's link is down
    model.send({"order": "3"})
    await until(lambda: model.state.value is not None and model.state.value.final, what="the refusal")
    assert model.state.value.phase == "failed" and "link is down" in model.state.value.text
    assert model.state.value.result is None
    model.set_link(True)
    model.send({"order": "3"})
    await until(lambda: model.state.value is not None and model.state.value.phase == "succeeded",
                what="the goal sent with the link up")
    model.stop()


async def test_goal_to_a_missing_server_fails_not_succeeds(client, types):
    model = ActionModel(ActionSettings(), Binding("/nowhere", FIB_TYPE, Role.ACTION), client.node("w2"), types=types)
    model.start()
    model.send({"order": "3"})
    await until(lambda: model.state.value is not None and model.state.value.final)
    assert model.state.value.phase == "failed" and "does not exist" in model.state.value.text
    model.stop()


async def test_stop_with_a_goal_in_flight_cancels_it_and_the_next_model_says_so(client, types):
    binding = Binding(FIB, FIB_TYPE, Role.ACTION)
    from rcon_core.canvas.port import GuardedPort

    node = client.node("w3")  # as the runtime gives it: a port naming the widget instance
    model = ActionModel(ActionSettings(), binding, GuardedPort(node, widget_id="w3"), types=types)
    model.start()
    model.send({"order": "40"})
    await until(lambda: model.state.value is not None and model.state.value.feedback_count >= 1)
    model.stop()
    node.close()
    again = ActionModel(ActionSettings(), binding, GuardedPort(client.node("w3"), widget_id="w3"), types=types)
    assert again.state.value.phase == "canceled" and "canvas switched away" in again.state.value.text


async def test_an_unknown_action_type_is_learned_from_the_robot(client):
    from rcon_core.msgs import TypeRegistry as Registry

    fresh = Registry.empty()  # knows no action: the goal form comes from the robot's typedefs
    model = ActionModel(ActionSettings(), Binding(NAV, NAV_TYPE, Role.ACTION), client.node("w4"), types=fresh)
    assert model.goal_fields() == []
    model.start()
    await until(lambda: model.goal_fields() != [] or model.state.error is not None)
    assert model.state.error is None
    assert [f.path for f in model.goal_fields()][:2] == ["target.latitude", "target.longitude"]
    assert fresh.fields(fresh.action_part_name(NAV_TYPE, "feedback"))[0].name == "distance_remaining"
    model.stop()


async def test_action_types_come_from_rosapi_action_type(client):
    assert await client.rosapi.action_type(NAV) == NAV_TYPE
    assert await client.rosapi.action_type("/nowhere") is None
    assert await client.rosapi.action_servers_with_types() == {FIB: FIB_TYPE, NAV: NAV_TYPE}
    # rosapi's topic_type ignores the hidden action topics (as rosapi 2.x does)
    assert await client.rosapi.topic_type(f"{NAV}/_action/feedback") is None
