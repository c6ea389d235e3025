"""`rcon match` with definitions from a live server (--url, the sim) and from the local registry."""

import json

import pytest

from rcon_core.cli.main import main


def run(capsys, *argv):
    code = main(list(argv))
    out = capsys.readouterr()
    return code, out.out, out.err


#: a lab's own message: the robot has its package, this machine does not (neither the standard registry nor
#: any installed widget plugin knows it), so only ``--url`` can give its fields
TANK = "lab_msgs/TankLevel"
TANK_MSG = "string tank\nfloat64 level_percent\nbool refilling\n"


def fits(data):
    return {(m["kind"], m["rank"], m["field_path"]) for m in data["matches"]}


def test_match_with_url_fetches_definitions(capsys, sim_thread, sim_url):
    pytest.importorskip("rcon_widgets_std", reason="the matches asserted are the standard widgets'")
    sim_thread.run_sync(lambda: sim_thread.types.registry.add_msg_text(TANK, TANK_MSG))
    code, out, err = run(capsys, "match", TANK, "--json")  # offline: the type is unknown here
    assert code == 0 and f"{TANK} is unknown" in err
    assert all(m["rank"] == "generic" and m["field_path"] == "" for m in json.loads(out)["matches"])
    code, out, err = run(capsys, "match", TANK, "--url", sim_url, "--json")
    assert code == 0, err
    data = json.loads(out)
    assert data["type"] == TANK and data["role"] == "subscribe"
    assert "unknown" not in err  # the robot's definition was fetched: each widget fits a field of it
    assert {("std.slider", "structural", "level_percent"), ("std.switch", "structural", "refilling"),
            ("std.label", "structural", "tank")} <= fits(data)
    assert not any(m["rank"] == "generic" for m in data["matches"])
    code, out, err = run(capsys, "match", "std_srvs/SetBool", "--url", sim_url, "--json")
    assert code == 0, err
    data = json.loads(out)
    assert data["role"] == "call"  # a service defaults to the call role
    assert ("std.switch", "exact", "request.data") in fits(data)


def test_match_unknown_type_on_the_server_is_a_clear_error(capsys, sim_url):
    code, out, err = run(capsys, "match", "nope_msgs/Nothing", "--url", sim_url)
    assert code == 1 and "could not get the definition of nope_msgs/Nothing" in err


def test_match_bad_name_and_unknown_offline(capsys):
    code, _out, err = run(capsys, "match", "not a type")
    assert code == 2 and "not a ROS type name" in err
    code, _out, err = run(capsys, "match", "lab_msgs/Unseen", "--json")
    assert code == 0 and "unknown (give --url to ask the robot)" in err
