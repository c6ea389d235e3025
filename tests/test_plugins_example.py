"""The example external plugin (tests/example_plugin), pip-installed into a temp dir and found only
through entry-point discovery: by the manager, `rcon plugins`, `rcon match` and on a canvas."""

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

EXAMPLE = Path(__file__).parent / "example_plugin"


@pytest.fixture(scope="module")
def lab_path(tmp_path_factory):
    target = tmp_path_factory.mktemp("site")
    proc = subprocess.run(
        [sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--no-input", "--target", str(target),
         str(EXAMPLE)],
        capture_output=True, text=True, timeout=300,
    )
    assert proc.returncode == 0, f"pip install of the example plugin failed:\n{proc.stderr}"
    assert list(target.glob("rcon_example_lab-0.3.1.dist-info/entry_points.txt"))
    return target


def run(lab_path, *args, code=None, env_extra=None, timeout=120):
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(lab_path), os.environ.get("PYTHONPATH", "")]))
    env.update(env_extra or {})
    cmd = [sys.executable, "-c", textwrap.dedent(code)] if code else [sys.executable, "-m", "rcon_core", *args]
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=timeout)
    assert proc.returncode == 0, proc.stderr
    return proc.stdout


def test_discovered_with_dist_name_and_version(lab_path):
    out = run(lab_path, code="""
        import json
        from rcon_core.plugins import PluginManager
        pm = PluginManager(); pm.load_entry_points()
        info = next(i for i in pm.plugins if i.name == "lab")
        spec = pm.widget("lab.gripper")
        print(json.dumps([info.status, info.dist, info.version, spec.package, spec.title,
                          [d.name for d in info.types]]))
    """)
    assert json.loads(out) == ["loaded", "rcon-example-lab", "0.3.1", "rcon-example-lab", "Gripper",
                               ["lab_msgs/Gripper"]]


def test_rcon_plugins_lists_it(lab_path):
    data = json.loads(run(lab_path, "plugins", "--json"))
    lab = next(p for p in data["plugins"] if p["name"] == "lab")
    assert lab["dist"] == "rcon-example-lab" and lab["version"] == "0.3.1" and lab["status"] == "loaded"
    assert lab["widgets"] == [{"kind": "lab.gripper", "title": "Gripper", "roles": ["subscribe"],
                               "accepts": ["lab_msgs/Gripper"]}]
    assert lab["templates"] == ["Gripper station"]
    text = run(lab_path, "plugins", "--check")  # also checks the template canvas against the widget
    assert "rcon-example-lab 0.3.1" in text and "lab.gripper" in text and "type lab_msgs/Gripper" in text
    assert "template 'Gripper station' (gripper_station.json)" in text
    off = run(lab_path, "plugins", env_extra={"RCON_DISABLE_PLUGINS": "lab"})
    assert "rcon-example-lab 0.3.1 (entry point 'lab' -> rcon_example_lab.plugin): disabled" in off


def test_rcon_match_knows_the_contributed_type(lab_path):
    data = json.loads(run(lab_path, "match", "lab_msgs/msg/Gripper", "--json"))
    assert data["role"] == "subscribe"
    first = data["matches"][0]
    assert (first["kind"], first["rank"], first["package"]) == ("lab.gripper", "exact", "rcon-example-lab")
    text = run(lab_path, "match", "lab_msgs/Gripper", "--role", "subscribe")
    assert text.splitlines()[0].split()[:2] == ["exact", "lab.gripper"]


