"""rosapi 2.1.0 against RCON: only listed services are asked, and no call that kills rosapi is ever sent.

A scripted server replays the real rosbridge 2.1.0 (Jazzy) answers (``tests/recordings/rosbridge-ros2-2.1.0``,
``ScriptedServer(recording=ROS2)``); the calls that killed its rosapi are taken from the recording itself
(``rosapi.jsonl:64-76``) and must be refused before anything reaches the wire.
"""

from __future__ import annotations

import json

import pytest
from replay_server import ROS2, ScriptedServer, ThreadedServer, load

from rcon_core.app.link import fetch_catalog
from rcon_core.bridge import BridgeClient, RosapiRefusedError
from rcon_core.bridge.rosapi_guard import action_type_works, at_least, refusal
from rcon_core.bridge.rosinfo import RosInfo
from rcon_core.msgs.typedefs import clean_typedefs, parse_typedefs

pytestmark = pytest.mark.recordings

ROSAPI = load("rosapi.jsonl", ROS2)
LISTED_2_1_0 = tuple(s for s in ROSAPI[0]["received"]["values"]["services"] if s.startswith("/rosapi/"))


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


def _killers() -> list[tuple[int, dict]]:
    """The calls of rosapi.jsonl:64-76 that got no answer because they killed (or wedged) rosapi."""
    return [(n, line["sent"]) for n, line in enumerate(ROSAPI, 1)
            if n >= 64 and line["received"] is None and "probe" not in line["sent"]["id"]]


async def test_the_profile_reads_a_2_1_0_server(client, server):
    info = await client.rosapi_profile()
    assert info.version == 2 and info.distro == "jazzy" and info.source == "get_ros_version"
    assert set(info.rosapi_services) == set(LISTED_2_1_0)
    assert not at_least(info, "2.2.0") and not action_type_works(info)
    await client.rosapi_profile()
    await client.detect_ros()
    assert len(server.ops("call_service", service="/rosapi/services")) == 1  # once per connection


@pytest.mark.parametrize(("line", "frame"), _killers(), ids=lambda v: str(v) if isinstance(v, int) else "")
async def test_calls_that_kill_rosapi_are_never_sent(client, server, line, frame):
    before = len(server.received)
    with pytest.raises(RosapiRefusedError, match="not sent") as refused:
        await client.call_service(frame["service"], frame["args"])
    sent = [f for f in server.received[before:] if isinstance(f, dict) and f.get("service") == frame["service"]]
    assert sent == [], f"rosapi.jsonl:{line} reached the wire"
    assert "kill" in str(refused.value) or "deadlock" in str(refused.value)


async def test_safe_forms_of_the_same_calls_still_go_out(client, server):
    """The hazard is in the arguments: a listed node's details and a parameter of the demo node are asked."""
    details = await client.call_service("/rosapi/node_details", {"node": "/peer2_node"})
    assert details == ROSAPI[11]["received"]["values"]
    value = await client.call_service("/rosapi/get_param", {"name": "/peer2_node:speed_limit"})
    assert value == {"value": "1.5"}
    assert server.ops("call_service", service="/rosapi/node_details")


async def test_the_app_never_asks_a_2_1_0_server_for_action_type(client, server):
    """The bug seen in the app: every catalogue refresh asked /rosapi/action_type, which 2.1.0 lacks (each
    call logs an ERROR into the robot's /rosout).  Now the listing is read once and nothing else is asked."""
    for _ in range(3):
        catalog = await fetch_catalog(client)
    assert catalog["actions"] == [("/fibonacci", "")]  # the operator picks the type (app/action_type.py)
    assert server.ops("call_service", service="/rosapi/action_type") == []
    # the rosapi listing behind that decision is learned once; the catalogue's own listings are its business
    assert len(server.ops("call_service", service="/rosapi/get_ros_version")) == 1
    assert await client.rosapi.action_type("/fibonacci") is None
    assert server.ops("call_service", service="/rosapi/action_type") == []


async def test_services_rosapi_does_not_list_are_not_asked(client, server):
    """rosapi.jsonl:62-63: search_param and interfaces do not exist in 2.1.0; asking logs an ERROR into the
    robot's /rosout.  Not sent at all, and the caller learns why (so does the Action widget's look-up of
    the action details 2.1.0 lacks)."""
    for n in (62, 63):
        frame = ROSAPI[n - 1]["sent"]
        with pytest.raises(RosapiRefusedError, match="does not list"):
            await client.call_service(frame["service"], frame["args"])
        assert server.ops("call_service", service=frame["service"]) == []
    with pytest.raises(RosapiRefusedError, match="does not list"):
        await client.call_service("/rosapi/action_goal_details", {"type": "example_interfaces/action/Fibonacci"})


