"""Persistence: versioned JSON, atomic writes (crash-safe), backups, unknown data kept, import/export."""

import json
import os
import signal
import subprocess
import sys
import textwrap

import pytest

from rcon_core.canvas import (
    AutoSaver,
    Binding,
    Canvas,
    Document,
    Geometry,
    NewerVersionError,
    Workspace,
    WorkspaceFileError,
    WorkspaceStore,
    default_path,
    dumps_workspace,
    export_canvas,
    import_canvas,
    loads_workspace,
)
from rcon_core.canvas import store as store_mod


def sample() -> Workspace:
    doc = Document(Workspace.new("Main"))
    c = doc.current
    doc.add_widget(c.id, "std.slider", Binding("/speed", "std_msgs/Float64", "publish", "data"),
                   Geometry(10, 20, 200, 60), {"minimum": -1.5, "maximum": 2, "label": "Speed ⚓"})
    deck = doc.create_canvas("Deck")
    doc.add_widget(deck.id, "std.switch", Binding("/lights", "std_srvs/SetBool", "call", ["request.data"]))
    doc.set_locked(deck.id, True)
    return doc.workspace


def test_round_trip_is_exact(tmp_path):
    ws = sample()
    text = dumps_workspace(ws)
    data = json.loads(text)
    assert data["format"] == "rcon-workspace" and data["version"] == 2
    assert data["canvases"][1]["locked"] is True
    assert data["canvases"][1]["widgets"][0]["binding"] == {
        "name": "/lights", "type": "std_srvs/SetBool", "role": "call", "field_paths": ["request.data"],
        "robot": ""}
    again = loads_workspace(text)
    assert again == ws
    assert dumps_workspace(again) == text
    store = WorkspaceStore(tmp_path / "sub" / "ws.json")
    assert store.load().canvases[0].name == "Main"  # no file yet: a new workspace
    store.save(ws)
    assert store.load() == ws


def test_missing_plugin_widget_and_unknown_keys_saved_back_byte_for_byte(tmp_path):
    path = tmp_path / "ws.json"
    store = WorkspaceStore(path)
    ws = sample()
    store.save(ws)
    data = json.loads(path.read_text())
    odd = {"nested": {"list": [1, 2.5, None, True, "ü"], "big": 12345678901234567890}, "tiny": 1e-300}
    data["canvases"][0]["widgets"].append({
        "id": "w-gone", "kind": "retired.widget", "title": "Old", "binding": {"name": "/x", "type": "a/B",
        "role": "subscribe", "field_paths": [], "robot": ""}, "geometry": {"x": 1.0, "y": 2.0, "w": 3.0, "h": 4.0},
        "settings": odd, "future_widget_key": {"keep": "me"}})
    data["canvases"][0]["future_canvas_key"] = [1, 2]
    data["future_top_key"] = "yes"
    path.write_text(json.dumps(data, indent=2, ensure_ascii=False) + "\n")
    before = path.read_bytes()
    loaded = store.load()
    gone = loaded.canvases[0].widget("w-gone")
    assert gone.settings == odd and gone.extra == {"future_widget_key": {"keep": "me"}}
    store.save(loaded)
    assert path.read_bytes() == before


@pytest.mark.parametrize("content, reason", [
    (b"{not json", "not valid JSON"),
    (b'{"format": "something-else", "version": 1}', "not an RCON workspace file"),
    (b'{"format": "rcon-workspace", "version": "one"}', "bad format version"),
    (b'{"format": "rcon-workspace", "version": 1, "canvases": [{"id": "c", "name": "A", "widgets": '
     b'[{"id": "w", "kind": "k", "geometry": {"x": "left"}}]}]}', "geometry.x must be a number"),
    (b'{"format": "rcon-workspace", "version": 1, "canvases": [{"id": "c", "name": "A"}, '
     b'{"id": "c", "name": "B"}]}', "duplicate ids"),
])
def test_corrupt_file_clear_error_backup_and_never_overwritten(tmp_path, content, reason):
    path = tmp_path / "ws.json"
    path.write_bytes(content)
    store = WorkspaceStore(path)
    with pytest.raises(WorkspaceFileError, match=reason) as info:
        store.load()
    assert str(path) in str(info.value)
    assert info.value.backup is not None and info.value.backup.read_bytes() == content
    assert store.read_only
    with pytest.raises(WorkspaceFileError, match="not saving over a file that could not be read"):
        store.save(Workspace.new())
    assert path.read_bytes() == content
    store.save(Workspace.new(), force=True)  # after the user said so
    assert store.load().canvases[0].name == "Main"


