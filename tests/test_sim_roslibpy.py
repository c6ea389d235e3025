"""The sim seen through roslibpy, an independent rosbridge client (sync, twisted in a thread)."""

from __future__ import annotations

import base64
import threading
import time
from collections.abc import Callable, Iterator
from typing import Any

import pytest
import roslibpy

from rcon_core.sim import SimServer
from rcon_core.sim.graph import BRIDGE_NODE
from rcon_core.testing import until_sync

TIMEOUT = 10.0


@pytest.fixture
def ros(sim_thread: SimServer) -> Iterator[roslibpy.Ros]:
    client = roslibpy.Ros(host="127.0.0.1", port=sim_thread.port)
    client.run(timeout=TIMEOUT)
    try:
        yield client
    finally:
        client.close()


def first_message(ros: roslibpy.Ros, topic: str, type_name: str | None = None,
                  pred: Callable[[dict[str, Any]], bool] = lambda m: True) -> dict[str, Any]:
    """Subscribe, wait for a message that fits ``pred``, unsubscribe."""
    got: list[dict[str, Any]] = []
    event = threading.Event()

    def on_message(msg: dict[str, Any]) -> None:
        if not event.is_set() and pred(msg):
            got.append(msg)
            event.set()

    listener = roslibpy.Topic(ros, topic, type_name)
    listener.subscribe(on_message)
    try:
        assert event.wait(TIMEOUT), f"no message on {topic}"
    finally:
        listener.unsubscribe()
    return got[0]


def test_discovery(ros: roslibpy.Ros) -> None:
    topics = ros.get_topics()
    assert {"/odom", "/gps/fix", "/imu/data", "/scan", "/map", "/camera/front/image_raw"} <= set(topics)
    assert ros.get_topic_type("/gps/fix") == "sensor_msgs/NavSatFix"
    services = ros.get_services()
    assert {"/reset_pose", "/lights/set", "/dock", "/rosapi/topics"} <= set(services)
    assert ros.get_service_type("/dock") == "std_srvs/Trigger"
    details = ros.get_message_details("sensor_msgs/Imu")
    layout = {d["type"]: d for d in details["typedefs"]}
    assert details["typedefs"][0]["type"] == "sensor_msgs/Imu"
    assert layout["sensor_msgs/Imu"]["fieldarraylen"][2] == 9
    assert layout["time"]["fieldnames"] == ["secs", "nsecs"]
    request = ros.get_service_request_details("std_srvs/SetBool")
    assert request["typedefs"][0]["type"] == "std_srvs/SetBoolRequest"
    assert "/kingfisher" in ros.get_nodes()
    assert ros.get_time()["secs"] > 1_600_000_000


def test_sensor_streams(ros: roslibpy.Ros) -> None:
    image = first_message(ros, "/camera/front/image_raw", "sensor_msgs/Image")
    assert (image["width"], image["height"], image["encoding"], image["step"]) == (640, 480, "rgb8", 1920)
    assert len(base64.b64decode(image["data"])) == 640 * 480 * 3
    rear = first_message(ros, "/camera/rear/image_raw/compressed")
    assert base64.b64decode(rear["data"])[:3] == b"\xff\xd8\xff"
    fix = first_message(ros, "/gps/fix", "sensor_msgs/NavSatFix")
    assert 43.0 < fix["latitude"] < 44.0 and -80.0 < fix["longitude"] < -79.0
    imu = first_message(ros, "/imu/data")
    q = imu["orientation"]
    assert abs(q["x"] ** 2 + q["y"] ** 2 + q["z"] ** 2 + q["w"] ** 2 - 1.0) < 1e-6
    assert 9.0 < imu["linear_acceleration"]["z"] < 10.6
    scan = first_message(ros, "/scan", "sensor_msgs/LaserScan")
    assert len(scan["ranges"]) == 360 and scan["range_max"] == 30.0
    grid = first_message(ros, "/map", "nav_msgs/OccupancyGrid")
    assert len(grid["data"]) == grid["info"]["width"] * grid["info"]["height"]


def test_cmd_vel_drives_then_watchdog_stops(ros: roslibpy.Ros, sim_thread: SimServer) -> None:
    cmd = roslibpy.Topic(ros, "/cmd_vel", "geometry_msgs/Twist")
    cmd.advertise()
    start = first_message(ros, "/odom")["pose"]["pose"]["position"]
    for _ in range(8):
        cmd.publish(roslibpy.Message({"linear": {"x": 1.5, "y": 0.0, "z": 0.0},
                                      "angular": {"x": 0.0, "y": 0.0, "z": 0.0}}))
        time.sleep(0.1)
    moving = first_message(ros, "/odom", pred=lambda m: m["twist"]["twist"]["linear"]["x"] > 0.3)
    position = moving["pose"]["pose"]["position"]
    assert (position["x"], position["y"]) != (start["x"], start["y"])
    cmd.unadvertise()
    stopped = first_message(ros, "/rosout", pred=lambda m: "watchdog" in m["msg"])
    assert stopped["name"] == "/kingfisher"
    assert sim_thread.robot.cmd_surge == 0.0 and sim_thread.robot.watchdog_tripped


