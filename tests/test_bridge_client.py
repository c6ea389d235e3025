"""BridgeClient against a scripted rosbridge server that replays the real server's recorded frames."""

from __future__ import annotations

import asyncio
import logging
import math

import orjson
import pytest
from replay_server import ScriptedServer, load, recorded

from rcon_core.bridge import (
    ActionError,
    ActionTimeoutError,
    BridgeClient,
    BridgeError,
    ConnectionLostError,
    ConnectionState,
    GoalStatus,
    NotConnectedError,
    ServiceError,
    ServiceTimeoutError,
)
from rcon_core.bridge.protocol import png_to_text
from rcon_core.msgs.values import as_bytes
from rcon_core.testing import until

pytestmark = pytest.mark.usefixtures("transport")  # every test runs on each transport

pytestmark = pytest.mark.recordings


@pytest.fixture
async def server():
    async with ScriptedServer() as srv:
        yield srv


@pytest.fixture
async def client(server):
    c = BridgeClient(server.url, backoff_min=0.05, backoff_max=0.2, call_timeout=5)
    await c.connect(timeout=5)
    yield c
    await c.close()


# ------------------------------------------------------------------------------------------ topics


async def test_subscribe_receives_the_recorded_frames(server, client):
    got = []
    node = client.node("w1")
    node.subscribe("/rec/scan", got.append, type="sensor_msgs/LaserScan", throttle_rate=100, queue_length=1)
    (sub,) = await server.wait_for("subscribe", topic="/rec/scan")
    assert sub["type"] == "sensor_msgs/LaserScan" and sub["throttle_rate"] == 100 and sub["queue_length"] == 1
    assert sub["compression"] == "none" and isinstance(sub["id"], str)
    await until(lambda: len(got) == 2)
    assert got[0]["header"]["frame_id"] == "laser" and got[0]["ranges"][0] is None


@pytest.mark.parametrize("compression", ["cbor", "png", "cbor-raw"])
async def test_each_compression_gives_the_same_dicts(server, client, compression):
    got = []
    client.node("w").subscribe("/rec/str", got.append, type="std_msgs/String", compression=compression)
    await until(lambda: len(got) == 2)
    assert all("café °C" in m["data"] for m in got)
    (sub,) = server.ops("subscribe")
    assert sub["compression"] == compression


def _recorded_png(topic: str) -> tuple[str, dict]:
    """A real server's png frame for ``topic`` and the publish frame hidden in it."""
    frame = recorded().frames[(topic, "png")][0]
    return frame, orjson.loads(png_to_text(orjson.loads(frame)["data"]))


@pytest.mark.parametrize("style", ["fragment", "png-pieces"])
async def test_fragmented_png_frames_are_reassembled_and_decoded(server, client, style):
    """``fragment``: a fragment_size server cuts the png frame's JSON text into fragment frames (rosbridge
    0.11, float total); ``png-pieces``: the spec's own form, png frames carrying slices of the base64 PNG
    with id/num/total.  Either way the recorded image comes out, twice in a row."""
    frame, inner = _recorded_png("/rec/image")
    assert inner["op"] == "publish" and inner["topic"] == "/rec/image"
    if style == "fragment":
        size = len(frame) // 7 + 1
        pieces = [frame[i:i + size] for i in range(0, len(frame), size)]
        total = len(pieces) + 0.42  # rosbridge's float total: floor() is the count
        frames = [orjson.dumps({"op": "fragment", "id": 0, "data": d, "num": n, "total": total}).decode()
                  for n, d in enumerate(pieces)]
    else:
        data = orjson.loads(frame)["data"]
        size = len(data) // 5 + 1
        pieces = [data[i:i + size] for i in range(0, len(data), size)]
        frames = [orjson.dumps({"op": "png", "id": "img", "data": d, "num": n, "total": len(pieces)}).decode()
                  for n, d in enumerate(pieces)]
    assert len(frames) > 3
    server.on_subscribe = lambda sub: frames + frames
    got = []
    client.node("cam").subscribe("/rec/image", got.append, type="sensor_msgs/Image", compression="png",
                                 fragment_size=size)
    await until(lambda: len(got) == 2)
    assert got[0] == got[1] == inner["msg"]
    assert got[0]["encoding"] and len(as_bytes(got[0]["data"])) == got[0]["step"] * got[0]["height"]
    assert client.stats["bad_frames"] == 0


