"""rosapi of the sim in --ros2 mode, in raw frames: the rosapi 2.x service set, versions, node parameters."""

from __future__ import annotations

import base64
import json
from collections.abc import AsyncIterator
from typing import Any

import pytest_asyncio
import websockets

from rcon_core.sim import SimServer


@pytest_asyncio.fixture
async def sim2() -> AsyncIterator[SimServer]:
    server = SimServer(ros2=True, rate_scale=4.0)
    await server.start()
    try:
        yield server
    finally:
        await server.stop()


class Raw:
    """One raw WebSocket client calling services by frames."""

    def __init__(self, ws: Any) -> None:
        self.ws = ws
        self.n = 0

    async def call(self, service: str, args: dict[str, Any] | None = None) -> dict[str, Any]:
        self.n += 1
        cid = f"c{self.n}"
        await self.ws.send(json.dumps({"op": "call_service", "id": cid, "service": service, "args": args or {}}))
        while True:
            frame = json.loads(await self.ws.recv())
            if frame.get("id") == cid:
                return frame


async def test_rosapi_2x_service_set_and_types(sim2: SimServer) -> None:
    async with websockets.connect(sim2.url) as ws:
        raw = Raw(ws)
        services = (await raw.call("/rosapi/services"))["values"]["services"]
        rosapi = sorted(s for s in services if s.startswith("/rosapi/"))
        types = {s: (await raw.call("/rosapi/service_type", {"service": s}))["values"]["type"] for s in rosapi}
        version = await raw.call("/rosapi/get_ros_version")
        missing = await raw.call("/rosapi/search_param", {"name": "x"})
    assert "/rosapi/search_param" not in rosapi and "/rosapi/service_host" not in rosapi
    assert {"/rosapi/get_ros_version", "/rosapi/topics_and_raw_types", "/rosapi/action_servers"} <= set(rosapi)
    assert types["/rosapi/topics"] == "rosapi_msgs/srv/Topics"
    assert types["/rosapi/get_ros_version"] == "rosapi_msgs/srv/GetROSVersion"
    # rosapi's own services; the rosapi node's parameter services share the prefix, as on a real robot
    assert all(t.startswith("rosapi_msgs/srv/") or t.startswith("rcl_interfaces/srv/") for t in types.values())
    assert types["/rosapi/get_parameters"] == "rcl_interfaces/srv/GetParameters"
    assert version == {"op": "service_response", "service": "/rosapi/get_ros_version", "id": "c" + str(raw.n - 1),
                       "values": {"version": 2, "distro": "jazzy"}, "result": True}
    assert missing["result"] is False and "does not exist" in missing["values"]
    # no ROS 1 logger services on ROS 2 nodes
    assert not [s for s in services if s.endswith(("/get_loggers", "/set_logger_level"))]


async def test_ros1_mode_keeps_rosapi_1(sim: SimServer) -> None:
    async with websockets.connect(sim.url) as ws:
        raw = Raw(ws)
        topics_type = (await raw.call("/rosapi/service_type", {"service": "/rosapi/topics"}))["values"]["type"]
        search = await raw.call("/rosapi/search_param", {"name": "kingfisher"})
        version = await raw.call("/rosapi/get_ros_version")
        param = await raw.call("/rosapi/get_param", {"name": "/kingfisher/max_speed"})
    assert topics_type == "rosapi/Topics"
    assert search["result"] is True
    assert version["result"] is False  # rosapi 0.11 has no get_ros_version
    assert json.loads(param["values"]["value"]) == 2.0