async def test_the_listing_is_asked_again_on_a_new_connection(client, server):
    await client.rosapi_profile()
    await server.drop()
    await server.wait_connections(2)
    await client.wait_connected()
    await client.rosapi.action_servers_with_types()
    assert len(server.ops("call_service", service="/rosapi/get_ros_version")) == 2


def _info(*extra: str, distro: str = "jazzy") -> RosInfo:
    return RosInfo(2, distro, "test", LISTED_2_1_0 + extra)


def test_releases_are_told_apart_by_what_rosapi_lists():
    """2.2.0 added /rosapi/interfaces (#988), 2.3.0 the action details (#1021), 2.4.0 action_type (#1046,
    which crashes until #1307): what is lifted on each."""
    old, v22, v23, v24 = _info(), _info("/rosapi/interfaces"), _info("/rosapi/interfaces",
                                                                     "/rosapi/action_goal_details"), \
        _info("/rosapi/interfaces", "/rosapi/action_goal_details", "/rosapi/action_type")
    has = {"name": "/peer2_node:nope"}
    assert refusal("/rosapi/has_param", has, old) and refusal("/rosapi/has_param", has, v22) is None
    assert refusal("/rosapi/delete_param", has, old) and refusal("/rosapi/delete_param", has, v22) is None
    md = {"type": "sensor_msgs/msg/Image"}
    assert refusal("/rosapi/message_details", md, v22) and refusal("/rosapi/message_details", md, v23) is None
    assert refusal("/rosapi/message_details", md, _info(distro="humble")) is None  # no _check_fields there
    assert refusal("/rosapi/message_details", {"type": "nope"}, v24)  # never without '/'
    assert refusal("/rosapi/set_param", {"name": "/n:p", "value": "not json"}, v24)
    assert refusal("/rosapi/action_type", {"action": "/f"}, v24)  # listed, but crashes in every release
    sim_like = _info("/rosapi/action_goal_details", "/rosapi/action_type")
    assert action_type_works(sim_like) and refusal("/rosapi/action_type", {"action": "/f"}, sim_like) is None
    ros1 = RosInfo(1, "noetic", "test", ("/rosapi/has_param", "/rosapi/delete_param"))
    assert refusal("/rosapi/delete_param", has, ros1) is None and refusal("/rosapi/has_param", has, None) is None


# ------------------------------------------------------------------------------------------ message_details


def test_recorded_typedefs_keep_only_real_constants():
    """rosapi.jsonl:5-10, :21-23: SLOT_TYPES, every field name (Python reprs as values) and rosidl's
    <FIELD>__DEFAULT attributes are no constants; GoalStatus' STATUS_* are."""
    found = {}
    for n in (5, 7, 8, 9, 10, 21, 22, 23):
        raw = ROSAPI[n - 1]["received"]["values"]["typedefs"]
        assert any("SLOT_TYPES" in td["constnames"] for td in raw)
        for td in clean_typedefs(raw):
            found[td["type"]] = dict(zip(td["constnames"], td["constvalues"], strict=True))
        for md in parse_typedefs(raw):
            assert all("0x" not in str(c.value) and c.name != "SLOT_TYPES" for c in md.constants), md.name
    assert found["sensor_msgs/Image"] == {} and found["geometry_msgs/Quaternion"] == {}
    assert found["action_msgs/GoalStatus"]["STATUS_SUCCEEDED"] == "4" and len(found["action_msgs/GoalStatus"]) == 7


async def test_message_details_on_2_1_0_jazzy_come_from_the_msg_text(client, server):
    """message_details is not sent (a stock 2.1.0 rosapi dies on Jazzy's _check_fields slot); the typedefs
    are built from topics_and_raw_types and match what the (patched) server's message_details said."""
    tds = await client.rosapi.message_details("sensor_msgs/msg/Image")
    assert server.ops("call_service", service="/rosapi/message_details") == []
    recorded = {td["type"]: td for td in ROSAPI[6]["received"]["values"]["typedefs"]}
    assert [td["type"] for td in tds] == list(recorded)
    for td in tds:
        for key in ("fieldnames", "fieldtypes", "fieldarraylen"):
            assert td[key] == recorded[td["type"]][key], (td["type"], key)
        assert td["constnames"] == []
    with pytest.raises(RosapiRefusedError):  # a type no topic carries: not asked, and said so
        await client.rosapi.message_details("geometry_msgs/msg/Twist")