async def test_cbor_on_fixed_array_types_switches_to_cbor_raw(server, client):
    """rosbridge's cbor sends nothing for Imu (publish_cbor.jsonl:12-14); the client asks for cbor-raw instead."""
    got, scans = [], []
    client.node("imu").subscribe("/rec/imu", got.append, type="sensor_msgs/Imu", compression="cbor")
    client.node("scan").subscribe("/rec/scan", scans.append, type="sensor_msgs/LaserScan", compression="cbor")
    (imu_sub,) = await server.wait_for("subscribe", topic="/rec/imu")
    (scan_sub,) = await server.wait_for("subscribe", topic="/rec/scan")
    assert imu_sub["compression"] == "cbor-raw"
    assert scan_sub["compression"] == "cbor"  # variable-length arrays work with cbor
    await until(lambda: len(got) == 2 and len(scans) == 2)
    assert len(got[0]["orientation_covariance"]) == 9 and got[0]["header"]["frame_id"] == "imu_link"
    assert math.isnan(scans[0]["ranges"][10])
    assert server.ops("call_service", service="/rosapi/message_details")


async def test_cbor_raw_without_type_asks_rosapi_for_it(server, client):
    got = []
    client.node("o").subscribe("/rec/odom", got.append, compression="cbor-raw")
    (sub,) = await server.wait_for("subscribe", topic="/rec/odom")
    assert sub["type"] == "nav_msgs/Odometry"
    await until(lambda: len(got) == 2)
    assert len(got[0]["pose"]["covariance"]) == 36


async def test_cbor_without_typedefs_falls_back_to_json(server, client, caplog):
    got = []
    server.services["/rosapi/message_details"] = lambda f: {"op": "service_response", "id": f["id"],
                                                             "values": "no such type", "result": False}
    with caplog.at_level(logging.WARNING):
        client.node("x").subscribe("/rec/str", got.append, type="std_msgs/String", compression="cbor")
        (sub,) = await server.wait_for("subscribe", topic="/rec/str")
    assert sub["compression"] == "none"
    assert "subscribing without compression" in caplog.text
    await until(lambda: len(got) == 2)


async def test_nodes_share_one_subscription_and_tightest_options_win(server, client):
    a, b = [], []
    na, nb, nc = client.node("a"), client.node("b"), client.node("c")
    sa = na.subscribe("/rec/f64", a.append, type="std_msgs/Float64", throttle_rate=500)
    first = (await server.wait_for("subscribe", topic="/rec/f64"))[0]
    sb = nb.subscribe("/rec/f64", b.append, throttle_rate=100, queue_length=5)
    subs = await server.wait_for("subscribe", count=2, topic="/rec/f64")
    assert subs[1]["throttle_rate"] == 100 and subs[1]["queue_length"] == 5
    assert subs[1]["type"] == "std_msgs/Float64" and subs[1]["id"] != first["id"]
    # the old subscription is dropped after the new one is in place
    (unsub,) = await server.wait_for("unsubscribe", topic="/rec/f64")
    assert unsub["id"] == first["id"]
    await until(lambda: len(a) >= 2 and len(b) >= 2)
    assert a[-1] == b[-1]
    # a node that did not subscribe gets nothing; the other topics are not routed to these nodes
    other = []
    nc.subscribe("/rec/i32", other.append)
    await until(lambda: len(other) == 2)
    assert all("data" in m and isinstance(m["data"], float) for m in a)
    # leaving: the tightest remaining options are recomputed, the last one unsubscribes
    sb.unsubscribe()
    subs = await server.wait_for("subscribe", count=3, topic="/rec/f64")
    assert subs[2]["throttle_rate"] == 500
    sa.unsubscribe()
    unsubs = await server.wait_for("unsubscribe", count=3, topic="/rec/f64")
    assert unsubs[-1]["id"] == subs[2]["id"]
    assert "/rec/f64" not in client.session.topics


async def test_a_raising_callback_does_not_affect_others(server, client, caplog):
    good = []

    def bad(msg):
        raise RuntimeError("widget bug")

    client.node("bad").subscribe("/rec/bool", bad)
    client.node("good").subscribe("/rec/bool", good.append)
    with caplog.at_level(logging.ERROR):
        await until(lambda: len(good) >= 2)
    assert "widget bug" in caplog.text
    assert client.connected


async def test_subscribe_argument_errors(client):
    node = client.node("n")
    with pytest.raises(ValueError, match="compression must be one of"):
        node.subscribe("/a", print, compression="zip")
    with pytest.raises(ValueError, match="throttle_rate"):
        node.subscribe("/a", print, throttle_rate=-1)
    with pytest.raises(ValueError, match="topic"):
        node.subscribe("", print)
    with pytest.raises(TypeError, match="callable"):
        node.subscribe("/a", None)