def test_newer_version_is_refused(tmp_path):
    path = tmp_path / "ws.json"
    content = json.dumps({"format": "rcon-workspace", "version": 7, "canvases": []}).encode()
    path.write_bytes(content)
    store = WorkspaceStore(path)
    with pytest.raises(NewerVersionError, match="newer RCON.*version 7.*reads up to 2"):
        store.load()
    doc = Document()
    saver = AutoSaver(doc, store, on_error=lambda exc: errors.append(exc))
    errors = []
    doc.create_canvas("X")
    assert path.read_bytes() == content and len(errors) == 1 and saver.saves == 0


def test_crash_in_replace_leaves_old_file_and_no_temp(tmp_path, monkeypatch):
    path = tmp_path / "ws.json"
    store = WorkspaceStore(path)
    store.save(sample())
    before = path.read_bytes()

    def boom(src, dst):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(store_mod.os, "replace", boom)
    with pytest.raises(OSError, match="No space left"):
        store.save(Workspace.new("Other"))
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ws.json"]


def test_process_killed_mid_save_leaves_old_file_intact(tmp_path):
    path = tmp_path / "ws.json"
    WorkspaceStore(path).save(sample())
    before = path.read_bytes()
    script = textwrap.dedent(f"""
        import os, signal
        from rcon_core.canvas import store as s
        from rcon_core.canvas import Workspace, WorkspaceStore
        def die(*a):  # killed after the data hit the temp file, before the rename
            os.kill(os.getpid(), signal.SIGKILL)
        s.os.replace = die
        ws = Workspace.new("Half written")
        WorkspaceStore({str(path)!r}).save(ws)
    """)
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, timeout=60)
    assert proc.returncode == -signal.SIGKILL, proc.stderr.decode()
    assert path.read_bytes() == before
    leftovers = [p for p in tmp_path.iterdir() if p.name != "ws.json"]
    assert leftovers and all(p.name.startswith(".ws.json.") for p in leftovers)  # the dead temp file
    assert WorkspaceStore(path).load() == loads_workspace(before)


def test_autosave_after_each_change_and_debounced(tmp_path):
    store = WorkspaceStore(tmp_path / "ws.json")
    doc = Document(Workspace.new())
    saver = AutoSaver(doc, store)
    w = doc.add_widget(doc.current.id, "std.label")
    doc.move_widget(w.id, 7, 8)
    assert saver.saves == 2
    assert store.load().current_canvas.widget(w.id).geometry.x == 7
    saver.close()
    slow = AutoSaver(doc, store, debounce=30.0)
    for x in range(10):
        doc.move_widget(w.id, x + 100, 0)
    assert slow.saves == 0  # still waiting for the burst to end
    assert slow.flush() and slow.saves == 1
    assert store.load().current_canvas.widget(w.id).geometry.x == 109
    slow.close()


def test_export_and_import_one_canvas(tmp_path):
    ws = sample()
    deck = ws.canvas_named("Deck")
    export_canvas(deck, tmp_path / "deck.json")
    data = json.loads((tmp_path / "deck.json").read_text())
    assert data["format"] == "rcon-canvas" and data["version"] == 2
    back = import_canvas(tmp_path / "deck.json")
    assert back == deck
    doc = Document(ws)
    added = doc.add_canvas(back)
    assert added.name == "Deck (2)" and added.id != deck.id
    (tmp_path / "ws.json").write_text(dumps_workspace(ws))
    with pytest.raises(WorkspaceFileError, match="not an RCON canvas file"):
        import_canvas(tmp_path / "ws.json")
    with pytest.raises(WorkspaceFileError, match="no such file"):
        import_canvas(tmp_path / "nope.json")


def test_default_path_uses_config_dir(monkeypatch, tmp_path):
    monkeypatch.setenv("RCON_CONFIG_DIR", str(tmp_path))
    assert default_path() == tmp_path / "workspace.json"
    monkeypatch.delenv("RCON_CONFIG_DIR")
    p = default_path()
    assert p.name == "workspace.json" and "rcon" in p.parts
    assert os.path.isabs(p)


