"""Layout files as hostile input: deep nesting, numbers that are not finite or out of range, booleans that
are not booleans, wrong types anywhere. Each is one clear WorkspaceFileError (which canvas, which widget,
which key, what was found), a kept copy, and a file that is never overwritten."""

from __future__ import annotations

import copy
import json
import math

import attrs
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rcon_core.canvas import (
    AutoSaver,
    Binding,
    Document,
    Geometry,
    Workspace,
    WorkspaceFileError,
    WorkspaceStore,
    dumps_workspace,
    export_canvas,
    import_canvas,
    loads_workspace,
)
from rcon_core.canvas.checks import COORD_LIMIT, MAX_DEPTH


def layout(**canvas_extra) -> dict:
    """A valid version 1 layout: canvas 'Main' (c-main) with widget 'Speed' (w-speed)."""
    return {"format": "rcon-workspace", "version": 1, "current": "c-main", "canvases": [
        {"id": "c-main", "name": "Main", "locked": False, "widgets": [
            {"id": "w-speed", "kind": "std.slider", "title": "Speed",
             "binding": {"name": "/speed", "type": "std_msgs/Float64", "role": "publish", "field_paths": ["data"]},
             "geometry": {"x": 16, "y": 32, "w": 160, "h": 80}, "settings": {"maximum": 2.0}}],
         **canvas_extra}], "plugin_settings": {}}


def refused(tmp_path, content: bytes | str, match: str) -> WorkspaceFileError:
    """``content`` as the layout file: the store refuses it with ``match``, keeps a copy, becomes
    read-only, and a save (the app's autosave after an edit) leaves the file byte for byte."""
    raw = content.encode() if isinstance(content, str) else content
    path = tmp_path / "ws.json"
    path.write_bytes(raw)
    store = WorkspaceStore(path)
    with pytest.raises(WorkspaceFileError, match=match) as info:
        store.load()
    assert store.read_only
    assert info.value.backup is not None and info.value.backup.read_bytes() == raw
    doc = Document(Workspace.new())
    errors: list[Exception] = []
    saver = AutoSaver(doc, store, on_error=errors.append)
    doc.create_canvas("Edited")
    assert saver.saves == 0 and len(errors) == 1 and path.read_bytes() == raw
    return info.value


def with_value(place: str, key: str, value: str) -> str:
    """The sample layout's text with ``place[key]`` set to the JSON text ``value`` (NaN, 1e999...)."""
    data = layout()
    target = {"canvas": data["canvases"][0], "widget": data["canvases"][0]["widgets"][0],
              "geometry": data["canvases"][0]["widgets"][0]["geometry"],
              "settings": data["canvases"][0]["widgets"][0]["settings"]}[place]
    target[key] = "@@"
    return json.dumps(data).replace('"@@"', value)


# --------------------------------------------------------------------------------------- deep nesting
def test_a_small_file_nested_5000_deep_is_refused_not_a_crash(tmp_path):
    deep = '{"format": "rcon-workspace", "version": 1, "canvases": ' + "[" * 5000 + "]" * 5000 + "}"
    assert len(deep) < 11_000
    err = refused(tmp_path, deep, f"nested deeper than {MAX_DEPTH} levels")
    assert "RecursionError" not in str(err)


def test_settings_nested_deeper_than_the_limit_name_the_widget(tmp_path):
    # deep enough to trouble the app later (undo copies, the next save), shallow enough for json.loads
    text = with_value("settings", "tree", "[" * 300 + "]" * 300)
    refused(tmp_path, text, r"canvas 'Main' \('c-main'\) \(#1\), widget 'Speed' \('w-speed'\) \(#1\): "
                            rf"settings\.tree\[0\].* is nested deeper than {MAX_DEPTH} levels")
    # a layout nested up to the limit still loads
    ok = with_value("settings", "tree", "[" * (MAX_DEPTH - 6) + "]" * (MAX_DEPTH - 6))
    assert loads_workspace(ok).canvases[0].widgets[0].settings["tree"]


# ---------------------------------------------------------------------------------------------- numbers
@pytest.mark.parametrize("key, text, found", [
    ("x", "NaN", "nan"), ("y", "Infinity", "inf"), ("w", "-Infinity", "-inf"), ("h", "1e999", "inf"),
])
def test_a_coordinate_that_is_not_finite_is_refused(tmp_path, key, text, found):
    refused(tmp_path, with_value("geometry", key, text),
            rf"widget 'Speed' \('w-speed'\) \(#1\): geometry\.{key} is not a finite number \(found {found}\)")


