"""BridgeClient against a server replaying the real rosbridge 2.1.0 (ROS 2 Jazzy) frames: each quirk of
``tests/recordings/rosbridge-ros2-2.1.0`` survived, fed from the recorded frame that shows it."""

from __future__ import annotations

import math

import orjson
import pytest
from replay_server import ROS2, ScriptedServer, load, recorded

from rcon_core.bridge import ActionError, ActionNoAnswerError, BridgeClient, GoalStatus, ServiceTimeoutError
from rcon_core.msgs.values import as_bytes
from rcon_core.testing import until

pytestmark = pytest.mark.recordings

FIB, FIB_TYPE = "/fibonacci", "example_interfaces/action/Fibonacci"
ACTIONS = load("actions.jsonl", ROS2)


@pytest.fixture
async def server():
    async with ScriptedServer(recording=ROS2) as srv:
        yield srv


@pytest.fixture
async def client(server):
    c = BridgeClient(server.url, backoff_min=0.05, backoff_max=0.2, call_timeout=3)
    await c.connect(timeout=5)
    yield c
    await c.close()


# ------------------------------------------------------------------------------------------ actions


async def test_a_rejected_goal_says_no_answer_instead_of_running_forever(client, server):
    """actions.jsonl:14-15: order -1 is rejected by the action server and rosbridge 2.1.0 sends nothing."""
    sent = ACTIONS[13]["sent"]
    goal = client.node("g").send_action_goal(sent["action"], sent["action_type"], sent["args"], answer_timeout=0.4)
    assert goal.outcome == "running"
    with pytest.raises(ActionNoAnswerError, match=r"no answer from the action server \(rejected\?\)"):
        await goal.result(timeout=5)
    assert goal.outcome == "no answer (rejected?)"
    (op,) = server.ops("send_action_goal")
    assert op["feedback"] is True  # asked in any case: feedback is how a running goal shows it was accepted


async def test_a_goal_that_runs_is_not_taken_for_a_rejection(client):
    """actions.jsonl:1-6: feedback comes at once, so a short answer_timeout does not fire; status 4."""
    got = []
    goal = client.node("g").send_action_goal(FIB, FIB_TYPE, {"order": 5}, got.append, answer_timeout=0.2)
    result = await goal.result(timeout=5)
    assert result == {"sequence": [0, 1, 1, 2, 3, 5]} and goal.status == GoalStatus.SUCCEEDED
    assert [f["sequence"][-1] for f in got] == [1, 2, 3, 5] and goal.outcome == "succeeded"


async def test_a_goal_without_a_feedback_callback_gets_its_result(client):
    """actions.jsonl:7-8: without feedback asked the server sends only the result; the client asks anyway
    and keeps what comes to itself."""
    goal = client.node("g").send_action_goal(FIB, FIB_TYPE, {"order": 3}, answer_timeout=2)
    assert await goal.result(timeout=5) == {"sequence": [0, 1, 1, 2]}
    assert goal.feedback_count == 0


async def test_a_late_result_after_no_answer_still_tells_the_end(client, server):
    goal = client.node("g").send_action_goal(FIB, FIB_TYPE, {"order": -1}, answer_timeout=0.2)
    with pytest.raises(ActionNoAnswerError):
        await goal.result(timeout=5)
    late = ACTIONS[5]["received_text"].replace('"goal:fib5"', orjson.dumps(goal.id).decode())
    await server.send(late)
    await until(lambda: goal.status is not None)
    assert goal.outcome == "succeeded" and goal.late_result == {"sequence": [0, 1, 1, 2, 3, 5]}


async def test_newer_servers_answer_a_rejection_and_the_outcome_says_rejected(client, server):
    """rosbridge 2.5.0 (#1139) answers a rejected goal with result false and "Action goal was rejected"."""
    goal = client.node("g").send_action_goal(FIB, FIB_TYPE, {"order": -1}, answer_timeout=5)
    await server.wait_for("send_action_goal")
    await server.send({"op": "action_result", "action": FIB, "values": "Action goal was rejected", "status": 0,
                       "result": False, "id": goal.id})
    with pytest.raises(ActionError, match="rejected"):
        await goal.result(timeout=5)
    assert goal.outcome == "rejected"