# ------------------------------------------------------------------------------------------ publish


async def test_advertise_publish_and_latch_in_every_publish(server, client):
    node = client.node("pub")
    pub = node.advertise("/client/cmd_vel", "geometry_msgs/Twist")
    latched = node.advertise("/client/latched", "std_msgs/String", latch=True)
    assert pub.publish({"linear": {"x": 0.25}})
    latched.publish({"data": "hello"})
    (adv,) = await server.wait_for("advertise", topic="/client/cmd_vel")
    assert adv["type"] == "geometry_msgs/Twist" and adv["latch"] is False and adv["queue_size"] == 100
    (p,) = await server.wait_for("publish", topic="/client/cmd_vel")
    assert p["msg"] == {"linear": {"x": 0.25}} and "latch" not in p
    (lp,) = await server.wait_for("publish", topic="/client/latched")
    assert lp["latch"] is True  # repeated in every publish (client_publish.jsonl:26-30)
    with pytest.raises(TypeError):
        pub.publish([1, 2])


async def test_advertisements_are_shared_and_the_last_unadvertises(server, client):
    p1 = client.node("a").advertise("/cmd", "std_msgs/Float64")
    p2 = client.node("b").advertise("/cmd", "std_msgs/msg/Float64")
    await server.wait_for("advertise", topic="/cmd")
    with pytest.raises(BridgeError, match="already advertised as std_msgs/Float64"):
        client.node("c").advertise("/cmd", "std_msgs/String")
    p1.unadvertise()
    p2.publish({"data": 1.0})
    await server.wait_for("publish", topic="/cmd")
    assert not server.ops("unadvertise")
    p2.unadvertise()
    await server.wait_for("unadvertise", topic="/cmd")
    assert len(server.ops("advertise", topic="/cmd")) == 1
    with pytest.raises(BridgeError, match="after unadvertise"):
        p2.publish({"data": 2.0})


# ------------------------------------------------------------------------------------------ services


async def test_call_service_success_and_server_failure(server, client):
    node = client.node("caller")
    assert await node.call_service("/rec/set_bool", {"data": True}) == {"success": True, "message": "motors enabled"}
    assert await node.call_service("/rec/empty", {}) == {}
    with pytest.raises(ServiceError) as info:
        await node.call_service("/rec/does_not_exist", {})
    assert info.value.message == "Service /rec/does_not_exist does not exist"
    with pytest.raises(ServiceError, match="requires a bool for field data"):
        await node.call_service("/rec/set_bool", {"data": "yes"})
    with pytest.raises(ServiceError, match="error processing request"):
        await node.call_service("/rec/fails", {})


async def test_call_service_always_has_a_client_side_timeout(server, client):
    """A service that never answers (rosbridge ignores 'timeout') must not hang the caller."""
    server.services["/hung"] = lambda frame: None
    with pytest.raises(ServiceTimeoutError, match="no answer to call_service within 0.3 s"):
        await client.call_service("/hung", {}, timeout=0.3)
    (call,) = server.ops("call_service", service="/hung")
    assert call["timeout"] == 0.3
    client.call_timeout = 0.2
    with pytest.raises(ServiceTimeoutError):
        await client.call_service("/hung")
    assert not client.session.pending


async def test_status_error_fails_the_matching_call(server, client):
    server.services["/bad"] = lambda f: {"op": "status", "level": "error", "id": f["id"], "msg": "no such service"}
    statuses = []
    client.add_status_listener(statuses.append)
    with pytest.raises(ServiceError, match="no such service"):
        await client.call_service("/bad", timeout=3)
    assert statuses and statuses[0]["level"] == "error"