@pytest.mark.parametrize("key, text", [
    ("x", "1" + "0" * 400), ("y", "-2e7"), ("x", str(COORD_LIMIT * 2)), ("w", "-160"), ("h", "-0.5"),
])
def test_a_coordinate_out_of_range_is_refused(tmp_path, key, text):
    refused(tmp_path, with_value("geometry", key, text),
            rf"widget 'Speed' \('w-speed'\) \(#1\): geometry\.{key} must be between .*, found ")


def test_a_number_that_is_not_finite_anywhere_is_refused(tmp_path):
    refused(tmp_path, with_value("settings", "maximum", "NaN"),
            r"widget 'Speed' \('w-speed'\) \(#1\): settings\.maximum is not a finite number")
    top = json.dumps(layout()).replace('"plugin_settings": {}', '"plugin_settings": {"std.slider": {"step": Infinity}}')
    refused(tmp_path, top, r"plugin_settings\.std\.slider\.step is not a finite number")


def test_a_workspace_holding_a_nan_is_not_saved_and_the_file_stays(tmp_path):
    path = tmp_path / "ws.json"
    store = WorkspaceStore(path)
    doc = Document(Workspace.new())
    store.save(doc.workspace)
    before = path.read_bytes()
    errors: list[Exception] = []
    AutoSaver(doc, store, on_error=errors.append)
    doc.add_widget(doc.current.id, "std.slider", Binding("/s", "std_msgs/Float64", "publish", "data"),
                   Geometry(0, 0, 160, 80), {"maximum": math.nan})
    assert len(errors) == 1 and "not a finite number" in str(errors[0])
    assert path.read_bytes() == before
    with pytest.raises(WorkspaceFileError, match="cannot be saved"):
        dumps_workspace(doc.workspace)


# --------------------------------------------------------------------------------------------- booleans
@pytest.mark.parametrize("value, found", [
    ('"no"', "'no'"), ('"false"', "'false'"), ("0", "0"), ("1", "1"), ("null", "None"), ("[]", "a list of 0"),
])
def test_locked_must_be_a_boolean(tmp_path, value, found):
    refused(tmp_path, with_value("canvas", "locked", value),
            rf"canvas 'Main' \('c-main'\) \(#1\): locked must be true or false, found {found}")


def test_true_and_false_load_as_themselves():
    for value in (True, False):
        assert loads_workspace(json.dumps(layout(locked=value))).canvases[0].locked is value


@attrs.define
class Flags:
    """A widget's settings with a boolean, as a plugin declares them."""

    follow: bool = True
    label: str = ""


def test_a_boolean_setting_that_is_not_a_boolean_is_a_problem_sentence():
    from rcon_core.plugins import Accepts, Role, WidgetSpec
    from rcon_core.plugins.model import WidgetModel

    spec = WidgetSpec(kind="test.flags", title="Flags", model=WidgetModel, roles={Role.SUBSCRIBE},
                      accepts=Accepts(messages=["any"]), settings=Flags)
    for bad, found in (("no", "'no'"), (0, "0"), (None, "None"), ("false", "'false'")):
        assert spec.settings_problems({"follow": bad}) == [
            f"invalid settings: follow must be true or false (got {found})"]
    assert spec.settings_problems({"follow": False}) == []
    assert spec.make_settings({"follow": False}).follow is False


# ------------------------------------------------------------------------------------ wrong types, ids
@pytest.mark.parametrize("text, match", [
    (json.dumps(layout()).replace('"name": "Main"', '"name": 5'), r"canvas \('c-main'\) \(#1\): name must be a string, found 5"),
    (json.dumps(layout()).replace('"id": "w-speed"', '"id": ["w"]'), r"widget 'Speed' \(#1\): id must be a string"),
    (json.dumps(layout()).replace('"role": "publish"', '"role": 7'), r"binding\.role must be a string, found 7"),
    (json.dumps(layout()).replace('"widgets": [', '"widgets": [3, '), r"canvas 'Main' .*widget \(#1\): .*must be an object, found 3"),
    (json.dumps({**layout(), "canvases": {"a": 1}}), "invalid workspace"),
    (json.dumps({**layout(), "current": ["c"]}), "current must be a canvas id"),
    (json.dumps({**layout(), "plugin_settings": [1]}), "plugin_settings must map widget kinds to objects"),
])
def test_wrong_types_are_one_sentence_each(tmp_path, text, match):
    refused(tmp_path, text, match)