def test_on_a_canvas_against_the_sim(lab_path):
    # the sim runs where the plugin is installed, so it knows lab_msgs/Gripper and plays the robot's side
    out = run(lab_path, code="""
        import asyncio, json
        from rcon_core.bridge import BridgeClient
        from rcon_core.canvas import Binding, Document, Workspace
        from rcon_core.canvas.runtime import CanvasRuntime
        from rcon_core.msgs import TypeRegistry
        from rcon_core.plugins import PluginManager
        from rcon_core.sim import SimServer
        from rcon_core.testing import until

        async def main():
            sim = SimServer(host="127.0.0.1", port=0, plugin_types=True)
            await sim.start()
            sim.advertise_internal("/gripper", "lab_msgs/Gripper", "/lab_gripper")
            pm = PluginManager(); pm.load_entry_points()
            types = TypeRegistry.standard(); pm.apply_types(types)
            doc = Document(Workspace.new("Lab"))
            w = doc.add_widget(doc.current.id, "lab.gripper",
                               Binding("/gripper", "lab_msgs/Gripper", "subscribe"), settings={"max_opening": 0.1})
            client = BridgeClient(sim.url, reconnect=False)
            await client.connect()
            rt = CanvasRuntime(pm, client, types=types)
            rt.start(doc.current)
            model = rt.models[w.id]
            await until(lambda: sim.topic_subscriber_count("/gripper") == 1, 10, "the gripper subscription")
            sim.publish("/gripper", {"opening": 0.05, "force": 2.0, "grasping": True, "tool_id": "t1"},
                        "/lab_gripper")
            await until(lambda: model.state.count > 0, 10, "the gripper message")
            st = model.state
            rt.stop(); await client.close(); await sim.stop()
            print(json.dumps([type(model).__name__, st.value, model.problems(),
                              types.default("lab_msgs/Gripper")]))
        asyncio.run(main())
    """)
    name, value, problems, default = json.loads(out.strip().splitlines()[-1])
    assert name == "GripperModel" and value == [0.5, True] and problems == []
    assert default == {"opening": 0.0, "force": 0.0, "grasping": False, "tool_id": ""}


def test_layout_survives_the_plugin_being_uninstalled(lab_path, tmp_path):
    path = tmp_path / "ws.json"
    run(lab_path, code=f"""
        from rcon_core.canvas import Binding, Document, Workspace, WorkspaceStore
        doc = Document(Workspace.new("Lab"))
        doc.add_widget(doc.current.id, "lab.gripper", Binding("/gripper", "lab_msgs/Gripper", "subscribe"),
                       settings={{"max_opening": 0.12, "note": "left arm"}})
        WorkspaceStore({str(path)!r}).save(doc.workspace)
    """)
    before = path.read_bytes()
    # without the plugin on the path: the widget becomes a placeholder and is saved back unchanged
    from rcon_core.canvas import Document, WorkspaceStore
    from rcon_core.canvas.runtime import CanvasRuntime, MissingWidgetModel
    from rcon_core.plugins import PluginManager

    store = WorkspaceStore(path)
    doc = Document(store.load())
    pm = PluginManager(environ={})
    pm.load_entry_points()
    assert not pm.has_widget("lab.gripper")
    rt = CanvasRuntime(pm, client=None)
    (inst,) = doc.current.widgets
    model = rt.build_model(inst, port=None)
    assert isinstance(model, MissingWidgetModel) and "lab.gripper" in model.state.error
    doc.create_canvas("Other")
    doc.undo()
    store.save(doc.workspace)
    assert path.read_bytes() == before


def test_the_packages_own_tests_pass_against_the_sim(lab_path):
    """issue 15.1: the sim fixture knows the types installed plugins contribute (lab_msgs/Gripper), so the
    lab's `async def test_gripper(sim)` runs with no extra step."""
    env = dict(os.environ, PYTHONPATH=str(lab_path), QT_QPA_PLATFORM="offscreen")
    proc = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "tests"],
                          cwd=EXAMPLE, capture_output=True, text=True, env=env, timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "2 passed" in proc.stdout


def _start_sim(lab_path, *extra):
    env = dict(os.environ, PYTHONPATH=str(lab_path))
    proc = subprocess.Popen([sys.executable, "-m", "rcon_core", "sim", "--port", "0", *extra],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    first = proc.stdout.readline()
    assert " on ws://" in first, first + proc.stderr.read()
    return proc, first.split(" on ")[1].split()[0]


@pytest.mark.parametrize("extra, source", [((), "server"), (("--no-plugin-types",), "local")])
def test_rcon_sim_serves_the_plugin_types_unless_told(lab_path, extra, source):
    """issue 15.1: `rcon sim` knows plugin types by default; --no-plugin-types plays a robot without them
    (then `rcon type` still knows the type locally: issue 15.2)."""
    proc, url = _start_sim(lab_path, *extra)
    try:
        data = json.loads(run(lab_path, "type", "lab_msgs/Gripper", "--url", url, "--json"))
    finally:
        proc.terminate()
        proc.wait(timeout=20)
        proc.stdout.close()
        proc.stderr.close()
    assert data["source"] == source
    text = json.dumps(data)
    assert "opening" in text and "grasping" in text


def test_rcon_type_knows_the_contributed_type_without_a_server(lab_path):
    """issue 15.2: `rcon type lab_msgs/Winch` said "unknown type" although a plugin contributes it."""
    out = run(lab_path, "type", "lab_msgs/Gripper", "--url", "ws://127.0.0.1:1")
    assert "float64 opening" in out and "string tool_id" in out