async def test_advertised_service_answers_the_servers_calls(server, client):
    calls = []

    def handler(req):
        calls.append(req)
        return {"success": req["data"], "message": "ok"}

    async def async_handler(req):
        await asyncio.sleep(0)
        return {"success": True, "message": "async"}

    def broken(req):
        raise ValueError("cannot do that")

    node = client.node("provider")
    srv = node.advertise_service("/client/set_bool", "std_srvs/SetBool", handler)
    node.advertise_service("/client/async", "std_srvs/SetBool", async_handler)
    node.advertise_service("/client/broken", "std_srvs/SetBool", broken)
    node.advertise_service("/client/wrong", "std_srvs/SetBool", lambda req: "not a dict")
    (adv,) = await server.wait_for("advertise_service", service="/client/set_bool")
    assert adv["type"] == "std_srvs/SetBool"
    with pytest.raises(BridgeError, match="already advertised by node provider"):
        client.node("other").advertise_service("/client/set_bool", "std_srvs/SetBool", handler)
    # the exact frame the real server sends (client_service.jsonl:2), slashes escaped
    await server.send(load("client_service.jsonl")[1]["received_text"])
    (resp,) = await server.wait_for("service_response", id="service_request:/client/set_bool:1")
    assert resp == {"op": "service_response", "service": "/client/set_bool", "id": "service_request:/client/set_bool:1",
                    "values": {"success": True, "message": "ok"}, "result": True}
    assert calls == [{"data": True}]
    await server.send({"op": "call_service", "id": "r2", "service": "/client/async", "args": {"data": False}})
    (resp,) = await server.wait_for("service_response", id="r2")
    assert resp["values"] == {"success": True, "message": "async"} and resp["result"] is True
    # a failing handler: always an object (rosbridge 0.11 rejects anything else and the caller hangs), the
    # response type's default (learned from the recorded /rosapi/service_response_details) with the error
    # in its `message` field
    await server.send({"op": "call_service", "id": "r3", "service": "/client/broken", "args": {}})
    (resp,) = await server.wait_for("service_response", id="r3")
    assert resp["result"] is False and resp["values"] == {"success": False, "message": "ValueError: cannot do that"}
    (details,) = server.ops("call_service", service="/rosapi/service_response_details")
    assert details["args"] == {"type": "std_srvs/SetBool"}
    await server.send({"op": "call_service", "id": "r4", "service": "/client/wrong"})
    (resp,) = await server.wait_for("service_response", id="r4")
    assert resp["result"] is False and resp["values"] == {
        "success": False, "message": "TypeError: handler returned str, expected a dict"}
    assert len(server.ops("call_service", service="/rosapi/service_response_details")) == 1  # cached
    await server.send({"op": "call_service", "id": "r5", "service": "/client/unknown"})
    (resp,) = await server.wait_for("service_response", id="r5")
    assert resp["result"] is False and resp["values"] == {}
    srv.unadvertise()
    await server.wait_for("unadvertise_service", service="/client/set_bool")
    node.close()
    await server.wait_for("unadvertise_service", count=4)


async def test_failed_handler_answers_with_the_response_types_default(server, caplog):
    """Empty has no fields; a type rosapi cannot describe gets {}; with a registry no rosapi call is made."""
    from rcon_core.msgs import TypeRegistry

    server.services["/rosapi/service_response_details"] = lambda f: (
        None if f["args"]["type"] != "lab_srvs/Mystery" else
        {"op": "service_response", "id": f["id"], "service": f["service"], "result": False,
         "values": "rosapi: unknown type lab_srvs/Mystery"})
    server.replay = True
    async with BridgeClient(server.url, call_timeout=5) as client:
        def broken(req):
            raise RuntimeError("sensor offline")

        node = client.node("provider")
        node.advertise_service("/client/empty", "std_srvs/Empty", broken)
        srv = node.advertise_service("/client/mystery", "lab_srvs/Mystery", broken)
        await server.wait_for("advertise_service", count=2)
        await server.send({"op": "call_service", "id": "e1", "service": "/client/mystery"})
        (resp,) = await server.wait_for("service_response", id="e1")
        assert resp["values"] == {} and resp["result"] is False and srv.failures == 1
        assert "sensor offline" in caplog.text and "cannot learn the response type of lab_srvs/Mystery" in caplog.text
    server.services.clear()  # the recorded answer for std_srvs/Empty would come from the replay
    del server.received[:]
    async with BridgeClient(server.url, call_timeout=5, registry=TypeRegistry.standard()) as client:
        node = client.node("provider")
        node.advertise_service("/client/trigger", "std_srvs/Trigger", lambda req: 1 / 0)
        node.advertise_service("/client/time", "rosapi/GetTime", lambda req: 1 / 0)
        await server.wait_for("advertise_service", count=2)
        await server.send({"op": "call_service", "id": "t1", "service": "/client/trigger"})
        await server.send({"op": "call_service", "id": "m1", "service": "/client/time"})
        (t1,) = await server.wait_for("service_response", id="t1")
        (m1,) = await server.wait_for("service_response", id="m1")
    assert t1["values"] == {"success": False, "message": "ZeroDivisionError: division by zero"}
    assert m1["values"] == {"time": {"secs": 0, "nsecs": 0}}  # no message field: the default alone
    assert server.ops("call_service") == []  # the registry knew both types


