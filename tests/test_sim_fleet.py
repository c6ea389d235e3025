"""Named sims (one vessel of a fleet): topic namespace, node names, start positions, camera scenes.

Raw ``websockets`` clients and our BridgeClient against real SimServers on free loopback ports.
"""

from __future__ import annotations

import asyncio
import json
import math
import subprocess
import sys
from collections.abc import AsyncIterator
from typing import Any

import numpy as np
import pytest
import pytest_asyncio
import websockets

from rcon_core.bridge import BridgeClient
from rcon_core.msgs.values import as_bytes
from rcon_core.sim import SimServer
from rcon_core.sim.identity import Identity, index_of
from rcon_core.testing import until

ROBOT_TOPICS = ["/odom", "/gps/fix", "/imu/data", "/imu/mag", "/camera/front/image_raw",
                "/camera/rear/image_raw/compressed", "/scan", "/battery", "/depth", "/lights/state", "/cmd_vel",
                "/speed_limit"]
GLOBAL_TOPICS = ["/rosout", "/rosout_agg", "/client_count", "/map"]


@pytest_asyncio.fixture
async def boat2() -> AsyncIterator[SimServer]:
    async with SimServer(name="boat2", rate_scale=2.0) as server:
        yield server


@pytest_asyncio.fixture
async def fleet() -> AsyncIterator[list[SimServer]]:
    """The unnamed sim, boat1 and boat2, each on its own free port."""
    servers = [SimServer(rate_scale=2.0), SimServer(name="boat1", rate_scale=2.0),
               SimServer(name="boat2", rate_scale=2.0)]
    for s in servers:
        await s.start()
    try:
        yield servers
    finally:
        for s in servers:
            await s.stop()


async def recv_until(ws: Any, pred: Any, timeout: float = 5.0) -> dict[str, Any]:
    async def loop() -> dict[str, Any]:
        while True:
            raw = await ws.recv()
            if isinstance(raw, bytes):
                continue
            msg = json.loads(raw)
            if pred(msg):
                return msg

    return await asyncio.wait_for(loop(), timeout)


async def call(ws: Any, service: str, args: Any = None, call_id: str = "c") -> dict[str, Any]:
    await ws.send(json.dumps({"op": "call_service", "id": call_id, "service": service, "args": args or {}}))
    return await recv_until(ws, lambda m: m.get("op") == "service_response" and m.get("id") == call_id)


def test_identity_names_and_indexes() -> None:
    assert index_of(None) == 0 and index_of("boat2") == 2 and index_of("boat17") == 17
    assert index_of("alpha") == index_of("alpha") and 1 <= index_of("alpha") <= 97
    unnamed = Identity.of()
    assert (unnamed.namespace, unnamed.node, unnamed.topic("/cmd_vel")) == ("", "/kingfisher", "/cmd_vel")
    assert unnamed.hull is None
    two = Identity.of("boat2")
    assert (two.namespace, two.node, two.topic("/gps/fix")) == ("/boat2", "/boat2/kingfisher", "/boat2/gps/fix")
    for bad in ("", "2boat", "boat/2", "boat 2", "/boat2"):
        with pytest.raises(ValueError, match="must start with a letter"):
            Identity.of(bad)
    with pytest.raises(ValueError, match="non-negative"):
        Identity.of("boat", -1)


def test_start_positions_are_a_few_hundred_metres_apart() -> None:
    origins = [Identity.of(None if i == 0 else f"boat{i}").origin for i in range(7)]
    for i, a in enumerate(origins):
        for b in origins[i + 1:]:
            north = math.radians(b[0] - a[0]) * 6_378_137.0
            east = math.radians(b[1] - a[1]) * 6_378_137.0 * math.cos(math.radians(a[0]))
            assert 150.0 < math.hypot(north, east) < 2000.0