async def test_topics_and_raw_types_and_message_details(sim2: SimServer) -> None:
    async with websockets.connect(sim2.url) as ws:
        raw = Raw(ws)
        listing = (await raw.call("/rosapi/topics_and_raw_types"))["values"]
        unknown = await raw.call("/rosapi/message_details", {"type": "no_pkg/msg/Nothing"})
        goal = await raw.call("/rosapi/message_details", {"type": "example_interfaces/action/Fibonacci_Goal"})
    assert list(listing) == ["topics", "types", "typedefs_full_text"]
    assert len(listing["topics"]) == len(listing["types"]) == len(listing["typedefs_full_text"])
    text = dict(zip(listing["topics"], listing["typedefs_full_text"], strict=True))
    gps = text["/gps/fix"]
    assert "float64 latitude" in gps and "std_msgs/Header header" in gps and "/msg/" not in gps
    # depth first from the last field, as rosapi 2.x walks its stack; time is a message there
    assert [line for line in gps.splitlines() if line.startswith("MSG: ")] == [
        "MSG: sensor_msgs/NavSatStatus", "MSG: std_msgs/Header", "MSG: builtin_interfaces/Time"]
    assert gps.endswith("MSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n")
    # rosapi 2.x logs a type it cannot load and answers an empty list (no failure)
    assert unknown["result"] is True and unknown["values"] == {"typedefs": []}
    # nor the parts of an action (rosapi 2.1.0 looks for them where the package does not export them)
    assert goal["result"] is True and goal["values"] == {"typedefs": []}


async def test_parameters_per_node(sim2: SimServer) -> None:
    async with websockets.connect(sim2.url) as ws:
        raw = Raw(ws)
        names = (await raw.call("/rosapi/get_param_names"))["values"]["names"]
        got = (await raw.call("/rosapi/get_param", {"name": "/kingfisher:max_speed"}))["values"]
        nested = (await raw.call("/rosapi/get_param", {"name": "/kingfisher:gps.origin_lat"}))["values"]
        port = (await raw.call("/rosapi/get_param", {"name": "/rosbridge_websocket:actual_port"}))["values"]
        set_ok = await raw.call("/rosapi/set_param", {"name": "/kingfisher:max_speed", "value": "3.5"})
        after = (await raw.call("/rosapi/get_param", {"name": "/kingfisher:max_speed"}))["values"]
        # an integer for a double parameter: the node refuses, rosapi still answers success
        refused = await raw.call("/rosapi/set_param", {"name": "/kingfisher:max_speed", "value": "4"})
        unchanged = (await raw.call("/rosapi/get_param", {"name": "/kingfisher:max_speed"}))["values"]
        # a JSON string is unwrapped and typed again: "\"hello\"" sets the string hello
        await raw.call("/rosapi/set_param", {"name": "/kingfisher:frame_id", "value": json.dumps("hull")})
        frame_id = (await raw.call("/rosapi/get_param", {"name": "/kingfisher:frame_id"}))["values"]
        undeclared = await raw.call("/rosapi/set_param", {"name": "/kingfisher:new_one", "value": "1"})
        has = [(await raw.call("/rosapi/has_param", {"name": n}))["values"]["exists"]
               for n in ("/kingfisher:max_speed", "/kingfisher:new_one", "/nobody:x", "max_speed")]
        missing = (await raw.call("/rosapi/get_param", {"name": "/kingfisher:nope"}))["values"]
        missing_default = (await raw.call("/rosapi/get_param", {"name": "/kingfisher:nope",
                                                               "default_value": "7"}))["values"]
        malformed = (await raw.call("/rosapi/get_param", {"name": "max_speed"}))["values"]
        bad_json = await raw.call("/rosapi/set_param", {"name": "/kingfisher:max_speed", "value": "not json"})
        deleted = await raw.call("/rosapi/delete_param", {"name": "/kingfisher:watchdog_timeout"})
        gone = (await raw.call("/rosapi/has_param", {"name": "/kingfisher:watchdog_timeout"}))["values"]
    assert "/kingfisher:max_speed" in names and "/kingfisher:use_sim_time" in names
    assert "/kingfisher:gps.origin_lat" in names and "/rosbridge_websocket:actual_port" in names
    assert not [n for n in names if n.startswith(("/rosapi:", "/rosout:"))]  # rosapi does not list itself
    assert all(n.count(":") == 1 for n in names)
    assert got == {"value": "2.0"} and json.loads(nested["value"]) == sim2.robot.origin_lat
    assert json.loads(port["value"]) == sim2.port
    assert set_ok["result"] is True and set_ok["values"] == {} and after == {"value": "3.5"}
    assert refused["result"] is True and unchanged == {"value": "3.5"}
    assert frame_id == {"value": '"hull"'}
    assert undeclared["result"] is True
    assert has == [True, False, False, False]
    assert missing == {"value": '""'} and missing_default == {"value": "7"}
    assert malformed == {"value": ""}
    assert bad_json["result"] is False and "JSON" in bad_json["values"]
    assert deleted["result"] is True and gone == {"exists": False}