# ------------------------------------------------------------------------------------------ other ops


async def test_set_level_status_and_auth():
    auth = {"mac": "m", "client": "127.0.0.1", "dest": "127.0.0.1", "rand": "r", "t": 1, "level": "admin", "end": 2}
    async with ScriptedServer() as server:
        c = BridgeClient(server.url, auth=auth)
        await c.connect(timeout=5)
        c.set_level("warning")
        await server.wait_for("set_level")
        assert server.received[0] == {"op": "auth", **auth}  # auth is the first frame
        assert server.ops("set_level")[0]["level"] == "warning"
        with pytest.raises(ValueError, match="level must be one of"):
            c.set_level("loud")
        seen = []
        c.add_status_listener(seen.append)
        await server.send({"op": "status", "level": "warning", "msg": "careful", "id": "x"})
        await until(lambda: seen)
        assert seen[0]["msg"] == "careful"
        await c.close()
    with pytest.raises(ValueError, match="missing rosauth field"):
        BridgeClient("ws://127.0.0.1:1", auth={"mac": "m"})


async def test_an_auth_that_takes_time_goes_first_and_calls_wait_for_it():
    """The socket is open while an awaitable auth is being made: nothing may go out before the auth op,
    and a call made meanwhile waits for the restored link (not for its timeout)."""
    auth = {"mac": "m", "client": "127.0.0.1", "dest": "127.0.0.1", "rand": "r", "t": 1, "level": "admin", "end": 2}
    gate, asked = asyncio.Event(), []

    async def slow_auth():
        asked.append(1)
        await gate.wait()
        return auth

    async with ScriptedServer() as server:
        server.services["/ok"] = lambda f: {"op": "service_response", "id": f["id"], "service": f["service"],
                                            "values": {"v": 1}, "result": True}
        c = BridgeClient(server.url, auth=slow_auth)
        connecting = asyncio.ensure_future(c.connect(timeout=5))
        await until(lambda: c.connected)  # the socket is open; the auth is not made yet
        call = asyncio.ensure_future(c.call_service("/ok", {}, timeout=5))
        await until(lambda: asked, what="the auth being made")
        assert not call.done() and server.received == []  # (the order check below is the one that counts)
        gate.set()
        assert await asyncio.wait_for(call, 3) == {"v": 1}
        await connecting
        assert [f["op"] for f in server.received] == ["auth", "call_service"]
        await c.close()
    with pytest.raises(ValueError, match="ws:// or wss://"):
        BridgeClient("http://x")


async def test_action_goal_feedback_result_and_cancel(server, client):
    server.services["/rosapi/action_servers"] = lambda f: {
        "op": "service_response", "id": f["id"], "service": f["service"], "result": True,
        "values": {"action_servers": ["/fibonacci"]}}
    node = client.node("nav")
    feedback = []
    goal = node.send_action_goal("/fibonacci", "example_interfaces/action/Fibonacci", {"order": 3}, feedback.append)
    (sent,) = await server.wait_for("send_action_goal")
    assert sent == {"op": "send_action_goal", "id": goal.id, "action": "/fibonacci",
                    "action_type": "example_interfaces/action/Fibonacci", "args": {"order": 3}, "feedback": True}
    await server.send({"op": "action_feedback", "id": goal.id, "action": "/fibonacci", "values": {"sequence": [0, 1]}})
    await server.send({"op": "action_result", "id": goal.id, "action": "/fibonacci",
                       "values": {"sequence": [0, 1, 1, 2]}, "status": 4, "result": True})
    assert await goal.result(timeout=5) == {"sequence": [0, 1, 1, 2]}
    assert feedback == [{"sequence": [0, 1]}] and goal.status == GoalStatus.SUCCEEDED and goal.succeeded
    # no callback: feedback is still asked for (it is how a running goal shows it was accepted, goals.py)
    # and kept to the client
    g2 = node.send_action_goal("/fibonacci", "example_interfaces/action/Fibonacci", [50])
    (sent2,) = await server.wait_for("send_action_goal", id=g2.id)
    assert sent2["feedback"] is True and sent2["args"] == [50]
    g2.cancel()
    (cancel,) = await server.wait_for("cancel_action_goal")
    assert cancel == {"op": "cancel_action_goal", "id": g2.id, "action": "/fibonacci"}
    # rosbridge's ROS 2 capability answers a cancelled goal with result true and status CANCELED
    await server.send({"op": "action_result", "id": g2.id, "action": "/fibonacci",
                       "values": {"sequence": [0, 1]}, "status": 5, "result": True})
    assert await g2.result(timeout=5) == {"sequence": [0, 1]}
    assert g2.status == GoalStatus.CANCELED and not g2.succeeded and g2.cancel_requested
    # a goal the server could not run: result false, status 0, the error as a string (its _failure shape)
    g3 = node.send_action_goal("/fibonacci", "example_interfaces/action/Fibonacci", {"order": 1})
    await server.send({"op": "action_result", "id": g3.id, "action": "/fibonacci",
                       "values": "No action server available", "status": 0, "result": False})
    with pytest.raises(ActionError, match="^/fibonacci: No action server available$") as info:
        await g3.result(timeout=5)
    assert info.value.status == GoalStatus.UNKNOWN


