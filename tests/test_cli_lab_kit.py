"""issue 25.7: what cost a lab time on the command line.

- `rcon call /pump/set '{on: true, flow_lpm: 12.5}'` crashed (YAML 1.1 read the key `on` as a boolean);
  keys stay text, and `rcon call` checks the request against the service's type as `rcon pub` does;
- `rcon type ... | head` and `rcon services | head` printed a BrokenPipeError traceback;
- `rcon layout validate` accepted a widget on a type it cannot show, a misspelt type, a wrong field path;
- `rcon echo` on a topic nobody advertises now says to give `--type`;
- `rcon type --recursive` writes nested types out under their fields.
"""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from rcon_core.canvas import Binding, Document, Workspace, WorkspaceStore
from rcon_core.cli.main import main
from rcon_core.msgs.text import parse_text

pytest.importorskip("rcon_widgets_std")


def run(capsys, *argv):
    rc = main(list(argv))
    out, err = capsys.readouterr()
    return rc, out, err


def test_yaml_keys_stay_field_names():
    assert parse_text("{on: true, flow_lpm: 12.5}") == {"on": True, "flow_lpm": 12.5}
    assert parse_text("off: 1\nyes: no\nnull: 2\n1: x") == {"off": 1, "yes": False, "null": 2, "1": "x"}
    assert parse_text("{'on': on}") == {"on": True}  # values are still YAML's
    assert parse_text("a: &x {on: 1}\nb: {<<: *x, off: 2}")["b"] == {"on": 1, "off": 2}  # merges still work


def test_call_a_lab_service_whose_field_is_named_on(threaded_client, sim_url, capsys):
    bt, client = threaded_client
    requests = []

    def set_pump(request):  # the lab's service, provided on the robot's side
        requests.append(request)
        return {"success": True, "message": f"pump at {request['flow_lpm']} l/min"}

    bt.call(lambda: client.node("pump").advertise_service("/pump/set", "lab_srvs/SetPump", set_pump)).result(5)
    rc, out, err = run(capsys, "call", "/pump/set", "{on: true, flow_lpm: 12.5}", "--url", sim_url)
    assert (rc, err) == (0, "")
    assert requests == [{"on": True, "flow_lpm": 12.5}]
    assert out.strip() == "success: true\nmessage: pump at 12.5 l/min"


def test_call_checks_the_request_against_the_type(sim_url, sim_thread, capsys):
    rc, out, err = run(capsys, "call", "/lights/set", "{data: true, on: 1}", "--url", sim_url)
    assert (rc, out) == (2, "")
    assert err.strip() == "rcon: bad request for /lights/set: on: unknown field 'on' (known: data)"
    rc, _, err = run(capsys, "call", "/lights/set", "{data: maybe}", "--url", sim_url)
    assert rc == 2 and err.startswith("rcon: bad request for /lights/set: data: ")
    rc, _, err = run(capsys, "call", "/lights/set", "{data: [", "--url", sim_url)
    assert rc == 2 and err.startswith("rcon: ARGS is not YAML or JSON: not valid YAML or JSON")
    rc, out, err = run(capsys, "call", "/lights/set", "{}", "--url", sim_url)  # missing fields: defaults
    assert rc == 0, err
    assert out.startswith("success: true")


@pytest.mark.parametrize("argv", [["type", "sensor_msgs/Imu", "--recursive", "--url", "ws://127.0.0.1:9"],
                                  ["services"], ["topics"], ["type", "sensor_msgs/NavSatFix"]])
def test_a_reader_that_goes_away_gets_no_traceback(sim_url, argv):
    if "--url" not in argv:
        argv = [*argv, "--url", sim_url]
    proc = subprocess.Popen([sys.executable, "-m", "rcon_core", *argv], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE)
    proc.stdout.close()  # like `| head` that has read its lines: every write fails from now on
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=120) == 0
    assert "Traceback" not in err and "BrokenPipe" not in err, err


def test_type_recursive_writes_nested_fields_out(sim_url, capsys):
    for url in (sim_url, "ws://127.0.0.1:9"):  # the robot's definitions, then (no robot) the local ones
        rc, out, _ = run(capsys, "type", "sensor_msgs/Imu", "--recursive", "--url", url)
        assert rc == 0
        lines = out.splitlines()
        at = lines.index("geometry_msgs/Quaternion orientation")
        # the field type's spelling is the source's: this ROS 1 robot's float64, as local ROS 1 text
        assert lines[at + 1:at + 5] == ["  float64 x", "  float64 y", "  float64 z", "  float64 w"]
        assert all(line.startswith("  ") and not line.startswith("   ") for line in lines[at + 1:at + 5])
        assert "MSG:" not in out
    rc, out, _ = run(capsys, "type", "std_srvs/SetBool", "-r", "--url", "ws://127.0.0.1:9")
    assert (rc, out) == (0, "bool data\n---\nbool success\nstring message\n")
    rc, out, _ = run(capsys, "type", "geometry_msgs/Twist", "--url", "ws://127.0.0.1:9")  # without: as before
    assert rc == 0 and "Vector3 linear" in out and "  float64 x" not in out