def test_cli_type_prints_the_robots_own_text_without_fake_constants(capsys):
    from rcon_core.cli.main import main

    with ThreadedServer(recording=ROS2) as server:
        rc = main(["type", "sensor_msgs/msg/Image", "--url", server.url])
        out = capsys.readouterr().out
        assert rc == 0 and "uint8[] data" in out and "MSG: std_msgs/Header" in out
        assert "SLOT_TYPES" not in out and "0x" not in out and "array('B')" not in out
        rc = main(["type", "sensor_msgs/msg/Image", "--url", server.url, "--json"])
        answer = json.loads(capsys.readouterr().out)
        assert rc == 0 and answer["source"] == "server"
        assert all(td["constnames"] == [] for td in answer["typedefs"])
        assert server.ops("call_service", service="/rosapi/message_details") == []


# ------------------------------------------------------------------------------------------ parameters


async def test_parameters_never_touch_rosapis_parameter_calls(client, server):
    """The Parameters panel's calls (``client.params``) go to the nodes' own services: list_parameters,
    get_parameters and set_parameters, answered here in the recorded shapes (rosapi.jsonl:34-35; a missing
    name reads back as type 0).  Nothing reaches get_param_names, get_param, has_param, set_param or
    delete_param, whose 2.1.0 handlers die, hang or lie."""
    store = {"speed_limit": {"type": 3, "double_value": 1.5}, "robot_name": {"type": 4, "string_value": "peer2"}}
    recorded_value = ROSAPI[34]["received"]["values"]["values"][0]  # every typed slot present
    empty = {**recorded_value, "type": 0, "string_value": ""}

    def listing(frame):
        return {"op": "service_response", "id": frame["id"], "service": frame["service"], "result": True,
                "values": {"result": {"names": sorted(store), "prefixes": []}}}

    def get(frame):
        values = [{**empty, **store.get(n, {})} for n in frame["args"]["names"]]
        return {"op": "service_response", "id": frame["id"], "service": frame["service"], "result": True,
                "values": {"values": values}}

    def set_(frame):
        p = frame["args"]["parameters"][0]
        ok = p["name"] in store and (p["value"]["type"] in (0, store[p["name"]]["type"]))
        if ok and p["value"]["type"] == 0:
            del store[p["name"]]
        elif ok:
            store[p["name"]] = p["value"]
        reason = "" if ok else "Wrong parameter type"
        return {"op": "service_response", "id": frame["id"], "service": frame["service"], "result": True,
                "values": {"results": [{"successful": ok, "reason": reason}]}}

    server.services.update({"/peer2_node/list_parameters": listing, "/peer2_node/get_parameters": get,
                            "/peer2_node/set_parameters": set_,
                            "/rosbridge_websocket/list_parameters": lambda f: listing(f) | {"values": {
                                "result": {"names": ["port"], "prefixes": []}}}})
    params = client.params
    groups = await params.by_owner()
    assert groups["/peer2_node"] == ["/peer2_node:robot_name", "/peer2_node:speed_limit"]
    assert groups["/rosapi"] == [f"/rosapi:{n}" for n in sorted(ROSAPI[33]["received"]["values"]["result"]["names"])]
    assert await params.get("/peer2_node:speed_limit") == 1.5
    assert await params.get("/peer2_node:no_such_param", default=None) is None
    assert not await params.has("/peer2_node:no_such_param")
    await params.set("/peer2_node:speed_limit", 2.5)
    assert await params.get("/peer2_node:speed_limit") == 2.5
    from rcon_core.bridge import ParamRejectedError

    with pytest.raises(ParamRejectedError, match="holds float 2.5, so the node refused a string"):
        await params.set("/peer2_node:speed_limit", "fast")
    await params.delete("/peer2_node:robot_name")
    assert "robot_name" not in store
    for dangerous in ("get_param_names", "get_param", "has_param", "set_param", "delete_param"):
        assert server.ops("call_service", service=f"/rosapi/{dangerous}") == [], dangerous