async def test_each_node_serves_its_parameters(sim2: SimServer) -> None:
    """The ROS 2 node parameter services, as rosbridge's own tests use them to read ``actual_port``."""
    async with websockets.connect(sim2.url) as ws:
        raw = Raw(ws)
        services = (await raw.call("/rosapi/services"))["values"]["services"]
        kind = (await raw.call("/rosapi/service_type", {"service": "/kingfisher/set_parameters"}))["values"]
        port = await raw.call("/rosbridge_websocket/get_parameters", {"names": ["actual_port", "nope"]})
        listed = (await raw.call("/kingfisher/list_parameters", {"prefixes": ["gps"]}))["values"]
        refused = (await raw.call("/kingfisher/set_parameters", {"parameters": [
            {"name": "max_speed", "value": {"type": 2, "integer_value": 3}},
            {"name": "max_yaw_rate", "value": {"type": 3, "double_value": 0.5}}]}))["values"]
        via_rosapi = (await raw.call("/rosapi/get_param", {"name": "/kingfisher:max_yaw_rate"}))["values"]
        types = (await raw.call("/kingfisher/get_parameter_types", {"names": ["frame_id", "use_sim_time"]}))["values"]
    for node in ("/kingfisher", "/rosbridge_websocket", "/rosapi"):
        assert {f"{node}/get_parameters", f"{node}/set_parameters", f"{node}/list_parameters"} <= set(services)
    assert kind == {"type": "rcl_interfaces/srv/SetParameters"}
    values = port["values"]["values"]
    assert values[0]["type"] == 2 and values[0]["integer_value"] == sim2.port
    assert values[1]["type"] == 0
    assert listed == {"result": {"names": ["gps.origin_lat", "gps.origin_lon"], "prefixes": ["gps"]}}
    assert refused["results"][0]["successful"] is False and "double" in refused["results"][0]["reason"]
    assert refused["results"][1] == {"successful": True, "reason": ""}
    assert via_rosapi == {"value": "0.5"}
    assert base64.b64decode(types["types"]) == bytes([4, 1])  # uint8[] travels as base64


async def test_time_fields_take_either_spelling_and_now(sim2: SimServer) -> None:
    """rosbridge 2.x fills builtin_interfaces/Time from sec/nanosec or secs/nsecs, and from "now"."""
    frames = [{"header": {"stamp": {"secs": 5, "nsecs": 6}, "frame_id": "a"}, "point": {"x": 1.0}},
              {"header": {"stamp": {"sec": 7}, "frame_id": "b"}},
              {"header": {"stamp": "now", "frame_id": "c"}}]
    async with websockets.connect(sim2.url) as ws:
        await ws.send(json.dumps({"op": "advertise", "topic": "/clicked", "type": "geometry_msgs/PointStamped"}))
        for msg in frames:
            await ws.send(json.dumps({"op": "publish", "topic": "/clicked", "msg": msg}))
        await sim2.wait_for_published("/clicked", lambda m: m["header"]["frame_id"] == "c")
    a, b, c = sim2.published("/clicked")
    assert a["header"]["stamp"] == {"sec": 5, "nanosec": 6} and a["point"] == {"x": 1.0, "y": 0.0, "z": 0.0}
    assert b["header"]["stamp"] == {"sec": 7, "nanosec": 0}
    assert c["header"]["stamp"]["sec"] > 1_600_000_000