async def test_named_sim_lists_its_topics_services_nodes_and_rosout_under_its_namespace(boat2: SimServer) -> None:
    async with websockets.connect(boat2.url, max_size=None) as ws:
        topics = (await call(ws, "/rosapi/topics", call_id="t"))["values"]["topics"]
        for t in ROBOT_TOPICS:
            assert f"/boat2{t}" in topics and t not in topics
        for t in GLOBAL_TOPICS:
            assert t in topics
        services = (await call(ws, "/rosapi/services", call_id="s"))["values"]["services"]
        for s in ("/dock", "/lights/set", "/reset_pose", "/kingfisher/get_loggers"):
            assert f"/boat2{s}" in services and s not in services
        assert "/rosapi/topics" in services and "/rosout/get_loggers" in services
        nodes = (await call(ws, "/rosapi/nodes", call_id="n"))["values"]["nodes"]
        assert "/boat2/kingfisher" in nodes and "/kingfisher" not in nodes
        pubs = (await call(ws, "/rosapi/publishers", {"topic": "/boat2/gps/fix"}, "p"))["values"]["publishers"]
        assert pubs == ["/boat2/kingfisher"]
        # the robot's latched start-up line on /rosout names the namespaced node and command topic
        await ws.send(json.dumps({"op": "subscribe", "topic": "/rosout"}))
        line = await recv_until(ws, lambda m: m.get("op") == "publish"
                                and m["msg"]["name"] == "/boat2/kingfisher")
        assert "/boat2/cmd_vel" in line["msg"]["msg"]
        # a command on the namespaced topic drives the vessel; the root /cmd_vel is not the robot's
        await ws.send(json.dumps({"op": "advertise", "topic": "/boat2/cmd_vel", "type": "geometry_msgs/Twist"}))
        await ws.send(json.dumps({"op": "publish", "topic": "/boat2/cmd_vel",
                                  "msg": {"linear": {"x": 0.7}, "angular": {"z": 0.0}}}))
        await boat2.wait_for_published("/boat2/cmd_vel")
        await until(lambda: boat2.robot.cmd_surge)
        assert boat2.robot.cmd_surge == pytest.approx(0.7)
        ok = await call(ws, "/boat2/lights/set", {"data": True}, "l")
        assert ok["result"] is True and boat2.robot.lights is True
        missing = await call(ws, "/lights/set", {"data": False}, "m")
        assert missing["result"] is False and "does not exist" in missing["values"]
        assert boat2.robot.lights is True


async def test_unnamed_sim_keeps_its_root_topics(fleet: list[SimServer]) -> None:
    unnamed = fleet[0]
    assert unnamed.name is None and unnamed.topic("/cmd_vel") == "/cmd_vel"
    for t in ROBOT_TOPICS:
        assert t in unnamed.topics
    assert "/kingfisher/get_loggers" in unnamed.services and "/dock" in unnamed.services
    assert unnamed.robot.origin_lat == 43.6385 and unnamed.robot.origin_lon == -79.3790


async def test_each_vessel_has_its_own_fix_and_camera_scene_through_our_client(fleet: list[SimServer]) -> None:
    fixes: dict[str, dict[str, Any]] = {}
    frames: dict[str, dict[str, Any]] = {}
    clients = []
    try:
        for sim in fleet:
            key = sim.name or "unnamed"
            c = BridgeClient(sim.url, call_timeout=5)
            await c.connect(timeout=5)
            clients.append(c)
            topics = await c.rosapi.topics()
            assert sim.topic("/camera/front/image_raw") in topics
            node = c.node("test")
            node.subscribe(sim.topic("/gps/fix"), lambda m, k=key: fixes.setdefault(k, m))
            node.subscribe(sim.topic("/camera/front/image_raw"), lambda m, k=key: frames.setdefault(k, m))
        await until(lambda: len(fixes) == 3 and len(frames) == 3)
        assert set(fixes) == set(frames) == {"unnamed", "boat1", "boat2"}
        positions = [(f["latitude"], f["longitude"]) for f in fixes.values()]
        for i, a in enumerate(positions):
            for b in positions[i + 1:]:
                assert math.hypot(a[0] - b[0], a[1] - b[1]) > 1e-3  # about 100 m or more
        images = {k: np.frombuffer(as_bytes(m["data"]), np.uint8).reshape(m["height"], m["width"], 3)
                  for k, m in frames.items()}
        skies = {k: tuple(int(c) for c in img[2, 2]) for k, img in images.items()}
        assert len(set(skies.values())) == 3  # a visibly different sky per vessel
        assert skies["unnamed"] == (120, 170, 225)  # the unnamed sim looks as it always did
        for sim in fleet[1:]:
            hull = sim.identity.hull
            bow = images[sim.name][470, 320 - 60]  # left of the painted name, inside the bow
            assert tuple(int(c) for c in bow) == hull
        assert tuple(int(c) for c in images["unnamed"][470, 260]) != fleet[1].identity.hull
    finally:
        for c in clients:
            await c.close()


