"""End to end against the embedded sim over a real loopback WebSocket, with roslibpy as a second opinion."""

from __future__ import annotations

import asyncio
import threading
import time

import pytest

from rcon_core.bridge import BridgeClient, ServiceError
from rcon_core.testing import connected, until

pytestmark = pytest.mark.usefixtures("transport")  # every test runs on each transport


@pytest.fixture
async def client(sim):
    async with connected(sim.url, call_timeout=5) as c:
        yield c


async def test_subscribe_every_compression_on_the_sim(sim, client):
    got: dict[str, list] = {"none": [], "cbor": [], "cbor-raw": [], "png": []}
    for comp, box in got.items():
        client.node(f"imu-{comp}").subscribe("/imu/data", box.append, compression=comp) if comp == "none" else \
            client.node(f"odom-{comp}").subscribe("/odom", box.append, type="nav_msgs/Odometry", compression=comp)
    await until(lambda: all(len(v) >= 1 for v in got.values()))
    assert len(got["none"][0]["orientation_covariance"]) == 9
    assert len(got["cbor"][0]["pose"]["covariance"]) == 36  # odom asked as cbor arrives (as cbor-raw)
    assert sim.topic_subscriber_count("/odom") == 1  # three nodes, one rosbridge subscription


async def test_publish_and_services_on_the_sim(sim, client):
    node = client.node("teleop")
    pub = node.advertise("/cmd_vel", "geometry_msgs/Twist")  # (the publish follows it on the same connection)
    pub.publish({"linear": {"x": 0.4, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.1}})
    msg = await sim.wait_for_published("/cmd_vel", lambda m: m["linear"]["x"] == 0.4, timeout=5)
    assert msg["angular"]["z"] == 0.1
    assert (await node.call_service("/lights/set", {"data": True}))["success"] is True
    with pytest.raises(ServiceError, match="does not exist"):
        await node.call_service("/no/such/service", {})
    assert "/imu/data" in await client.rosapi.topics()
    assert await client.rosapi.topic_type("/odom") == "nav_msgs/Odometry"
    assert await client.rosapi.topic_type("/no/such/topic") is None
    t = await client.rosapi.get_time()
    assert t["secs"] > 0
    await client.rosapi.set_param("/rcon_test/value", {"a": [1, 2]})
    assert await client.rosapi.get_param("/rcon_test/value") == {"a": [1, 2]}
    assert await client.rosapi.has_param("/rcon_test/value")
    await client.rosapi.set_param("/rcon_test/scalar", "hi")
    assert await client.rosapi.get_param("/rcon_test/scalar") == "hi"
    assert "/rcon_test/scalar" in await client.rosapi.param_names()
    await client.rosapi.delete_param("/rcon_test/value")
    assert not await client.rosapi.has_param("/rcon_test/value")
    assert await client.rosapi.get_param("/rcon_test/missing", default=3) == 3
    # the sim has no get_ros_version service; a ROS 1 master's /rosversion and /rosdistro params answer
    assert await client.rosapi.ros_version() is None
    await client.rosapi.set_param("/rosversion", "1.15.15\n")
    await client.rosapi.set_param("/rosdistro", "noetic\n")
    assert await client.rosapi.ros_version() == {"version": 1, "distro": "noetic"}
    nodes = await client.rosapi.nodes()
    assert nodes and isinstance(await client.rosapi.node_details(nodes[0]), dict)
    assert isinstance(await client.rosapi.publishers("/odom"), list)
    assert isinstance(await client.rosapi.action_servers(), list)


async def test_advertised_service_called_by_roslibpy_through_the_sim(sim, client):
    roslibpy = pytest.importorskip("roslibpy")
    client.node("provider").advertise_service("/rcon/echo", "std_srvs/SetBool",
                                              lambda req: {"success": req["data"], "message": "from rcon"})
    await until(lambda: "/rcon/echo" in sim.services, what="the service advertised")

    def call():
        ros = roslibpy.Ros("127.0.0.1", sim.port)
        ros.run(timeout=10)
        try:
            svc = roslibpy.Service(ros, "/rcon/echo", "std_srvs/SetBool")
            return svc.call(roslibpy.ServiceRequest({"data": True}), timeout=10)
        finally:
            ros.close()

    result = await asyncio.to_thread(call)
    assert dict(result) == {"success": True, "message": "from rcon"}


def test_same_messages_as_roslibpy(sim_thread):
    """Both clients subscribed to the sim's latched /map see the same message."""
    roslibpy = pytest.importorskip("roslibpy")
    got_rl: list = []
    done = threading.Event()
    ros = roslibpy.Ros("127.0.0.1", sim_thread.port)
    ros.run(timeout=10)
    try:
        topic = roslibpy.Topic(ros, "/map", "nav_msgs/OccupancyGrid")
        topic.subscribe(lambda m: (got_rl.append(m), done.set()))
        assert done.wait(10)
    finally:
        ros.close()

    async def ours():
        c = BridgeClient(sim_thread.url)
        await c.connect(timeout=5)
        box: list = []
        c.node("map").subscribe("/map", box.append, type="nav_msgs/OccupancyGrid")
        await until(lambda: box)
        await c.close()
        return box[0]

    mine = asyncio.run(ours())
    for m in (mine, got_rl[0]):
        m["header"].pop("seq", None)
    assert mine == got_rl[0]


@pytest.mark.parametrize("srv_type", ["std_srvs/Trigger", "std_srvs/SetBool"])
async def test_a_failing_handler_answers_the_caller_promptly(sim, client, srv_type, caplog):
    """Through the sim (which, like rosbridge 0.11, rejects a non-object answer), a second client calling a
    service whose handler raises gets the response type's default with the error text, not a hang."""

    async def broken(req):
        await asyncio.sleep(0)
        raise RuntimeError("gripper jammed")

    srv = client.node("provider").advertise_service("/rcon/broken", srv_type, broken)
    await until(lambda: "/rcon/broken" in sim.services)
    other = BridgeClient(sim.url, call_timeout=5)
    await other.connect(timeout=5)
    try:
        started = time.monotonic()
        args = {"data": True} if srv_type.endswith("SetBool") else {}
        answer = await other.node("caller").call_service("/rcon/broken", args, timeout=5)
        elapsed = time.monotonic() - started
        again = await other.node("caller").call_service("/rcon/broken", args, timeout=5)
    finally:
        await other.close()
    assert answer == {"success": False, "message": "RuntimeError: gripper jammed"} == again
    assert elapsed < 3  # prompt: one rosapi round trip, far from the caller's timeout
    assert srv.failures == 2 and srv.calls == 2
    assert "handler of /rcon/broken (node provider) failed: RuntimeError: gripper jammed" in caplog.text