async def test_action_goal_errors_reach_the_caller_promptly(server, client):
    node = client.node("nav")
    # ROS 1 rosapi lists its actionlib servers (none in the recording): the goal fails at once, clearly
    goal = node.send_action_goal("/no_such_action", "pkg/action/Nope", {})
    with pytest.raises(ActionError, match=r"^/no_such_action: action does not exist \(action servers: none\)"):
        await goal.result(timeout=5)
    (cancel,) = await server.wait_for("cancel_action_goal", id=goal.id)
    # an error status naming the goal ends it (the op failed on the server, no result will come)
    g2 = node.send_action_goal("/x", "pkg/action/X", check=False)
    await server.send({"op": "status", "level": "error", "id": g2.id, "msg": "send_action_goal: bad args"})
    with pytest.raises(ActionError, match="bad args"):
        await g2.result(timeout=5)
    # nothing ever comes back: the client-side timeout cancels the goal and says so
    g3 = node.send_action_goal("/silent", "pkg/action/X", check=False, timeout=0.2)
    with pytest.raises(ActionTimeoutError, match="no result within 0.2 s") as info:
        await g3.result(timeout=5)
    assert isinstance(info.value, TimeoutError)
    await server.wait_for("cancel_action_goal", id=g3.id)
    # a late result for a finished goal is ignored
    await server.send({"op": "action_result", "id": g3.id, "action": "/silent", "values": {}, "status": 5,
                       "result": True})
    for bad, exc in ((dict(action="", action_type="a/b"), ValueError), (dict(action="/a", action_type="ab"), ValueError),
                     (dict(action="/a", action_type="a/b", args="x"), TypeError),
                     (dict(action="/a", action_type="a/b", timeout=0), ValueError),
                     (dict(action="/a", action_type="a/b", feedback=3), TypeError)):
        with pytest.raises(exc):
            node.send_action_goal(**bad)
    # the link drops while a goal runs: ConnectionLostError
    g4 = node.send_action_goal("/x", "pkg/action/X", check=False)
    await server.wait_for("send_action_goal", id=g4.id)
    await server.drop()
    with pytest.raises(ConnectionLostError):
        await g4.result(timeout=5)


# ------------------------------------------------------------------------------------------ bad input


BAD_FRAMES = [
    "this is not json",
    '{"op": "call_service", "service": "/x"',
    '{"id": "noop"}',
    '{"receiver": "/rosapi/get_time", "msg": {}}',
    '{"op": "frobnicate"}',
    '{"op": 5}',
    "[1, 2, 3]",
    '"a string"',
    "",
    "NaN",
    '{"op":"publish"}',
    '{"op":"publish","topic":"/rec/str"}',
    '{"op":"publish","topic":42,"msg":{}}',
    '{"op":"publish","topic":["/rec/str"],"msg":{}}',
    '{"op":"service_response","id":"nobody","values":{},"result":true}',
    '{"op":"service_response","id":[1],"values":{}}',
    '{"op":"fragment","id":0,"data":"abc","num":3,"total":5}',
    '{"op":"fragment","id":0,"data":7,"num":0,"total":5}',
    '{"op":"fragment","id":0,"data":"x","num":0,"total":"many"}',
    '{"op":"png","data":"bm90IGEgcG5n"}',
    '{"op":"png"}',
    '{"op":"call_service","service":5}',
    '{"op":"action_result","values":{}}',
    '{"op":"status","level":"error"}',
    b"\xff\xfe\x00garbage",
    b"",
]


