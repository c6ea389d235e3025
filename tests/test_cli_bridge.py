"""``rcon topics|services|type|echo|pub|call`` through ``rcon_core.cli.main.main`` against the embedded sim."""

from __future__ import annotations

import json

import pytest

from rcon_core.cli.main import main


def run(capsys, *argv):
    rc = main(list(argv))
    out, err = capsys.readouterr()
    return rc, out, err


def test_topics_and_services(sim_url, capsys):
    rc, out, _ = run(capsys, "topics", "--url", sim_url, "--json")
    assert rc == 0
    topics = json.loads(out)
    assert topics["/cmd_vel"] == "geometry_msgs/Twist" and topics["/imu/data"] == "sensor_msgs/Imu"
    rc, out, _ = run(capsys, "topics", "--url", sim_url)
    assert rc == 0 and any(line.split() == ["/odom", "nav_msgs/Odometry"] for line in out.splitlines())
    rc, out, _ = run(capsys, "services", "--url", sim_url, "--json")
    assert rc == 0 and json.loads(out)["/lights/set"] == "std_srvs/SetBool"


def test_type_from_server_and_from_the_standard_registry(sim_url, capsys):
    rc, out, _ = run(capsys, "type", "sensor_msgs/Imu", "--url", sim_url)
    assert rc == 0
    assert "float64[9] orientation_covariance" in out and "MSG: std_msgs/Header" in out
    rc, out, _ = run(capsys, "type", "std_srvs/SetBool", "--url", sim_url, "--json")
    assert rc == 0 and json.loads(out)["source"] == "server"
    # the server is unreachable: the standard definitions answer
    rc, out, _ = run(capsys, "type", "geometry_msgs/Twist", "--url", "ws://127.0.0.1:9")
    assert rc == 0 and "Vector3 linear" in out
    rc, _, err = run(capsys, "type", "nope_msgs/Nope", "--url", "ws://127.0.0.1:9")
    assert rc == 1 and "unknown type nope_msgs/Nope" in err


def test_echo_n_messages(sim_url, capsys):
    rc, out, _ = run(capsys, "echo", "/odom", "-n", "2", "--url", sim_url, "--json")
    assert rc == 0
    msgs = [json.loads(line) for line in out.splitlines()]
    assert len(msgs) == 2 and len(msgs[0]["pose"]["covariance"]) == 36
    rc, out, _ = run(capsys, "echo", "/imu/data", "-n", "1", "--url", sim_url, "--compression", "cbor")
    assert rc == 0 and "orientation_covariance" in out and out.rstrip().endswith("---")


def test_pub_reaches_the_robot(sim_url, sim_thread, capsys):
    rc, _, err = run(capsys, "pub", "/cmd_vel", "geometry_msgs/Twist", "{linear: {x: 0.5}}", "--url", sim_url)
    assert rc == 0, err
    assert any(m["linear"]["x"] == 0.5 for m in sim_thread.published("/cmd_vel"))
    rc, _, err = run(capsys, "pub", "/speed_limit", "std_msgs/Float64", "{data: 2.5}", "--rate", "50", "--count", "3",
                     "--url", sim_url)
    assert rc == 0 and len([m for m in sim_thread.published("/speed_limit") if m["data"] == 2.5]) >= 3


def test_pub_bad_message_is_a_clear_error(sim_url, capsys):
    rc, _, err = run(capsys, "pub", "/cmd_vel", "geometry_msgs/Twist", "{linear: {x: fast}}", "--url", sim_url)
    assert rc == 2 and "linear.x" in err


def test_call_success_and_failure(sim_url, capsys):
    rc, out, _ = run(capsys, "call", "/lights/set", "{data: true}", "--url", sim_url, "--json")
    assert rc == 0 and json.loads(out)["success"] is True
    rc, out, _ = run(capsys, "call", "/rosapi/get_time", "--url", sim_url)
    assert rc == 0 and "secs:" in out
    rc, _, err = run(capsys, "call", "/no/such/service", "--url", sim_url, "--timeout", "3")
    assert rc == 1 and "/no/such/service" in err and "does not exist" in err
    rc, _, err = run(capsys, "call", "/lights/set", "{data: [", "--url", sim_url)
    assert rc == 2 and "not YAML or JSON" in err


def test_unreachable_server(capsys):
    rc, _, err = run(capsys, "topics", "--url", "ws://127.0.0.1:9")
    assert rc == 1 and "cannot connect to ws://127.0.0.1:9" in err