def test_messages_quote_briefly_whatever_the_file_holds(tmp_path):
    huge = "k" * 100_000
    err = refused(tmp_path, with_value("settings", huge, "NaN"), "is not a finite number")
    assert len(str(err)) < 600
    err = refused(tmp_path, json.dumps({"format": huge, "version": 1}), "not an RCON workspace file")
    assert len(str(err)) < 600
    err = refused(tmp_path, json.dumps(layout()).replace('"name": "Main"', f'"name": 5, "id2": "{huge}"')
                  .replace('"locked": false', f'"locked": "{huge}"'), "locked must be true or false")
    assert len(str(err)) < 800


def test_duplicate_ids_are_found_among_many_and_listed_briefly(tmp_path):
    data = layout()
    widget = data["canvases"][0]["widgets"][0]
    data["canvases"][0]["widgets"] = [dict(widget, id=f"w-{i}") for i in range(5000)]
    assert loads_workspace(json.dumps(data))  # 5000 distinct ids: fine
    data["canvases"][0]["widgets"] += [dict(widget, id=f"w-{i}") for i in (7, 4999, 12, 300)]
    data["canvases"].append({"id": "w-9", "name": "Clash", "widgets": []})  # a canvas id equal to a widget's
    err = refused(tmp_path, json.dumps(data), "duplicate ids")
    assert "'w-12', 'w-300', 'w-4999' and 2 more" in str(err)


def test_an_imported_canvas_file_gets_the_same_checks(tmp_path):
    doc = Document(Workspace.new())
    path = tmp_path / "deck.rcon-canvas"
    export_canvas(doc.current, path)
    data = json.loads(path.read_text())
    data["canvas"]["locked"] = "yes"
    path.write_text(json.dumps(data))
    with pytest.raises(WorkspaceFileError, match="locked must be true or false, found 'yes'"):
        import_canvas(path)
    path.write_text('{"format": "rcon-canvas", "version": 1, "canvas": ' + "{\"a\":" * 3000 + "1" + "}" * 3001)
    with pytest.raises(WorkspaceFileError, match="nested deeper"):
        import_canvas(path)


# ------------------------------------------------------------------------------------- anything at all
JSON_VALUES = st.recursive(
    st.none() | st.booleans() | st.integers(-10**30, 10**30) | st.floats(allow_nan=True, allow_infinity=True)
    | st.text(max_size=8),
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=5), inner, max_size=3),
    max_leaves=8,
)


def _places(value, path=()):
    yield path
    if isinstance(value, dict):
        for k, v in value.items():
            yield from _places(v, (*path, k))
    elif isinstance(value, list):
        for i, v in enumerate(value):
            yield from _places(v, (*path, i))


PLACES = [p for p in _places(layout()) if p]


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(place=st.sampled_from(PLACES), value=JSON_VALUES)
def test_any_value_anywhere_loads_sanely_or_is_a_workspace_file_error(place, value):
    data = copy.deepcopy(layout())
    target = data
    for key in place[:-1]:
        target = target[key]
    target[place[-1]] = value
    text = json.dumps(data)  # NaN and Infinity written as such, the way a hand edit or another tool might
    try:
        ws = loads_workspace(text)
    except WorkspaceFileError as exc:
        assert str(exc) and len(str(exc)) < 2000
        return
    for canvas in ws.canvases:
        assert isinstance(canvas.locked, bool) and isinstance(canvas.name, str)
        for w in canvas.widgets:
            g = w.geometry
            assert all(math.isfinite(v) and abs(v) <= COORD_LIMIT for v in (g.x, g.y, g.w, g.h))
            assert g.w >= 0 and g.h >= 0
            assert all(isinstance(s, str) for s in (w.id, w.kind, w.title, w.binding.name, w.binding.type))
    assert loads_workspace(dumps_workspace(ws)) == ws  # and what loads saves back
