"""The robot's part of "a stale command is dropped" (issue 22, item 19): after a silent stall the one command
already in flight still arrives the stall's length late (TCP cannot unsend it). The sim takes
``TwistStamped`` on ``/cmd_vel_stamped``, drops one older than ``cmd_max_age`` and runs its watchdog from
the stamp."""

from __future__ import annotations

import json
import time
from typing import Any

import pytest
import websockets

from rcon_core.sim import SimServer
from rcon_core.sim.commands import LOG_EVERY_S, StampedCommands, stamp_seconds
from rcon_core.testing import until


def stamped(t: float, x: float, ros2: bool = False) -> dict[str, Any]:
    secs, nsecs = int(t), int(round((t % 1) * 1e9))
    stamp = {"sec": secs, "nanosec": nsecs} if ros2 else {"secs": secs, "nsecs": nsecs}
    return {"header": {"stamp": stamp, "frame_id": "base_link"},
            "twist": {"linear": {"x": x, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.2}}}


async def publish(ws: Any, msg: dict[str, Any], ros2: bool = False) -> None:
    kind = "geometry_msgs/msg/TwistStamped" if ros2 else "geometry_msgs/TwistStamped"
    await ws.send(json.dumps({"op": "advertise", "topic": "/cmd_vel_stamped", "type": kind}))
    await ws.send(json.dumps({"op": "publish", "topic": "/cmd_vel_stamped", "msg": msg}))


async def test_a_command_the_stalls_length_late_is_dropped_a_fresh_one_drives(sim: SimServer) -> None:
    """A command stamped 5 s ago (a 5 s stall, as in the probe) is not acted on, and /rosout says so."""
    node = sim.robot_node
    async with websockets.connect(sim.url) as ws:
        await ws.send(json.dumps({"op": "subscribe", "topic": "/rosout"}))
        await publish(ws, stamped(time.time() - 5.0, 1.0))
        await until(lambda: node.stamped.dropped_stale == 1, what="the late command dropped")
        assert sim.robot.cmd_surge == 0.0 and sim.robot.watchdog_tripped
        while True:
            line = json.loads(await ws.recv())
            if line.get("topic") == "/rosout" and "Dropped" in line["msg"]["msg"]:
                break
        assert "5." in line["msg"]["msg"] and "cmd_max_age" in line["msg"]["msg"]
        await publish(ws, stamped(time.time(), 1.0))
        await until(lambda: node.stamped.taken == 1, what="the fresh command taken")
    assert sim.robot.cmd_surge == pytest.approx(1.0) and sim.robot.cmd_yaw_rate == pytest.approx(0.2)


async def test_the_watchdog_runs_from_the_stamp(sim: SimServer) -> None:
    """A command 0.3 s old when it arrives drives only for what is left of the 0.5 s watchdog."""
    async with websockets.connect(sim.url) as ws:
        await publish(ws, stamped(time.time() - 0.3, 1.0))
        await until(lambda: sim.robot_node.stamped.taken == 1, what="the command taken")
        assert sim.robot.last_cmd_time <= time.monotonic() - 0.29
        await until(lambda: sim.robot.watchdog_tripped, what="the watchdog")


async def test_the_limit_is_the_robots_parameter_and_ros2_stamps_work(sim_ros2: SimServer) -> None:
    """With ``cmd_max_age`` raised to 10 s a 5 s old command is taken, and the watchdog, run from its stamp,
    stops it at once: older than the watchdog, a command never drives."""
    sim_ros2.params_tree.set("/kingfisher/cmd_max_age", 10.0)
    async with websockets.connect(sim_ros2.url) as ws:
        await publish(ws, stamped(time.time() - 5.0, 0.5, ros2=True), ros2=True)
        await until(lambda: sim_ros2.robot_node.stamped.taken == 1, what="the command taken")
    assert sim_ros2.robot_node.stamped.dropped_stale == 0
    assert sim_ros2.robot.last_cmd_time <= time.monotonic() - 4.9
    await until(lambda: sim_ros2.robot.watchdog_tripped and sim_ros2.robot.cmd_surge == 0.0, what="the watchdog")


async def test_the_stamped_topic_is_listed_with_its_type(sim: SimServer) -> None:
    async with websockets.connect(sim.url) as ws:
        await ws.send(json.dumps({"op": "call_service", "service": "/rosapi/topic_type", "id": "t",
                                  "args": {"topic": "/cmd_vel_stamped"}}))
        reply = json.loads(await ws.recv())
    assert reply["values"]["type"] == "geometry_msgs/TwistStamped"


def test_stamps_of_both_flavours_and_what_is_not_one() -> None:
    assert stamp_seconds({"stamp": {"secs": 3, "nsecs": 500_000_000}}) == 3.5
    assert stamp_seconds({"stamp": {"sec": 3, "nanosec": 250_000_000}}) == 3.25
    assert stamp_seconds({}) is None and stamp_seconds(None) is None
    assert stamp_seconds({"stamp": {"secs": "x"}}) is None


def test_future_zero_and_missing_stamps_are_dropped_and_the_log_is_rate_limited() -> None:
    wall, mono = [1000.0], [50.0]
    said: list[str] = []
    cmds = StampedCommands(0.5, said.append, wall=lambda: wall[0], mono=lambda: mono[0])
    assert cmds.judge({"header": {"stamp": {"secs": 1002, "nsecs": 0}}}, "/c") is None  # 2 s ahead
    assert "not in sync" in said[-1] and cmds.dropped_future == 1
    assert cmds.judge({"header": {"stamp": {"secs": 0, "nsecs": 0}}}, "/c") is None
    assert cmds.judge({"twist": {}}, "/c") is None
    assert cmds.dropped_stale == 2 and len(said) == 1  # within LOG_EVERY_S: not said again
    mono[0] += LOG_EVERY_S
    assert cmds.judge({}, "/c") is None and "no stamp" in said[-1]
    made = cmds.judge({"header": {"stamp": {"secs": 999, "nsecs": 800_000_000}}}, "/c")
    assert made == pytest.approx(mono[0] - 0.2) and cmds.taken == 1