async def test_bad_frames_are_logged_and_never_kill_anything(server, caplog):
    client = BridgeClient(server.url, max_message_size=1 << 16)
    await client.connect(timeout=5)
    got = []
    client.node("s").subscribe("/rec/str", got.append)
    await until(lambda: len(got) == 2)
    with caplog.at_level(logging.WARNING, logger="rcon_core.bridge"):
        for frame in BAD_FRAMES:
            await server.send(frame)
        # endless fragments: a new message always starts before the last one ends
        for _ in range(50):
            await server.send({"op": "fragment", "id": 0, "data": "{", "num": 0, "total": 1000})
        await server.send("x" * (1 << 17))  # a huge frame
        # a good frame after all that is still delivered, and calls still work
        await server.send(recorded().frames[("/rec/str", "none")][0])
        await until(lambda: len(got) == 3)
        assert (await client.call_service("/rosapi/get_time", {}))["time"]["secs"] > 1795259000
    assert client.connected and client.stats["connects"] == 1
    assert client.stats["bad_frames"] >= len(BAD_FRAMES) - 2  # all but the two ignored service_responses
    assert client.stats["oversize_frames"] == 1
    assert len(client.inbound.fragments) <= 1
    for text in ("not valid JSON", "unknown op 'frobnicate'", "without 'op'", "not an object",
                 "malformed 'publish' frame", "num 0 missing", "not a PNG", "neither CBOR nor JSON",
                 "exceeds max_message_size", "empty binary frame", "logged every 1000th"):
        assert text in caplog.text, text
    assert caplog.text.count("a new message started before") <= 21  # rate limited
    await client.close()


# ------------------------------------------------------------------------------------------ reconnect


async def test_reconnect_restores_everything_and_handles_publishes_while_down(server):
    states = []
    c = BridgeClient(server.url, backoff_min=0.05, backoff_max=0.2, latency_interval=0.1)
    c.add_state_listener(states.append)
    await c.connect(timeout=5)
    node = c.node("w")
    got = []
    node.subscribe("/rec/str", got.append, type="std_msgs/String", throttle_rate=50)
    cmd = node.advertise("/cmd_vel", "geometry_msgs/Twist")
    latched = node.advertise("/mode", "std_msgs/String", latch=True)
    node.advertise_service("/client/trigger", "std_srvs/Trigger", lambda req: {"success": True, "message": ""})
    c.set_level("error")
    await until(lambda: len(got) == 2)
    await until(lambda: c.latency is not None)
    assert c.latency >= 0

    # a call waiting when the link drops fails at once instead of hanging
    server.services["/slow"] = lambda f: None
    pending = asyncio.ensure_future(c.call_service("/slow", timeout=30))
    await server.wait_for("call_service", service="/slow")
    await server.stop()  # the robot goes away
    with pytest.raises(ConnectionLostError):
        await asyncio.wait_for(pending, 5)
    await until(lambda: c.state is ConnectionState.RECONNECTING)
    assert cmd.publish({"linear": {"x": 1.0}}) is False  # dropped, not queued for later
    assert cmd.dropped == 1 and c.stats["dropped_while_down"] == 1
    assert latched.publish({"data": "old"}) and latched.publish({"data": "newest"})
    received_before = len(server.received)

    await server.start()  # same port
    await until(lambda: c.state is ConnectionState.CONNECTED, timeout=10)

    def restored() -> list[tuple[str, str]]:
        return [(f["op"], f.get("topic") or f.get("service")) for f in server.received[received_before:]]

    # CONNECTED is the client's word; the server reads the restoring frames a moment later (a loaded machine)
    await until(lambda: {("advertise", "/cmd_vel"), ("subscribe", "/rec/str"), ("publish", "/mode")} <= set(restored()))
    new = server.received[received_before:]
    ops = restored()
    assert ("advertise", "/cmd_vel") in ops and ("advertise", "/mode") in ops
    assert ("advertise_service", "/client/trigger") in ops and ("subscribe", "/rec/str") in ops
    assert new[0] == {"op": "set_level", "level": "error"}
    assert ops.index(("advertise", "/mode")) < ops.index(("publish", "/mode"))
    pubs = [f for f in new if f["op"] == "publish"]
    assert [p["msg"] for p in pubs] == [{"data": "newest"}]  # only the latest latched value, no stale cmd_vel
    sub = next(f for f in new if f["op"] == "subscribe")
    assert sub["throttle_rate"] == 50 and sub["type"] == "std_msgs/String"
    await until(lambda: len(got) == 4)  # the subscription works again
    assert states[:3] == [ConnectionState.CONNECTING, ConnectionState.CONNECTED, ConnectionState.RECONNECTING]
    assert states[-1] is ConnectionState.CONNECTED
    # an abrupt drop (no close handshake) is survived too
    await server.drop(abort=True)
    await until(lambda: c.stats["connects"] == 3, timeout=10)
    await c.close()
    assert c.state is ConnectionState.CLOSED