# a workspace file exactly as this build writes format version 1 (kept verbatim: it must keep loading)
VERSION_1_FILE = """{
  "format": "rcon-workspace",
  "version": 1,
  "current": "c-0f1e2d3c",
  "canvases": [
    {
      "id": "c-0f1e2d3c",
      "name": "Drive",
      "locked": true,
      "widgets": [
        {
          "id": "w-1a2b3c4d",
          "kind": "std.slider",
          "title": "Speed limit",
          "binding": {"name": "/speed_limit", "type": "std_msgs/Float64", "role": "publish",
                      "field_paths": ["data"]},
          "geometry": {"x": 352.0, "y": 336.0, "w": 288.0, "h": 96.0},
          "settings": {"minimum": 0.0, "maximum": 3.0, "units": "m/s"}
        }
      ]
    }
  ],
  "plugin_settings": {"std.slider": {"haptics": false}}
}
"""


def test_version_1_files_load_and_migrate_to_one_robot(tmp_path):
    ws = loads_workspace(VERSION_1_FILE)
    [canvas] = ws.canvases
    assert (ws.current, canvas.name, canvas.locked) == ("c-0f1e2d3c", "Drive", True)
    [w] = canvas.widgets
    assert (w.id, w.kind, w.title) == ("w-1a2b3c4d", "std.slider", "Speed limit")
    assert w.binding == Binding("/speed_limit", "std_msgs/Float64", "publish", ("data",))
    assert (w.geometry.x, w.geometry.y, w.geometry.w, w.geometry.h) == (352, 336, 288, 96)
    assert w.settings == {"minimum": 0.0, "maximum": 3.0, "units": "m/s"}
    assert ws.plugin_settings == {"std.slider": {"haptics": False}}
    # the old single robot (whose URL the app kept: "" = the connection bar's) is the first robot now,
    # and the widget talks to it
    [robot] = ws.robots
    assert (robot.id, robot.name, robot.url, robot.auth, robot.view_only) == ("r-1", "Robot", "", False, False)
    assert ws.robot_of(w) is robot
    # saved again it is version 2, with the robot and the binding's robot ("" = the first)
    data = json.loads(dumps_workspace(ws))
    assert data["version"] == 2 and data["robots"][0]["id"] == "r-1"
    assert data["canvases"][0]["widgets"][0]["binding"]["robot"] == ""
    old = json.loads(VERSION_1_FILE)
    del data["robots"], data["canvases"][0]["widgets"][0]["binding"]["robot"]
    data["version"] = 1
    assert data == old  # nothing else changed


# a workspace file exactly as this build writes format version 2 (kept verbatim: it must keep loading)
VERSION_2_FILE = """{
  "format": "rcon-workspace",
  "version": 2,
  "current": "c-0f1e2d3c",
  "robots": [
    {"id": "r-1", "name": "Alpha", "url": "ws://10.0.0.5:9090", "ca_file": "", "client_cert": "",
     "client_key": "", "auth": false, "view_only": false, "colour": ""},
    {"id": "r-2", "name": "Bravo", "url": "wss://10.0.0.6:9090", "ca_file": "/etc/rcon/ca.pem",
     "client_cert": "", "client_key": "", "auth": true, "view_only": true, "colour": "#d55e00"}
  ],
  "canvases": [
    {
      "id": "c-0f1e2d3c",
      "name": "Drive",
      "locked": true,
      "widgets": [
        {
          "id": "w-1a2b3c4d",
          "kind": "std.slider",
          "title": "Speed limit",
          "binding": {"name": "/speed_limit", "type": "std_msgs/Float64", "role": "publish",
                      "field_paths": ["data"], "robot": "r-2"},
          "geometry": {"x": 352.0, "y": 336.0, "w": 288.0, "h": 96.0},
          "settings": {"minimum": 0.0, "maximum": 3.0, "units": "m/s"}
        }
      ]
    }
  ],
  "plugin_settings": {"std.slider": {"haptics": false}}
}
"""


def test_version_2_files_of_this_build_load_and_the_current_format_round_trips(tmp_path):
    ws = loads_workspace(VERSION_2_FILE)
    alpha, bravo = ws.robots
    assert (alpha.name, alpha.url, bravo.name, bravo.ca_file, bravo.auth, bravo.view_only) == (
        "Alpha", "ws://10.0.0.5:9090", "Bravo", "/etc/rcon/ca.pem", True, True)
    [w] = ws.canvases[0].widgets
    assert w.binding.robot == "r-2" and ws.robot_of(w) is bravo
    assert json.loads(dumps_workspace(ws)) == json.loads(VERSION_2_FILE)
    assert store_mod.VERSION == 2, "the saved shape changed: bump VERSION with a migration (see store.py)"
    text = dumps_workspace(sample())
    assert dumps_workspace(loads_workspace(text)) == text