async def test_failures_the_server_does_report_keep_its_words(client):
    """actions.jsonl:18-21: an unknown action_type and a bad argument come back as result false, status 0."""
    goal = client.node("g").send_action_goal(FIB, FIB_TYPE, {"order": "five"})
    with pytest.raises(ActionError, match="requires a int32 for field order"):
        await goal.result(timeout=5)
    assert goal.outcome == "failed" and goal.status == 0


# ------------------------------------------------------------------------------------------ calls


async def test_a_call_that_gets_silence_ends_with_a_timeout_naming_the_op(client, server):
    """Unknown ops, bad fields and wedged rosapi answer nothing (malformed.jsonl, rosapi.jsonl:77): the
    client's own timeout ends the call and names what it waited for."""
    server.services["/client/slow"] = lambda frame: None  # services.jsonl:20: a provider that stays silent
    with pytest.raises(ServiceTimeoutError) as err:
        await client.call_service("/client/slow", {}, timeout=0.3)
    assert "call_service" in str(err.value) and "/client/slow" in str(err.value)


async def test_a_call_stuck_behind_an_unanswered_one_says_so(client, server):
    """services.jsonl:20-25: one unanswered call holds up the next on the same connection (2.1.0 runs calls
    one at a time); the second timeout names the first, and the late answer is dropped quietly."""
    server.services["/client/slow"] = lambda frame: None  # the provider answers only later (:23-24)
    server.services["/peer_trigger"] = lambda frame: None  # stuck behind /client/slow, as recorded
    with pytest.raises(ServiceTimeoutError):
        await client.call_service("/client/slow", {}, timeout=0.3)
    with pytest.raises(ServiceTimeoutError, match=r"earlier call on this connection \(/client/slow\)"):
        await client.call_service("/peer_trigger", {}, timeout=0.3)
    (slow,) = server.ops("call_service", service="/client/slow")
    late = load("services.jsonl", ROS2)[23]["received_text"].replace('"svc:slow-timeout"',
                                                                        orjson.dumps(slow["id"]).decode())
    bad = client.stats["bad_frames"]
    await server.send(late)
    await until(lambda: not client.session.unanswered.get(slow["id"]))
    assert client.stats["bad_frames"] == bad


async def test_a_sticky_fragment_size_splits_the_service_response_too(client, server):
    """subscribe_options.jsonl:29-35: a service_response in fragments (float total, the request's id)."""
    frames = [line["received"] for line in load("subscribe_options.jsonl", ROS2)[29:35]]
    assert all(isinstance(f["total"], float) for f in frames)

    async def answer(frame):  # the recorded reply, with the caller's id, cut as rosbridge cuts it
        text = "".join(f["data"] for f in frames).replace('"frag-sticky-call"', orjson.dumps(frame["id"]).decode())
        size = 30
        total = (len(text) - 1) / size + 1  # rosbridge's float total
        for num, start in enumerate(range(0, len(text), size)):
            await server.send({"op": "fragment", "id": frame["id"], "data": text[start:start + size], "num": num,
                               "total": total})

    server.services["/peer_trigger"] = answer
    values = await client.call_service("/peer_trigger", {})
    assert values["success"] is True and values["message"].startswith("triggered")


# ------------------------------------------------------------------------------------------ topics


async def test_png_is_never_asked_of_a_ros2_server(client, server):
    """publish_png.jsonl:1-4: png sends nothing on 2.1.0 (and :8, it silences a plain id too)."""
    got = []
    client.node("p").subscribe("/chatter", got.append, type="std_msgs/msg/String", compression="png")
    (sub,) = await server.wait_for("subscribe", topic="/chatter")
    assert sub["compression"] == "none"
    await until(lambda: len(got) == len(recorded(ROS2).frames[("/chatter", "none")]))
    assert got[0]["data"].startswith("hello from ros2 peer")


async def test_fragment_size_never_goes_with_cbor(client, server):
    """subscribe_options.jsonl:41: cbor with fragment_size sends nothing; the compression wins."""
    got = []
    client.node("c").subscribe("/chatter", got.append, type="std_msgs/msg/String", compression="cbor",
                               fragment_size=30)
    (sub,) = await server.wait_for("subscribe", topic="/chatter")
    assert sub["compression"] == "cbor" and "fragment_size" not in sub
    await until(lambda: len(got) == 2)