async def test_named_ros2_sim_serves_its_action_under_the_namespace() -> None:
    async with SimServer(name="boat3", ros2=True, rate_scale=4.0) as sim:
        c = BridgeClient(sim.url, call_timeout=3)
        await c.connect(timeout=5)
        try:
            servers = await c.rosapi.action_servers()
            # the vessel's own action moves under its namespace; the tutorial's /fibonacci is not the vessel's
            assert "/boat3/navigate_to_fix" in servers and "/navigate_to_fix" not in servers
            assert "/fibonacci" in servers
            r = sim.robot
            lat = r.origin_lat + math.degrees((r.y + 2.5 * math.sin(r.yaw)) / 6_378_137.0)
            lon = r.origin_lon + math.degrees((r.x + 2.5 * math.cos(r.yaw))
                                              / (6_378_137.0 * math.cos(math.radians(r.origin_lat))))
            goal = c.node("nav").send_action_goal("/boat3/navigate_to_fix", "rcon_sim/action/NavigateToFix",
                                                  {"target": {"latitude": lat, "longitude": lon}}, timeout=30)
            result = await goal.result(timeout=30)
            assert result["success"] is True
        finally:
            await c.close()


def test_rcon_sim_name_option() -> None:
    code = ("import sys; from rcon_core.cli.main import main; sys.exit(main(['sim', '--port', '0', "
            "'--name', 'boat4']))")
    proc = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    try:
        line = proc.stdout.readline() if proc.stdout else ""
        assert "Kingfisher 'boat4' (topics under /boat4) simulator on ws://127.0.0.1:" in line
        import websockets.sync.client as wsc

        url = line.split(" on ")[1].split()[0]
        with wsc.connect(url) as ws:
            ws.send('{"op": "call_service", "id": "1", "service": "/rosapi/nodes"}')
            assert "/boat4/kingfisher" in ws.recv(timeout=10)
    finally:
        proc.terminate()
        assert proc.wait(timeout=10) == 0


async def test_a_named_sim_without_namespace_keeps_the_plain_names() -> None:
    async with SimServer(name="boat5", namespace=False, rate_scale=2.0) as sim:
        assert sim.topic("/cmd_vel") == "/cmd_vel" and sim.identity.namespace == ""
        for t in ROBOT_TOPICS:
            assert t in sim.topics and f"/boat5{t}" not in sim.topics
        assert "/dock" in sim.services and "/kingfisher/get_loggers" in sim.services
        # still its own vessel: its own start position and camera scene
        assert (sim.robot.origin_lat, sim.robot.origin_lon) == Identity.of("boat5").origin
        assert sim.identity.sky == Identity.of("boat5").sky != Identity.of().sky


def test_rcon_sim_refuses_a_bad_name(capsys: pytest.CaptureFixture[str]) -> None:
    from rcon_core.cli.main import main

    assert main(["sim", "--name", "boat/2"]) == 2
    assert "--name" in capsys.readouterr().err
    assert main(["sim", "--no-namespace"]) == 2
    assert "--no-namespace goes with --name" in capsys.readouterr().err
