"""``rcon info``: ROS version, distro and capabilities, against the sim in ROS 1 and ROS 2 mode."""

from __future__ import annotations

import json

from rcon_core.cli.main import main
from rcon_core.sim import SimServer


def run(capsys, *argv):
    rc = main(list(argv))
    out, err = capsys.readouterr()
    return rc, out, err


def test_info_on_ros2(capsys):
    with SimServer.in_thread(ros2=True, rate_scale=2.0) as server:
        rc, out, _ = run(capsys, "info", "--url", server.url, "--json")
        rc_text, text, _ = run(capsys, "info", "--url", server.url)
    report = json.loads(out)
    assert rc == 0 and report["ros_version"] == 2 and report["distro"] == "jazzy"
    assert report["learned_from"] == "get_ros_version"
    assert report["action_servers"] == ["/fibonacci", "/navigate_to_fix"]
    assert "cbor-raw as CDR" in report["capabilities"] and report["topics"] > 5
    assert rc_text == 0
    assert "ROS 2 (jazzy)   [from get_ros_version]" in text and "/navigate_to_fix" in text


def test_info_on_ros1(sim_url, capsys):
    rc, out, _ = run(capsys, "info", "--url", sim_url, "--json")
    report = json.loads(out)
    assert rc == 0 and report["ros_version"] == 1 and report["action_servers"] == []
    assert "rosapi/search_param" in report["capabilities"]


def test_info_unreachable(capsys):
    rc, _, err = run(capsys, "info", "--url", "ws://127.0.0.1:9")
    assert rc == 1 and "cannot connect to ws://127.0.0.1:9" in err