async def test_no_reconnect_raises_on_first_failure_and_calls_fail_fast():
    c = BridgeClient("ws://127.0.0.1:9", reconnect=False)
    with pytest.raises(OSError):
        await c.connect()
    assert c.state is ConnectionState.CLOSED
    with pytest.raises(NotConnectedError):
        await c.call_service("/x")
    goal = c.node("n").send_action_goal("/a", "pkg/action/A")
    with pytest.raises(NotConnectedError):
        await goal.result()


async def test_connect_timeout_while_retrying():
    c = BridgeClient("ws://127.0.0.1:9", backoff_min=0.05, backoff_max=0.1)
    with pytest.raises(TimeoutError, match="not connected"):
        await c.connect(timeout=0.5)
    assert c.state is ConnectionState.CONNECTING
    await c.close()
    assert c.state is ConnectionState.CLOSED


async def test_without_reconnect_a_drop_closes(server):
    c = BridgeClient(server.url, reconnect=False)
    await c.connect()
    assert c.state is ConnectionState.CONNECTED
    await server.drop()
    await until(lambda: c.state is ConnectionState.CLOSED)
    await c.close()


async def test_node_ids_are_unique_and_close_ends_everything(server, client):
    a, b = client.node("slider"), client.node("slider")
    assert a.id == "slider" and b.id == "slider#2"
    a.subscribe("/rec/bool", lambda m: None)
    a.advertise("/x", "std_msgs/Bool")
    await server.wait_for("advertise")
    a.close()
    await server.wait_for("unadvertise")
    await server.wait_for("unsubscribe")
    with pytest.raises(BridgeError, match="closed"):
        a.subscribe("/rec/bool", print)
    assert client.node("slider").id == "slider"


async def test_messages_dict_frames_are_plain_json(server, client):
    """The subscribed dicts are exactly what orjson gives for the recorded text (no copying, no wrapping)."""
    got = []
    client.node("n").subscribe("/rec/image", got.append)
    await until(lambda: len(got) == 2)
    expected = orjson.loads(recorded().frames[("/rec/image", "none")][0])["msg"]
    assert got[0] == expected and isinstance(got[0]["data"], str)  # base64 left lazy


async def test_cbor_raw_uses_the_registry_when_given(server):
    """With a TypeRegistry the registry's deserialize_ros1 decodes cbor-raw; it agrees with the built-in decoder."""
    msgs = pytest.importorskip("rcon_core.msgs")
    reg = msgs.TypeRegistry.standard()
    c = BridgeClient(server.url, registry=reg)
    plain = BridgeClient(server.url)
    await c.connect(timeout=5)
    await plain.connect(timeout=5)
    a, b = [], []
    c.node("n").subscribe("/rec/imu", a.append, type="sensor_msgs/Imu", compression="cbor")
    plain.node("n").subscribe("/rec/imu", b.append, type="sensor_msgs/Imu", compression="cbor")
    await until(lambda: len(a) == 2 and len(b) == 2)
    assert c.session.topics["/rec/imu"].decoder.registry is reg
    learned = plain.session.topics["/rec/imu"].decoder.registry  # learned from the server's typedefs
    assert learned is not reg and learned.names() and not learned.has("std_srvs/SetBool")
    assert a == b
    await c.close()
    await plain.close()


async def test_result_false_with_an_object_answer_names_its_message(server, client):
    server.services["/other_rcon"] = lambda f: {"op": "service_response", "id": f["id"], "service": f["service"],
                                                "result": False, "values": {"success": False, "message": "jammed"}}
    server.services["/plain"] = lambda f: {"op": "service_response", "id": f["id"], "service": f["service"],
                                           "result": False, "values": {"code": 3}}
    with pytest.raises(ServiceError, match="^/other_rcon: jammed$"):
        await client.call_service("/other_rcon", timeout=3)
    with pytest.raises(ServiceError, match="'code': 3"):
        await client.call_service("/plain", timeout=3)