@pytest.mark.parametrize("robots, expected", [
    ('[{"id": "a"}, {"id": "a"}]', "duplicate robot ids 'a'"),
    ('[{"id": "a", "auth": "yes"}]', "must be true or false, found 'yes' at robots[0].auth"),
    ('[{"id": "", "name": "no id"}]', "robot #1 ('no id') has no id"),
    ('[{"name": "no id"}]', "required field missing at robots[0].id"),
    ('"r-1"', "robots"),
    ('[{"id": "a", "envelope": {"max_linear": 999999999999}}]',
     "the maximum linear speed must be more than 0 and at most 100 m/s, not 1e+12 at robots[0].envelope"),
    ('[{"id": "a", "envelope": {"max_linear": -1}}]', "more than 0"),
    ('[{"id": "a", "envelope": {"max_angular": "fast"}}]', "must be a number"),
    ('[{"id": "a", "envelope": {"speed": 1}}]', "unknown keys speed"),
    ('[{"id": "a", "envelope": 2}]', "must be an object"),
])
def test_bad_robots_are_refused_with_a_reason(robots, expected):
    text = '{"format": "rcon-workspace", "version": 2, "robots": ' + robots + ', "canvases": []}'
    with pytest.raises(WorkspaceFileError) as info:
        loads_workspace(text)
    assert expected in str(info.value)


# an early development build: no canvas ids, "rect" instead of geometry, the same version number
EARLY_BUILD_FILE = json.dumps({"format": "rcon-workspace", "version": 1, "canvases": [
    {"name": "Main", "widgets": [{"kind": "std.label", "rect": [16, 16, 160, 80]}]}]}).encode()


def test_an_unreadable_file_is_copied_once_per_content_and_can_be_moved_aside(tmp_path):
    path = tmp_path / "ws.json"
    path.write_bytes(EARLY_BUILD_FILE)
    for _start in range(3):  # three starts on the same bad file keep one copy
        with pytest.raises(WorkspaceFileError, match="invalid workspace") as info:
            WorkspaceStore(path).load()
    copies = list(tmp_path.glob("ws.json.unreadable-*"))
    assert copies == [info.value.backup] and copies[0].read_bytes() == EARLY_BUILD_FILE
    path.write_bytes(EARLY_BUILD_FILE + b" ")  # other content: another copy
    with pytest.raises(WorkspaceFileError):
        WorkspaceStore(path).load()
    assert len(list(tmp_path.glob("ws.json.unreadable-*"))) == 2
    # the operator starts a new layout: the bad file goes aside (its content kept), saving works again
    store = WorkspaceStore(path)
    with pytest.raises(WorkspaceFileError):
        store.load()
    kept = store.move_aside()
    assert kept is not None and kept.read_bytes() == EARLY_BUILD_FILE + b" " and not path.exists()
    assert len(list(tmp_path.glob("ws.json.unreadable-*"))) == 2
    store.save(Workspace.new("Fresh"))
    assert WorkspaceStore(path).load().canvases[0].name == "Fresh"


def test_a_view_only_canvas_round_trips_and_others_do_not_write_the_key():
    ws = Workspace.new("Watch")
    ws.canvases[0].view_only = True
    ws.canvases.append(Canvas("c-2", "Drive"))
    data = json.loads(dumps_workspace(ws))
    assert data["canvases"][0]["view_only"] is True and "view_only" not in data["canvases"][1]
    back = loads_workspace(dumps_workspace(ws))
    assert [c.view_only for c in back.canvases] == [True, False]


def test_a_robots_safety_envelope_round_trips_and_is_written_only_when_set():
    """issue 21.4: the envelope is one of the robot's settings, saved with the workspace; a file of an
    earlier build (no envelope) loads with none and is written back without the key."""
    from rcon_core.bridge.envelope import Envelope

    ws = loads_workspace(VERSION_2_FILE)
    assert [r.envelope for r in ws.robots] == [None, None]
    ws.robots[1].envelope = Envelope(max_linear=1.5, max_angular=None)
    data = json.loads(dumps_workspace(ws))
    assert "envelope" not in data["robots"][0] and data["robots"][1]["envelope"] == {"max_linear": 1.5}
    again = loads_workspace(dumps_workspace(ws))
    assert again.robots[1].envelope == Envelope(1.5, None) and again.robots[0].envelope is None