def test_echo_on_a_topic_nobody_advertises_suggests_type(sim_url, capsys):
    rc, _, err = run(capsys, "echo", "/nobody/here", "--timeout", "0.5", "--url", sim_url)
    assert rc == 1
    assert err.splitlines() == [
        "rcon: note: /nobody/here is not advertised: give --type pkg/Msg to subscribe before it is",
        "rcon: no message on /nobody/here within 0.5 s (/nobody/here is not advertised: give --type pkg/Msg to "
        "subscribe before it is)"]
    rc, _, err = run(capsys, "echo", "/nobody/here", "--type", "std_msgs/String", "--timeout", "0.5", "--url", sim_url)
    assert rc == 1 and err.strip() == "rcon: no message on /nobody/here within 0.5 s"


def test_layout_validate_checks_type_fit_and_field_paths(tmp_path, capsys):
    doc = Document(Workspace.new("Ops"))
    c = doc.current.id
    good = doc.add_widget(c, "std.label", Binding("/battery", "sensor_msgs/BatteryState", "subscribe", ["percentage"]))
    misspelt = doc.add_widget(c, "std.label", Binding("/fix", "sensor_msgs/NavSatFixx", "subscribe"))
    unfit = doc.add_widget(c, "map.gps", Binding("/name", "std_msgs/String", "subscribe"))
    no_field = doc.add_widget(c, "std.label", Binding("/battery", "sensor_msgs/BatteryState", "subscribe",
                                                      ["percentag"]))
    wrong_field = doc.add_widget(c, "std.slider", Binding("/battery", "sensor_msgs/BatteryState", "publish",
                                                          ["serial_number"]), settings={"minimum": 0.0, "maximum": 1.0})
    srv_field = doc.add_widget(c, "std.button", Binding("/lights/set", "std_srvs/SetBool", "call", ["request.dat"]))
    lab = doc.add_widget(c, "std.label", Binding("/gripper", "lab_msgs/Gripper", "subscribe", ["opening"]))
    path = tmp_path / "ws.json"
    WorkspaceStore(path).save(doc.workspace)
    rc, out, err = run(capsys, "layout", "validate", str(path), "--json")
    assert rc == 1
    problems = json.loads(out)["problems"]

    def about(widget):
        return [p.split(": ", 1)[1] for p in problems if f"widget {widget.id} " in p]

    assert about(good) == [] and about(lab) == []  # a package RCON does not ship cannot be checked here
    assert about(misspelt) == ["unknown message type sensor_msgs/NavSatFixx: sensor_msgs has no such message "
                               "(misspelt?)"]
    assert about(unfit) == ["GPS Map cannot show std_msgs/String (subscribe): `rcon match std_msgs/String --role "
                            "subscribe` lists the widgets that can"]
    [missing] = about(no_field)
    assert missing.startswith("field 'percentag': ")
    [cannot] = about(wrong_field)
    assert cannot.startswith("Slider cannot show field 'serial_number' of sensor_msgs/BatteryState (it can: ")
    [srv] = about(srv_field)
    assert srv.startswith("field 'request.dat': ")
    assert len(problems) == 5


def test_type_json_from_a_ros1_robot_keeps_its_spelling(sim_url, capsys):
    """Found merging the ROS 2 work: the robot's .msg text was read into a ROS 2 registry whenever the quick
    rosapi profile could not tell the ROS (it cannot on rosapi 0.11), so a ROS 1 robot's typedefs came out
    as ``double`` and ``builtin_interfaces/Time``."""
    rc, out, _ = run(capsys, "type", "sensor_msgs/NavSatFix", "--json", "--url", sim_url)
    assert rc == 0
    typedefs = {td["type"]: td for td in json.loads(out)["typedefs"]}
    assert typedefs["sensor_msgs/NavSatFix"]["fieldtypes"][2:5] == ["float64"] * 3
    assert "time" in typedefs["std_msgs/Header"]["fieldtypes"]