async def test_an_imu_with_bare_nan_reaches_the_subscriber(client, server):
    """publish_json.jsonl:62: NaN/Infinity tokens in fixed-size arrays; the message is delivered."""
    got = []
    client.node("i").subscribe("/client/imu", got.append, type="sensor_msgs/msg/Imu")
    await until(lambda: got)
    cov = got[0]["angular_velocity_covariance"]
    assert math.isnan(cov[0]) and cov[4] == math.inf and client.stats["bad_frames"] == 0


async def test_uint8_data_is_base64_and_int8_a_list(client):
    """publish_json.jsonl:13, :58, :60: uint8[] one base64 string (even for numbers), int8[] a list."""
    image, u8, i8 = [], [], []
    node = client.node("b")
    node.subscribe("/peer/image", image.append, type="sensor_msgs/msg/Image")
    node.subscribe("/client/u8arr", u8.append, type="std_msgs/msg/UInt8MultiArray")
    node.subscribe("/client/i8arr", i8.append, type="std_msgs/msg/Int8MultiArray")
    await until(lambda: image and u8 and i8)
    assert len(as_bytes(image[0]["data"])) == image[0]["step"] * image[0]["height"] == 9216
    assert list(as_bytes(u8[0]["data"])) == [0, 1, 2, 253, 254, 255] and i8[0]["data"] == [-1, 0, 1, 127, -128]


async def test_subscriptions_are_sent_again_after_a_reconnect(client, server):
    """reconnect.jsonl:20-25: a new connection gets nothing until it subscribes again; the client does."""
    got = []
    n = len(recorded(ROS2).frames[("/chatter", "none")])
    client.node("r").subscribe("/chatter", got.append, type="std_msgs/msg/String")
    await until(lambda: len(got) == n)
    await server.drop(abort=True)  # without a close handshake, as reconnect.jsonl:26
    await server.wait_connections(2)
    await until(lambda: len(got) == 2 * n)
    assert len(server.ops("subscribe", topic="/chatter")) == 2


def test_the_replayed_goals_are_the_recorded_ones():
    goals = recorded(ROS2).goals
    rejected = [replies for _id, replies in goals.values() if not replies]
    assert len(rejected) == 2  # the rejected goal and the goal to a missing action (actions.jsonl:14, :16)


class _QuickAnswerPort:
    """The widget's port with a short ``answer_timeout`` (the widget uses the client's default of 5 s)."""

    def __init__(self, node, answer_timeout: float) -> None:
        self._node = node
        self._after = answer_timeout

    def send_action_goal(self, action, action_type, args=None, feedback=None, **options):
        return self._node.send_action_goal(action, action_type, args, feedback, answer_timeout=self._after,
                                           **options)

    def __getattr__(self, name):
        return getattr(self._node, name)


async def test_the_action_widget_says_no_answer_for_a_rejected_goal(client, server):
    """The std Action widget: a goal rejected by the server (actions.jsonl:14-15) ends in 'unknown' with
    the sentence, not 'active' for ever; a goal that runs (actions.jsonl:1-6) still succeeds."""
    pytest.importorskip("rcon_widgets_std")
    from rcon_widgets_std.action import ActionModel, ActionSettings

    from rcon_core.msgs import TypeRegistry
    from rcon_core.plugins import Binding, Role

    types = TypeRegistry.standard(ros2=True)
    port = _QuickAnswerPort(client.node("w"), 0.3)
    model = ActionModel(ActionSettings(), Binding(FIB, FIB_TYPE, Role.ACTION), port, types=types)
    model.start()
    assert model.send({"order": "-1"})
    await until(lambda: model.state.value is not None and model.state.value.final)
    status = model.state.value
    assert status.phase == "unknown" and "no answer from the action server (rejected?)" in status.text
    assert model.send({"order": "5"})
    await until(lambda: model.state.value.phase == "succeeded")
    assert model.state.value.feedback_count == 4
    model.stop()
