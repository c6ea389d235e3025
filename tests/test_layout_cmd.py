"""issue 15.7: `rcon layout validate FILE` (problems listed, exit 0/1), the JSON Schema shipped in the
package agrees with what the store writes, and plugins offer example canvases (rcon_canvas_templates)."""

from __future__ import annotations

import json
from importlib.resources import files

import pytest

from rcon_core.bridge.envelope import Envelope
from rcon_core.canvas import Binding, Document, Workspace, WorkspaceStore, export_canvas
from rcon_core.canvas.store import workspace_to_dict
from rcon_core.cli.main import main
from rcon_core.plugins import PluginManager, SpecError, WidgetSpec, hookimpl

pytest.importorskip("rcon_widgets_std")


def run(capsys, *argv):
    rc = main(list(argv))
    out, err = capsys.readouterr()
    return rc, out, err


def workspace() -> Document:
    doc = Document(Workspace.new("Ops"))
    doc.add_widget(doc.current.id, "std.label", Binding("/battery", "sensor_msgs/BatteryState", "subscribe",
                                                        ["percentage"]))
    doc.add_widget(doc.current.id, "std.slider", Binding("/speed_limit", "std_msgs/Float64", "publish", ["data"]),
                   settings={"minimum": 0.0, "maximum": 2.0})
    return doc


def test_a_good_workspace_and_canvas_file_pass(tmp_path, capsys):
    doc = workspace()
    ws_file, canvas_file = tmp_path / "ws.json", tmp_path / "canvas.json"
    WorkspaceStore(ws_file).save(doc.workspace)
    export_canvas(doc.current, canvas_file)
    rc, out, err = run(capsys, "layout", "validate", str(ws_file))
    assert (rc, err) == (0, "") and out.strip() == f"{ws_file}: OK (1 canvas, 2 widgets)"
    rc, out, _ = run(capsys, "layout", "validate", str(canvas_file), "--json")
    assert rc == 0 and json.loads(out)["ok"] is True


def test_every_problem_is_listed_and_exit_is_1(tmp_path, capsys):
    doc = workspace()
    data = workspace_to_dict(doc.workspace)
    label, slider = data["canvases"][0]["widgets"]
    slider["settings"] = {"minimum": "low"}
    label["binding"]["name"] = ""
    data["canvases"][0]["widgets"].append({"id": "w-typo", "kind": "std.lable", "geometry": {"w": 0, "h": 40}})
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(data))
    rc, out, err = run(capsys, "layout", "validate", str(path))
    assert rc == 1 and out == ""
    lines = err.strip().splitlines()
    assert f"{path}: canvas 'Ops', widget {label['id']} (std.label): no topic chosen" in lines
    assert (f"{path}: canvas 'Ops', widget {slider['id']} (std.slider): invalid settings: minimum must be a "
            "number (got 'low')") in lines
    assert any("widget w-typo (std.lable): no installed widget plugin offers this kind" in x for x in lines)
    assert any("widget w-typo (std.lable): geometry: width and height must be more than 0" in x for x in lines)


def test_a_binding_naming_a_robot_the_workspace_lacks_is_a_problem(tmp_path, capsys):
    data = workspace_to_dict(workspace().workspace)
    label, slider = data["canvases"][0]["widgets"]
    label["binding"]["robot"] = "r-9"
    data["robots"].append({"id": "r-2", "name": "Bravo", "url": "ws://10.0.0.6:9090"})
    slider["binding"]["robot"] = "r-2"  # a robot the workspace has: fine
    path = tmp_path / "fleet.json"
    path.write_text(json.dumps(data))
    rc, _out, err = run(capsys, "layout", "validate", str(path))
    assert rc == 1
    assert err.strip().splitlines() == [
        f"{path}: canvas 'Ops', widget {label['id']} (std.label): robot 'r-9' is not in this workspace"]


