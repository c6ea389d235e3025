"""``rcon topics|services|echo|pub|call|info`` against the foxglove-sdk peer (``rcon_core/foxglove/testing.py``): the
protocol is detected from the URL (or forced with ``--protocol``), and each command does what it does on a
rosbridge robot."""

from __future__ import annotations

import json
import threading

import pytest

from rcon_core.cli.main import main
from rcon_core.foxglove.testing import FoxPeer
from rcon_core.msgs import TypeRegistry

pytestmark = pytest.mark.usefixtures("transport")  # every test runs on each WebSocket transport

REG = TypeRegistry.standard(ros2=True)


def run(capsys, *argv):
    rc = main(list(argv))
    out, err = capsys.readouterr()
    return rc, out, err


@pytest.fixture
def peer():
    p = FoxPeer()
    stop = threading.Event()

    def talk() -> None:
        n = 0
        while not stop.wait(0.05):
            n += 1
            p.say(f"hello {n}")
            p.log_pose(float(n))

    t = threading.Thread(target=talk, daemon=True)
    t.start()
    yield p
    stop.set()
    t.join()
    p.stop()


def test_topics_and_services_with_their_types(peer, capsys):
    rc, out, err = run(capsys, "topics", "--url", peer.url, "--json")
    assert rc == 0, err
    topics = json.loads(out)
    assert topics["/pose"] == "geometry_msgs/msg/Pose" and topics["/camera/compressed"] == "foxglove.CompressedImage"
    rc, out, err = run(capsys, "services", "--url", peer.url, "--json", "--protocol", "foxglove")
    assert rc == 0, err
    assert json.loads(out)["/reset"] == "std_srvs/srv/Trigger"


def test_echo_decodes_cdr_and_json(peer, capsys):
    rc, out, err = run(capsys, "echo", "/pose", "-n", "2", "--url", peer.url, "--json")
    assert rc == 0, err
    poses = [json.loads(line) for line in out.splitlines()]
    assert len(poses) == 2 and poses[0]["position"]["y"] == 2.0
    rc, out, err = run(capsys, "echo", "/chatter", "-n", "1", "--url", peer.url)
    assert rc == 0, err
    assert out.startswith("data: hello")


def test_pub_reaches_the_robot_as_cdr(peer, capsys):
    rc, _, err = run(capsys, "pub", "/cmd_vel", "geometry_msgs/msg/Twist", "{linear: {x: 0.5}}", "--url", peer.url)
    assert rc == 0, err
    topic, encoding, data = peer.received[0]
    assert (topic, encoding) == ("/cmd_vel", "cdr")
    assert REG.deserialize_cdr("geometry_msgs/msg/Twist", data)["linear"]["x"] == 0.5


def test_call_a_cdr_service_and_a_json_one(peer, capsys):
    rc, out, err = run(capsys, "call", "/reset", "--url", peer.url, "--json")
    assert rc == 0, err
    assert json.loads(out) == {"success": True, "message": "reset done"}
    rc, out, err = run(capsys, "call", "/add", "{a: 2, b: 40}", "--url", peer.url, "--json")
    assert rc == 0, err
    assert json.loads(out) == {"sum": 42}
    rc, out, err = run(capsys, "call", "/fail", "{a: 1, b: 1}", "--url", peer.url)
    assert rc == 1 and "the pump is jammed" in err


def test_info_says_which_protocol_server_and_what_it_cannot_do(peer, capsys):
    rc, out, err = run(capsys, "info", "--url", peer.url)
    assert rc == 0, err
    assert "Foxglove WebSocket (foxglove.sdk.v1), server fox-peer" in out
    assert "encodings     cdr, json" in out and "clientPublish" in out
    assert "has no actions" in out
    rc, out, err = run(capsys, "info", "--url", peer.url, "--json")
    report = json.loads(out)
    assert report["protocol"] == "foxglove" and report["ros_version"] == 2 and report["topics"] == 5


def test_forcing_the_wrong_protocol_is_said_in_words(peer, sim_url, capsys):
    rc, _, err = run(capsys, "topics", "--url", sim_url, "--protocol", "foxglove")
    assert rc == 1 and "not a Foxglove server" in err
    rc, out, err = run(capsys, "info", "--url", sim_url)
    assert rc == 0 and "protocol      rosbridge v2" in out
