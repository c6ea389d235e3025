"""The client finds out which ROS it talks to, and reads/writes parameters the way that ROS names them."""

from __future__ import annotations

from collections.abc import AsyncIterator

import pytest
import pytest_asyncio

from rcon_core.bridge import BridgeClient, ParamNotFoundError, ParamRejectedError
from rcon_core.bridge.params import parse_like, split
from rcon_core.sim import SimServer
from rcon_core.testing import connected


@pytest_asyncio.fixture
async def client2(sim_ros2: SimServer) -> AsyncIterator[BridgeClient]:
    async with connected(sim_ros2.url, call_timeout=3) as c:
        yield c


@pytest_asyncio.fixture
async def client1(sim: SimServer) -> AsyncIterator[BridgeClient]:
    async with connected(sim.url, call_timeout=3) as c:
        yield c


async def test_detects_ros2_and_its_distro(client2: BridgeClient) -> None:
    assert client2.ros_version is None  # nothing asked yet
    info = await client2.detect_ros()
    assert (info.version, info.distro, info.source) == (2, "jazzy", "get_ros_version")
    assert client2.ros_version == 2 and info.ros2
    assert "/rosapi/get_ros_version" in info.rosapi_services
    assert "rosapi/action_servers" in info.capabilities and "cbor-raw as CDR" in info.capabilities


async def test_detects_ros1_from_what_the_answers_look_like(client1: BridgeClient) -> None:
    info = await client1.detect_ros()
    assert info.version == 1 and info.source == "rosapi service types (rosapi)"
    assert "rosapi/search_param" in info.capabilities and "cbor-raw as ROS 1 serialization" in info.capabilities


async def test_ros2_parameters_by_node(sim_ros2: SimServer, client2: BridgeClient) -> None:
    params = client2.params
    groups = await params.by_owner()
    assert "/kingfisher:max_speed" in groups["/kingfisher"] and "/rosbridge_websocket" in groups
    assert await params.get("/kingfisher:max_speed") == 2.0
    assert await params.get("/kingfisher:gps.origin_lat") == sim_ros2.robot.origin_lat
    await params.set("/kingfisher:max_speed", 3.25)
    assert await params.get("/kingfisher:max_speed") == 3.25
    with pytest.raises(ParamRejectedError, match="holds float 3.25, so the node refused a int"):
        await params.set("/kingfisher:max_speed", 4)
    with pytest.raises(ParamRejectedError, match="not declared"):
        await params.set("/kingfisher:invented", 1)
    with pytest.raises(ParamNotFoundError):
        await params.get("/kingfisher:invented")
    assert await params.get("/kingfisher:invented", default=7) == 7
    await params.set("/kingfisher:frame_id", "")  # an empty string is a value, not "missing"
    assert await params.get("/kingfisher:frame_id") == ""
    assert await params.has("/kingfisher:frame_id") and not await params.has("/nobody:x")
    await params.delete("/kingfisher:frame_id")
    assert not await params.has("/kingfisher:frame_id")
    with pytest.raises(ValueError, match="<node>:<param>"):
        await params.get("max_speed")


async def test_ros1_parameters_keep_their_shape(client1: BridgeClient) -> None:
    params = client1.params
    assert await params.get("/kingfisher/max_speed") == 2.0
    await params.set("/kingfisher/max_speed", 3)
    assert await params.get("/kingfisher/max_speed") == 3
    groups = await params.by_owner()
    assert "/kingfisher/max_speed" in groups["/kingfisher"] and "/kingfisher/gps/origin_lat" in groups["/kingfisher/gps"]
    with pytest.raises(ParamNotFoundError):
        await params.get("/kingfisher/nothing")


def test_editing_helpers() -> None:
    assert split("/kingfisher:gps.origin_lat", True) == ("/kingfisher", "gps.origin_lat")
    assert split("kingfisher:x", True) == ("/kingfisher", "x")
    assert split("/kingfisher/gps/origin_lat", False) == ("/kingfisher/gps", "origin_lat")
    assert parse_like("3", 2.0) == 3.0 and isinstance(parse_like("3", 2.0), float)
    assert parse_like("true", False) is True and parse_like("hello world", "x") == "hello world"
    assert parse_like("[1, 2]", [0.5]) == [1.0, 2.0]
    for text, current in (("yes please", 1), ("1.5", 2), ("[a]", [1]), ("3", True)):
        with pytest.raises(ValueError, match="expected"):
            parse_like(text, current)
    # issue 21.12: 1e5 was refused as "got a string"; 1.0e+400 became .inf without a word
    assert parse_like("1e5", 2.0) == 100000.0 and parse_like("-2.5E-3", 2.0) == -0.0025
    with pytest.raises(ValueError, match=r"1.0e\+400 is too large for a number \(it would become infinity\)"):
        parse_like("1.0e+400", 2.0)
    with pytest.raises(ValueError, match="nothing typed"):
        parse_like("  ", 2.0)