@pytest.mark.parametrize("content, reason", [
    ("{", "not valid JSON"),
    ('{"format": "something-else", "version": 1}', "not an RCON workspace file"),
    ('{"format": "rcon-workspace", "version": 99}', "written by a newer RCON"),
    ('{"format": "rcon-canvas", "version": 1, "canvas": {"id": 3}}', "invalid canvas"),
])
def test_unreadable_files_are_one_problem(tmp_path, capsys, content, reason):
    path = tmp_path / "layout.json"
    path.write_text(content)
    rc, _, err = run(capsys, "layout", "validate", str(path))
    assert rc == 1 and reason in err and len(err.strip().splitlines()) == 1
    rc, _, err = run(capsys, "layout", "validate", str(tmp_path / "missing.json"))
    assert rc == 1 and err.strip().endswith("missing.json: no such file")


def _schema_keys(schema, name):
    return set(schema["$defs"][name]["properties"])


def test_the_shipped_schema_describes_what_the_store_writes(capsys):
    text = files("rcon_core.canvas").joinpath("layout.schema.json").read_text()
    schema = json.loads(text)
    rc, out, _ = run(capsys, "layout", "schema")
    assert rc == 0 and json.loads(out) == schema
    ws = workspace().workspace
    ws.robots[0].envelope = Envelope(1.0, 0.5)  # written only when set: set here so the schema meets it
    ws.robots[0].recording = "run.mcap"  # likewise
    data = workspace_to_dict(ws)
    canvas = data["canvases"][0]
    widget = canvas["widgets"][0]
    assert _schema_keys(schema, "workspaceFile") == set(data)
    assert _schema_keys(schema, "canvas") == set(canvas)
    assert _schema_keys(schema, "widget") == set(widget)
    assert _schema_keys(schema, "binding") == set(widget["binding"])
    assert _schema_keys(schema, "geometry") == set(widget["geometry"])
    assert _schema_keys(schema, "robot") == set(data["robots"][0])
    assert _schema_keys(schema, "envelope") == set(data["robots"][0]["envelope"])
    assert set(schema["$defs"]["binding"]["properties"]["role"]["enum"]) == {"subscribe", "publish", "call", "serve"}


class Templates:
    def __init__(self, *paths):
        self.paths = paths

    @hookimpl
    def rcon_register_widgets(self, registry):
        registry.add(WidgetSpec(kind=f"t{len(self.paths)}.gauge", title="Gauge", model="x:y"))

    @hookimpl
    def rcon_canvas_templates(self, registry):
        for i, path in enumerate(self.paths):
            registry.add(f"Battery station {i}", path, description="the battery, big")


def test_plugins_offer_templates_and_a_missing_file_withdraws_only_that_template(tmp_path, capsys):
    """issue 25.1: a template file left out of the wheel took the whole plugin (both widgets) with it."""
    doc = workspace()
    export_canvas(doc.current, tmp_path / "station.json")
    pm = PluginManager(environ={})
    pm.register(Templates(tmp_path / "station.json"), name="good")
    pm.register(Templates(tmp_path / "nowhere.json", tmp_path / "station.json"), name="half")
    assert pm.failed == []
    assert pm.has_widget("t1.gauge") and pm.has_widget("t2.gauge")  # the widgets of both still load
    assert [(t.title, t.package) for t in pm.canvas_templates()] == [
        ("Battery station 0", "good"), ("Battery station 1", "half")]
    half = next(i for i in pm.plugins if i.name == "half")
    assert half.status == "loaded"
    assert half.problems == [f"template 'Battery station 0' is not offered: no file at {tmp_path / 'nowhere.json'} "
                             "(is it listed as package data in pyproject.toml?)"]
    assert half.to_dict()["problems"] == half.problems
    from rcon_core.cli.plugin_cmds import _check

    assert _check(pm, pm.type_registry()) == 1  # --check fails on it: a lab's CI sees the packaging slip
    err = capsys.readouterr().err.splitlines()
    assert [line for line in err if "is not offered" in line] == [
        f"rcon plugins: plugin 'half' ({half.value}) failed: {half.problems[0]}"]
    with pytest.raises(SpecError):
        from rcon_core.plugins import TemplateRegistry

        TemplateRegistry("x").add("", tmp_path / "station.json")
