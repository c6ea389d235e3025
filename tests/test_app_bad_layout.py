"""The app started on a hostile layout file: it opens, says what is wrong on the banner, and never writes
over the file, whatever the operator changes."""

from __future__ import annotations

import json

import pytest
from app_helpers import open_window, tap
from test_app_window import make_plugins

pytestmark = pytest.mark.usefixtures("qapp")


def probe_layout(geometry_x: str = "16", settings: str = "{}") -> str:
    data = {"format": "rcon-workspace", "version": 1, "current": "c-deck", "canvases": [
        {"id": "c-deck", "name": "Deck", "locked": True, "widgets": [
            {"id": "w-probe", "kind": "apptest.probe", "title": "Probe",
             "binding": {"name": "/battery", "type": "sensor_msgs/BatteryState", "role": "subscribe",
                         "field_paths": ["percentage"]},
             "geometry": {"x": "@x", "y": 16, "w": 192, "h": 112}, "settings": "@s"}]}], "plugin_settings": {}}
    return json.dumps(data).replace('"@x"', geometry_x).replace('"@s"', settings)


BAD_FILES = {
    "nested 5000 deep": '{"format": "rcon-workspace", "version": 1, "canvases": ' + "[" * 5000 + "]" * 5000 + "}",
    "NaN coordinate": probe_layout(geometry_x="NaN"),
    "huge coordinate": probe_layout(geometry_x="1e300"),
    "deep settings": probe_layout(settings='{"a": ' + "[" * 400 + "]" * 400 + "}"),
    "locked is a word": probe_layout().replace('"locked": true', '"locked": "no"'),
}
EXPECTED = {
    "nested 5000 deep": "nested deeper than",
    "NaN coordinate": "canvas 'Deck' ('c-deck') (#1), widget 'Probe' ('w-probe') (#1): geometry.x is not a finite number",
    "huge coordinate": "widget 'Probe' ('w-probe') (#1): geometry.x must be between",
    "deep settings": "widget 'Probe' ('w-probe') (#1): settings.a",
    "locked is a word": "canvas 'Deck' ('c-deck') (#1): locked must be true or false, found 'no'",
}


@pytest.mark.parametrize("name", list(BAD_FILES))
def test_a_hostile_layout_shows_the_banner_and_is_never_overwritten(qtbot, tmp_path, name):
    path = tmp_path / "workspace.json"
    content = BAD_FILES[name].encode()
    path.write_bytes(content)
    window = open_window(qtbot, tmp_path, make_plugins())
    try:
        assert window.notice.isVisible() and window.notice.kind == "problem"
        text = window.banner.text()
        assert EXPECTED[name] in text and "will not be overwritten" in text, text
        assert len(text) < 1500
        assert window.store.read_only
        # the operator carries on: switches to Edit mode and adds a canvas; each change is "saved"
        tap(window.lock_button)
        tap(window.edit_button)
        window.controller.add_canvas("Scratch")
        assert not window.controller.saver.flush()
        assert path.read_bytes() == content
    finally:
        window.close()
    assert path.read_bytes() == content  # closing saves too: refused
    [kept] = tmp_path.glob("workspace.json.unreadable-*")
    assert kept.read_bytes() == content


def test_start_a_new_layout_on_a_full_disk_keeps_the_file_and_says_why(qtbot, tmp_path, monkeypatch):
    from rcon_core.canvas import files

    def disk_full(src, dst, **_kw):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(files.shutil, "copy2", disk_full)
    path = tmp_path / "workspace.json"
    content = BAD_FILES["locked is a word"].encode()
    path.write_bytes(content)
    window = open_window(qtbot, tmp_path, make_plugins())
    try:
        assert window.notice.kind == "problem" and "locked must be true or false" in window.banner.text()
        tap(window.notice.buttons["Start a new layout"])
        assert window.notice.kind == "problem" and "no copy of it could be kept" in window.banner.text()
        window.controller.add_canvas("Scratch")
        assert window.store.read_only and path.read_bytes() == content
    finally:
        window.close()
    assert path.read_bytes() == content and list(tmp_path.glob("workspace.json.unreadable-*")) == []


def test_an_unreadable_demo_layout_on_a_full_disk_is_left_alone_and_reported(qtbot, tmp_path, monkeypatch):
    from rcon_core.canvas import Workspace, files

    def disk_full(src, dst, **_kw):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(files.shutil, "copy2", disk_full)
    path = tmp_path / "workspace.json"
    content = BAD_FILES["NaN coordinate"].encode()
    path.write_bytes(content)
    window = open_window(qtbot, tmp_path, make_plugins(), demo=lambda: Workspace.new("Demo"))
    try:
        text = window.banner.text()
        assert window.notice.kind == "problem" and "not a finite number" in text and "no copy" in text, text
        window.controller.add_canvas("Scratch")
    finally:
        window.close()
    assert path.read_bytes() == content


@pytest.mark.parametrize("app_json", [
    '{"url_history": ' + "[" * 5000 + "]" * 5000 + "}",
    '{"version": 2, "url_history": 42}',
    '{"version": 2, "url_history": "ws://robot:9090"}',
])
def test_a_hostile_app_json_does_not_keep_the_app_from_starting(qtbot, tmp_path, app_json):
    from rcon_core.app.config import DEFAULT_URL

    (tmp_path / "app.json").write_text(app_json)
    window = open_window(qtbot, tmp_path, make_plugins())
    try:
        assert window.config.last_url == DEFAULT_URL and window.config.url_history == []
        window.config.remember_url("ws://boat.local:9090")
        assert window.config.url_history == ["ws://boat.local:9090"]
    finally:
        window.close()
