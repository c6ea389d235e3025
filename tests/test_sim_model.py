"""The vessel model, the harbour world and the camera renderer, without any networking."""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest

from rcon_core.sim.auth import check_auth, make_mac
from rcon_core.sim.camera import CameraRenderer, encode_jpeg
from rcon_core.sim.encoding import fragments
from rcon_core.sim.params import ParamTree
from rcon_core.sim.vessel import Vessel
from rcon_core.sim.world import Lidar, depth_at, occupancy_grid


def run(vessel: Vessel, seconds: float, command: tuple[float, float] | None = None, dt: float = 0.02) -> list[str]:
    events: list[str] = []
    t = vessel.time_s
    for _ in range(int(seconds / dt)):
        t += dt
        if command is not None:
            vessel.command(*command, now=t)
        events += vessel.step(dt, t)
    return events


def test_surge_follows_the_command_with_a_lag_and_drag() -> None:
    v = Vessel()
    run(v, 0.5, (1.0, 0.0))
    early = v.surge
    run(v, 15.0, (1.0, 0.0))
    assert 0.0 < early < 0.5
    assert 0.85 < v.surge < 1.0  # drag keeps it a bit below the command
    assert v.distance_m > 10.0
    assert math.hypot(v.x, v.y) == pytest.approx(v.distance_m, rel=1e-3)  # straight line


def test_turning_changes_heading_and_watchdog_stops() -> None:
    v = Vessel()
    yaw0 = v.yaw
    run(v, 2.0, (0.5, 0.5))
    assert v.yaw != pytest.approx(yaw0, abs=0.3)
    events = run(v, 1.0)  # no more commands
    assert events.count("watchdog") == 1
    assert v.cmd_surge == 0.0 and v.cmd_yaw_rate == 0.0
    run(v, 20.0)
    assert abs(v.surge) < 0.01 and v.yaw_rate == 0.0


def test_speed_limit_and_hull_limits() -> None:
    v = Vessel()
    v.command(5.0, 9.0, now=0.0)
    assert v.cmd_surge == v.params.max_surge and v.cmd_yaw_rate == v.params.max_yaw_rate
    v.speed_limit = 0.4
    v.command(5.0, 0.0, now=0.0)
    assert v.cmd_surge == 0.4
    v.command(float("nan"), 0.0, now=0.0)
    assert v.cmd_surge == 0.4  # a NaN command is ignored


def test_battery_drains_faster_when_moving_and_charges_docked() -> None:
    idle, busy = Vessel(), Vessel()
    run(idle, 10.0)
    run(busy, 10.0, (2.0, 0.5))
    assert busy.battery_charge < idle.battery_charge < 17.0
    low = Vessel(battery_charge=4.01)
    assert "battery_low" in run(low, 30.0, (2.0, 0.0))
    low.docked = True
    before = low.battery_charge
    run(low, 10.0)
    assert low.battery_charge > before and low.current > 0


def test_docking_drives_home() -> None:
    v = Vessel(x=8.0, y=-3.0)
    v.docking = True
    events = run(v, 60.0)
    assert "docked" in events and v.docked and v.dock_distance < 1.5


def test_lat_lon_round_trip() -> None:
    v = Vessel(x=120.0, y=-45.0)
    lat, lon = v.lat_lon()
    assert 43.0 < lat < 44.0 and -80.0 < lon < -79.0
    assert v.local_from_lat_lon(lat, lon) == pytest.approx((120.0, -45.0), abs=1e-6)


def test_lidar_sees_buoys_and_nothing_beyond_range() -> None:
    lidar = Lidar()
    ranges = lidar.scan(0.0, 0.0, 0.0)
    assert ranges.dtype == np.float32 and ranges.shape == (360,)
    # red-1 sits at (12, 6): about 13 m at atan2(6, 12) = 26.6 degrees
    index = int(round((math.atan2(6, 12) - lidar.angle_min) / lidar.angle_increment))
    assert 12.5 < ranges[index] < 13.5
    assert np.isinf(ranges).any()
    turned = lidar.scan(0.0, 0.0, math.pi / 2)
    assert not np.array_equal(ranges, turned)


