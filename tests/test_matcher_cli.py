"""`rcon match` with definitions from a live server (--url, the sim) and from the local registry."""

import json

from rcon_core.cli.main import main


def run(capsys, *argv):
    code = main(list(argv))
    out = capsys.readouterr()
    return code, out.out, out.err


def test_match_with_url_fetches_definitions(capsys, sim_url):
    code, out, err = run(capsys, "match", "sensor_msgs/BatteryState", "--url", sim_url, "--json")
    assert code == 0, err
    data = json.loads(out)
    assert data["type"] == "sensor_msgs/BatteryState" and data["role"] == "subscribe"
    assert isinstance(data["matches"], list)
    code, out, err = run(capsys, "match", "std_srvs/SetBool", "--url", sim_url, "--json")
    assert code == 0, err
    assert json.loads(out)["role"] == "call"  # a service defaults to the call role


def test_match_unknown_type_on_the_server_is_a_clear_error(capsys, sim_url):
    code, out, err = run(capsys, "match", "nope_msgs/Nothing", "--url", sim_url)
    assert code == 1 and "could not get the definition of nope_msgs/Nothing" in err


def test_match_bad_name_and_unknown_offline(capsys):
    code, _out, err = run(capsys, "match", "not a type")
    assert code == 2 and "not a ROS type name" in err
    code, _out, err = run(capsys, "match", "lab_msgs/Unseen", "--json")
    assert code == 0 and "unknown (give --url to ask the robot)" in err
