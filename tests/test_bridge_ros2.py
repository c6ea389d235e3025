"""BridgeClient against the embedded sim in ROS 2 flavour: the /navigate_to_fix action end to end."""

from __future__ import annotations

import math
import time
from collections.abc import AsyncIterator

import pytest
import pytest_asyncio

from rcon_core.bridge import ActionError, BridgeClient, GoalStatus
from rcon_core.sim import SimServer
from rcon_core.testing import connected, until

pytestmark = pytest.mark.usefixtures("transport")  # every test runs on each transport

ACTION = "/navigate_to_fix"
ACTION_TYPE = "rcon_sim/action/NavigateToFix"


@pytest_asyncio.fixture
async def client(sim_ros2: SimServer) -> AsyncIterator[BridgeClient]:
    async with connected(sim_ros2.url, call_timeout=3) as c:
        yield c


def target_ahead(sim: SimServer, metres: float) -> dict[str, float]:
    """A NavSatFix target ``metres`` ahead of the vessel's heading."""
    r = sim.robot
    x = r.x + metres * math.cos(r.yaw)
    y = r.y + metres * math.sin(r.yaw)
    lat = r.origin_lat + math.degrees(y / 6_378_137.0)
    lon = r.origin_lon + math.degrees(x / (6_378_137.0 * math.cos(math.radians(r.origin_lat))))
    return {"latitude": lat, "longitude": lon}


async def test_goal_feedback_and_result(sim_ros2: SimServer, client: BridgeClient) -> None:
    feedback: list[dict] = []
    goal = client.node("nav").send_action_goal(ACTION, ACTION_TYPE, {"target": target_ahead(sim_ros2, 3.0)},
                                               feedback.append, timeout=30)
    result = await goal.result(timeout=30)
    assert goal.status == GoalStatus.SUCCEEDED and goal.succeeded
    assert result["success"] is True and result["distance"] <= 2.0 and result["message"].startswith("arrived")
    assert feedback and goal.feedback_count == len(feedback)
    assert 2.0 < feedback[0]["distance_remaining"] < 4.0
    assert set(feedback[0]["current"]) >= {"latitude", "longitude", "header", "status"}
    # the distance shrinks while the vessel drives toward the goal
    assert feedback[-1]["distance_remaining"] < feedback[0]["distance_remaining"]
    assert sim_ros2.robot.cmd_surge == 0.0


async def test_cancel_mid_way(sim_ros2: SimServer, client: BridgeClient) -> None:
    feedback: list[dict] = []
    goal = client.node("nav").send_action_goal(ACTION, ACTION_TYPE, {"target": target_ahead(sim_ros2, 500.0)},
                                               feedback.append)

    await until(lambda: feedback, what="the first feedback")
    goal.cancel()
    result = await goal.result(timeout=10)
    assert goal.status == GoalStatus.CANCELED and not goal.succeeded
    assert result["success"] is False and result["message"] == "canceled" and result["distance"] > 400
    assert sim_ros2.robot.cmd_surge == 0.0


async def test_goal_without_feedback_callback_gets_no_feedback(sim_ros2: SimServer, client: BridgeClient) -> None:
    goal = client.node("nav").send_action_goal(ACTION, ACTION_TYPE, {"target": target_ahead(sim_ros2, 500.0)})
    # the robot drives: a feedback frame goes out with each step, and the result comes after them
    await until(lambda: sim_ros2.navigate_action.goal is not None and sim_ros2.robot.cmd_surge > 0,
                what="the robot driving to the goal")
    goal.cancel()
    await goal.result(timeout=10)
    assert goal.feedback_count == 0 and goal.status == GoalStatus.CANCELED


@pytest.mark.parametrize("check", [True, False])
async def test_unknown_action_fails_clearly_within_the_client_timeout(sim_ros2: SimServer, client: BridgeClient,
                                                                      check: bool) -> None:
    """check=True: the client's rosapi check names the action servers; check=False: the server's own
    ``result: false`` answer.  Either way a clear ActionError well inside call_timeout."""
    started = time.monotonic()
    goal = client.node("nav").send_action_goal("/no_such_action", ACTION_TYPE, {}, check=check, timeout=20)
    with pytest.raises(ActionError) as info:
        await goal.result(timeout=20)
    assert time.monotonic() - started < client.call_timeout
    text = str(info.value)
    assert text.startswith("/no_such_action: ")
    if check:
        assert "action does not exist (action servers: /fibonacci, /navigate_to_fix)" in text
    else:
        assert "No action server available" in text and info.value.status == GoalStatus.UNKNOWN


async def test_bad_goal_args_fail_with_the_servers_reason(sim_ros2: SimServer, client: BridgeClient) -> None:
    goal = client.node("nav").send_action_goal(ACTION, ACTION_TYPE, {"target": {"latitude": "north"}})
    with pytest.raises(ActionError, match="latitude and longitude must be numbers"):
        await goal.result(timeout=10)
    assert sim_ros2.robot.cmd_surge == 0.0


async def test_failing_handler_on_ros2_answers_with_the_response_default(sim_ros2: SimServer,
                                                                          client: BridgeClient) -> None:
    """ROS 2 spelling and IDL typedefs: the Trigger response default with the error in ``message``."""
    srv = client.node("provider").advertise_service("/rcon/dock", "std_srvs/srv/Trigger", lambda req: {}["nope"])
    other = BridgeClient(sim_ros2.url, call_timeout=5)
    await other.connect(timeout=5)
    try:
        await until(lambda: "/rcon/dock" in sim_ros2.services, what="the service advertised")
        answer = await other.call_service("/rcon/dock", {}, timeout=5)
    finally:
        await other.close()
    assert answer == {"success": False, "message": "KeyError: 'nope'"} and srv.failures == 1