def test_each_service(ros: roslibpy.Ros, sim_thread: SimServer) -> None:
    lights = roslibpy.Service(ros, "/lights/set", "std_srvs/SetBool")
    assert lights.call(roslibpy.ServiceRequest({"data": True}), timeout=TIMEOUT)["success"] is True
    assert first_message(ros, "/lights/state")["data"] is True
    dock = roslibpy.Service(ros, "/dock", "std_srvs/Trigger")
    answer = dock.call(roslibpy.ServiceRequest(), timeout=TIMEOUT)
    assert answer["success"] is True and answer["message"]
    reset = roslibpy.Service(ros, "/reset_pose", "std_srvs/Empty")
    assert reset.call(roslibpy.ServiceRequest(), timeout=TIMEOUT) == {}
    missing = roslibpy.Service(ros, "/no/such", "std_srvs/Empty")
    with pytest.raises(roslibpy.core.ServiceException):
        missing.call(roslibpy.ServiceRequest(), timeout=TIMEOUT)
    assert sim_thread.robot.lights is True


def test_one_client_serves_another(sim_thread: SimServer) -> None:
    provider = roslibpy.Ros(host="127.0.0.1", port=sim_thread.port)
    caller = roslibpy.Ros(host="127.0.0.1", port=sim_thread.port)
    provider.run(timeout=TIMEOUT)
    caller.run(timeout=TIMEOUT)
    try:
        seen: list[dict[str, Any]] = []

        def handler(request: dict[str, Any], response: dict[str, Any]) -> bool:
            seen.append(dict(request))
            response["success"] = True
            response["message"] = f"armed={request['data']}"
            return True

        service = roslibpy.Service(provider, "/operator/arm", "std_srvs/SetBool")
        service.advertise(handler)
        until_sync(lambda: "/operator/arm" in sim_thread.services, TIMEOUT, what="the service advertised")
        client = roslibpy.Service(caller, "/operator/arm", "std_srvs/SetBool")
        answer = client.call(roslibpy.ServiceRequest({"data": True}), timeout=TIMEOUT)
        assert answer == {"success": True, "message": "armed=True"}
        assert seen == [{"data": True}]
        service.unadvertise()
    finally:
        provider.close()
        caller.close()


def test_published_messages_are_visible_to_the_server(ros: roslibpy.Ros, sim_thread: SimServer) -> None:
    note = roslibpy.Topic(ros, "/operator/note", "std_msgs/String")
    note.advertise()

    def heard() -> bool:  # roslibpy's advertise has no answer: publish until the robot hears one
        if not sim_thread.published("/operator/note"):
            note.publish(roslibpy.Message({"data": "checked"}))
            return False
        return True

    until_sync(heard, TIMEOUT, what="the note heard by the robot")
    assert sim_thread.wait_for_published_sync("/operator/note", lambda m: m["data"] == "checked") == {"data": "checked"}
    note.unadvertise()


def test_state_topics_are_latched_for_a_client_that_comes_later(sim_thread: SimServer) -> None:
    """The robot holds its speed limit and its lights' state latched (ROS 1 latched / ROS 2 transient
    local): a client connecting after they were set gets them at once, though the client that set the
    limit has gone (its own publisher with it)."""
    setter = roslibpy.Ros(host="127.0.0.1", port=sim_thread.port)
    setter.run(timeout=TIMEOUT)
    try:
        limit = roslibpy.Topic(setter, "/speed_limit", "std_msgs/Float64")
        limit.advertise()

        def limit_set() -> bool:  # publish until the robot takes it (advertise has no answer)
            if sim_thread.robot.speed_limit != 0.7:
                limit.publish(roslibpy.Message({"data": 0.7}))
                return False
            return True

        until_sync(limit_set, TIMEOUT, what="the speed limit taken")
        lights = roslibpy.Service(setter, "/lights/set", "std_srvs/SetBool")
        assert lights.call(roslibpy.ServiceRequest({"data": True}), timeout=TIMEOUT)["success"] is True
    finally:
        setter.close()
    topic = sim_thread.topics["/speed_limit"]
    # the setter's publisher is gone: what is latched is the robot's
    until_sync(lambda: not topic.publishers.get(BRIDGE_NODE), TIMEOUT, what="the setter's publisher gone")
    later = roslibpy.Ros(host="127.0.0.1", port=sim_thread.port)
    later.run(timeout=TIMEOUT)
    try:
        assert first_message(later, "/speed_limit", "std_msgs/Float64") == {"data": 0.7}
        assert first_message(later, "/lights/state", "std_msgs/Bool") == {"data": True}
    finally:
        later.close()