def test_map_and_depth() -> None:
    data, width, height = occupancy_grid()
    assert data.dtype == np.int8 and len(data) == width * height
    assert set(np.unique(data)) == {-1, 0, 100}
    assert 0.4 <= depth_at(0.0, 39.0) < depth_at(0.0, -40.0)


def test_camera_renders_and_caches() -> None:
    cam = CameraRenderer("front")
    v = Vessel()
    a = cam.frame(v, stamp=1_700_000_000.0)
    b = cam.frame(v, stamp=1_700_000_000.5)
    assert a.shape == (480, 640, 3) and a.dtype == np.uint8
    assert cam.renders == 1  # same pose: only the overlay was redrawn
    assert not np.array_equal(a, b)  # the clock moved
    v.yaw += 0.5
    c = cam.frame(v, stamp=1_700_000_000.5)
    assert cam.renders == 2 and not np.array_equal(b[:400], c[:400])
    assert encode_jpeg(c)[:2] == b"\xff\xd8"


def test_fragments_total_is_a_float_with_floor_count() -> None:
    import json

    frames = [json.loads(f) for f in fragments("x" * 2474, 100)]
    assert len(frames) == 25 and frames[0]["total"] == pytest.approx(25.74)
    assert [f["num"] for f in frames] == list(range(25)) and {f["id"] for f in frames} == {0}
    exact = [json.loads(f) for f in fragments("y" * 300, 100)]
    assert len(exact) == 3 and exact[0]["total"] == 3.0


def test_param_tree() -> None:
    tree = ParamTree({"/a/b": 1, "/a/c": [1, 2]})
    assert tree.get("/a") == {"b": 1, "c": [1, 2]}
    assert tree.names() == ["/a/b", "/a/c"]
    assert tree.delete("/a/b") and not tree.has("/a/b") and not tree.delete("/nope")


def test_auth_mac() -> None:
    now = 1_800_000_000
    mac = make_mac("k", "c", "d", "r", now, "admin", now + 10)
    frame = {"mac": mac, "client": "c", "dest": "d", "rand": "r", "t": now, "level": "admin", "end": now + 10}
    assert check_auth("k", frame, now=now) is None
    assert check_auth("other", frame, now=now) == "mac does not match"
    assert "5 s away" in (check_auth("k", frame, now=now + 20) or "")
    expired = {**frame, "end": now - 1, "mac": make_mac("k", "c", "d", "r", now, "admin", now - 1)}
    assert "expired" in (check_auth("k", expired, now=now) or "")
    assert check_auth("k", {**frame, "t": "x"}, now=now) == "fields t and end must be times in seconds"


def test_rcon_sim_command_serves_and_stops() -> None:
    code = ("import sys; from rcon_core.cli.main import main; sys.exit(main(['sim', '--port', '0', "
            "'--rate-scale', '0.5']))")
    proc = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    try:
        line = proc.stdout.readline() if proc.stdout else ""
        assert "ROS 1 Kingfisher simulator on ws://127.0.0.1:" in line
        import websockets.sync.client as wsc

        url = line.split(" on ")[1].split()[0]
        with wsc.connect(url) as ws:
            ws.send('{"op": "call_service", "id": "1", "service": "/rosapi/get_time"}')
            assert '"result":true' in ws.recv(timeout=10)
    finally:
        proc.terminate()
        assert proc.wait(timeout=10) == 0


def test_rcon_sim_rejects_bad_options(capsys: pytest.CaptureFixture[str]) -> None:
    from rcon_core.cli.main import main

    assert main(["sim", "--rate-scale", "0"]) == 2
    assert "--rate-scale must be positive" in capsys.readouterr().out
