"""issue 11.12 and 15.3 on the command line: one-line errors, non-zero exits and --timeout instead of a
traceback, a false success or waiting for ever."""

from __future__ import annotations

import json

import pytest
from replay_server import ThreadedServer

from rcon_core.cli.main import main


def run(capsys, *argv):
    rc = main(list(argv))
    out, err = capsys.readouterr()
    return rc, out, err


@pytest.mark.parametrize("argv", [("--url", "notaurl", "topics"), ("topics", "--url", "notaurl"),
                                  ("echo", "/x", "--url", "http://robot:9090")])
def test_a_bad_url_is_one_line_not_a_traceback(capsys, argv):
    rc, _, err = run(capsys, *argv)
    assert rc == 2
    assert err.startswith("rcon: --url must be a ws:// or wss:// URL, got ")
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err


def test_a_bad_timeout_is_refused(capsys):
    rc, _, err = run(capsys, "echo", "/odom", "--timeout", "0", "--url", "ws://127.0.0.1:9")
    assert rc == 2 and "--timeout must be a positive number of seconds" in err


def test_pub_of_a_type_the_robot_lacks_exits_1_with_the_sentence(sim_url, capsys):
    rc, _, err = run(capsys, "pub", "/x", "no_such/Type", "{}", "--url", sim_url)
    assert rc == 1
    assert err.strip() == "rcon: the robot does not know no_such/Type (is its package installed there?)"


def test_echo_of_a_type_the_robot_lacks_exits_1_with_the_sentence(sim_url, capsys):
    rc, _, err = run(capsys, "echo", "/winch", "--type", "lab_msgs/Winch", "--url", sim_url)
    assert rc == 1
    assert err.strip() == "rcon: the robot does not know lab_msgs/Winch (is its package installed there?)"


def test_pub_of_a_standard_type_still_succeeds(sim_url, capsys):
    rc, _, err = run(capsys, "pub", "/speed_limit", "std_msgs/Float64", "{data: 1.5}", "--url", sim_url)
    assert rc == 0, err


def test_echo_timeout_on_a_silent_topic(sim_url, capsys):
    rc, out, err = run(capsys, "echo", "/nobody_publishes", "--type", "std_msgs/Float64", "--timeout", "0.5",
                       "--url", sim_url)
    assert rc == 1 and out == ""
    assert err.strip() == "rcon: no message on /nobody_publishes within 0.5 s"


def test_echo_timeout_does_not_cut_a_live_topic(sim_url, capsys):
    rc, out, err = run(capsys, "echo", "/odom", "-n", "2", "--timeout", "10", "--json", "--url", sim_url)
    assert rc == 0, err
    assert len([json.loads(line) for line in out.splitlines()]) == 2


def test_echo_hears_a_status_refusal():
    def refuse(frame):
        return [json.dumps({"op": "status", "level": "error", "id": frame["id"],
                            "msg": "Subscribing to /secret is not allowed"})]

    with ThreadedServer(replay=False) as server:
        server.on_subscribe = refuse
        import subprocess
        import sys

        proc = subprocess.run([sys.executable, "-m", "rcon_core", "echo", "/secret", "--type", "std_msgs/Float64",
                               "--url", server.url], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 1
    assert proc.stderr.strip() == "rcon: the robot refused /secret: Subscribing to /secret is not allowed"


def test_listing_times_out_when_the_robot_does_not_answer(capsys):
    with ThreadedServer(replay=False) as server:  # accepts the connection, never answers rosapi
        rc, _, err = run(capsys, "topics", "--timeout", "0.5", "--url", server.url)
    assert rc == 1
    assert err.strip() == f"rcon: no answer from {server.url} within 0.5 s"