@pytest.mark.recordings
def test_call_against_the_recorded_server(capsys):
    """The exact failure text a real rosbridge sends reaches stderr (scripted server replaying services.jsonl)."""
    from replay_server import ThreadedServer

    with ThreadedServer() as server:
        rc, _, err = run(capsys, "call", "/rec/fails", "{}", "--url", server.url)
        assert rc == 1 and "error processing request: simulated failure" in err
        rc, out, _ = run(capsys, "call", "/rec/set_bool", '{"data": true}', "--url", server.url, "--json")
        assert rc == 0 and json.loads(out) == {"success": True, "message": "motors enabled"}


def test_echo_stops_quietly_when_the_reader_goes_away(sim_url):
    # `rcon echo /battery | head -3`: the pipe closes mid-message; echo must exit 0 with no traceback
    import subprocess
    import sys

    proc = subprocess.Popen(
        [sys.executable, "-m", "rcon_core", "echo", "/battery", "--url", sim_url],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE,
    )
    assert proc.stdout is not None
    first = proc.stdout.readline()
    proc.stdout.close()
    try:
        _, err = proc.communicate(timeout=20)
    finally:
        proc.kill()
    assert first.startswith(b"header:")
    assert proc.returncode == 0, err.decode()
    assert b"Traceback" not in err and b"BrokenPipe" not in err, err.decode()


def _layout(tmp_path, envelope=None, name="boat1", url=""):
    from rcon_core.bridge.envelope import Envelope
    from rcon_core.canvas import Workspace
    from rcon_core.canvas.robots import Robot
    from rcon_core.canvas.store import dumps_workspace

    ws = Workspace.new("Main")
    ws.robots = [Robot("r-1", "first", envelope=Envelope(2.0, 2.0)),
                 Robot("r-2", name, url=url, envelope=envelope)]
    path = tmp_path / "workspace.json"
    path.write_text(dumps_workspace(ws))
    return path


def test_pub_envelope_holds_a_command_to_the_saved_envelope_and_says_so(sim_url, sim_thread, tmp_path, capsys):
    """issue 21.4: ``rcon pub`` honours a saved workspace's envelope when asked: 43099999999.96 is sent as 0.8."""
    from rcon_core.bridge.envelope import Envelope

    path = _layout(tmp_path, Envelope(0.8, 0.3), url=sim_url)
    rc, _, err = run(capsys, "pub", "/cmd_vel", "geometry_msgs/Twist",
                     "{linear: {x: 43099999999.96}, angular: {z: -1}}", "--url", sim_url, "--envelope", str(path))
    assert rc == 0, err
    assert "held to the safety envelope: linear.x 4.31e+10 → 0.8, angular.z -1 → -0.3" in err
    assert "boat1: at most 0.8 m/s and 0.3 rad/s" in err  # the robot whose URL is --url
    got = sim_thread.wait_for_published_sync("/cmd_vel", lambda m: m["angular"]["z"] == -0.3, timeout=10)
    assert got["linear"]["x"] == 0.8
    assert not any(abs(m["linear"]["x"]) > 0.8 for m in sim_thread.published("/cmd_vel"))
    # --robot picks another robot of the file, by name or id
    rc, _, err = run(capsys, "pub", "/cmd_vel", "geometry_msgs/Twist", "{linear: {x: 5}}", "--url", sim_url,
                     "--envelope", str(path), "--robot", "first")
    assert rc == 0 and "linear.x 5 → 2" in err


@pytest.mark.parametrize("extra,problem", [
    (("--robot", "nobody"), "no robot 'nobody' in"),
    (("--robot", "r-2"), "robot 'boat1' in"),  # saved without an envelope: never sent without one
])
def test_pub_envelope_refuses_when_there_is_no_envelope_to_honour(sim_url, sim_thread, tmp_path, capsys, extra, problem):
    path = _layout(tmp_path, None)
    before = len(sim_thread.published("/cmd_vel"))
    rc, _, err = run(capsys, "pub", "/cmd_vel", "geometry_msgs/Twist", "{linear: {x: 5}}", "--url", sim_url,
                     "--envelope", str(path), *extra)
    assert rc == 2 and problem in err
    rc, _, err = run(capsys, "pub", "/cmd_vel", "geometry_msgs/Twist", "{linear: {x: 5}}", "--url", sim_url,
                     "--envelope", str(tmp_path / "missing.json"))
    assert rc == 2 and "cannot read" in err
    assert len(sim_thread.published("/cmd_vel")) == before
