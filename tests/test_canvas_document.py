"""Document: canvas and widget operations, undo/redo, notifications, locking."""

import pytest

from rcon_core.canvas import Binding, CanvasLocked, Document, EditError, Geometry, Workspace


@pytest.fixture
def doc():
    d = Document(Workspace.new("Main"))
    d.changes = []
    d.add_listener(d.changes.append)
    return d


def whats(doc):
    out = [c.what for c in doc.changes]
    doc.changes.clear()
    return out


def test_canvas_operations_with_undo_redo(doc):
    main = doc.current
    deck = doc.create_canvas("Deck")
    assert [c.name for c in doc.workspace.canvases] == ["Main", "Deck"]
    assert doc.create_canvas("Deck").name == "Deck (2)"
    doc.rename_canvas(deck.id, "Bridge deck")
    with pytest.raises(EditError, match="already exists"):
        doc.rename_canvas(deck.id, "Main")
    with pytest.raises(EditError, match="needs a name"):
        doc.create_canvas("   ")
    assert whats(doc) == ["canvas-added", "canvas-added", "canvas-renamed"]
    doc.undo()
    assert deck.name == "Deck"
    doc.redo()
    assert deck.name == "Bridge deck"
    doc.switch_canvas(deck.id)
    assert doc.current is deck
    doc.delete_canvas(deck.id)
    assert deck not in doc.workspace.canvases and doc.current is not deck
    doc.undo()
    assert doc.current is deck and doc.workspace.canvases.index(deck) == 1
    doc.delete_canvas(doc.workspace.canvases[2].id)
    doc.delete_canvas(deck.id)
    with pytest.raises(EditError, match="last canvas"):
        doc.delete_canvas(main.id)


def test_duplicate_gets_fresh_ids_and_a_deep_copy(doc):
    c = doc.current
    w = doc.add_widget(c.id, "std.slider", Binding("/speed", "std_msgs/Float64", "publish", "data"),
                       Geometry(10, 20, 100, 50), {"min": 0, "max": [1, 2]})
    dup = doc.duplicate_canvas(c.id)
    assert dup.name == "Main copy" and doc.workspace.canvases[1] is dup
    (w2,) = dup.widgets
    assert w2.id != w.id and w2.kind == w.kind and w2.binding == w.binding and w2.settings == w.settings
    w2.settings["max"].append(3)
    assert w.settings["max"] == [1, 2]
    doc.undo()
    assert dup not in doc.workspace.canvases


def test_widget_operations_and_undo_chain(doc):
    c = doc.current
    w = doc.add_widget(c.id, "std.label", Binding("/battery", "sensor_msgs/BatteryState", "subscribe",
                                                  ["percentage"]))
    doc.move_widget(w.id, 40, 80)
    doc.resize_widget(w.id, 300, 120)
    doc.reconfigure_widget(w.id, settings={"decimals": 2}, title="Battery")
    doc.reconfigure_widget(w.id, binding=Binding("/battery2", "sensor_msgs/BatteryState", "subscribe"))
    assert (w.geometry.x, w.geometry.y, w.geometry.w, w.geometry.h) == (40, 80, 300, 120)
    assert w.settings == {"decimals": 2} and w.title == "Battery" and w.binding.name == "/battery2"
    assert whats(doc) == ["widget-added"] + ["widget-changed"] * 4
    assert doc.undo_label == "configure"
    doc.undo()
    assert w.binding.name == "/battery"
    doc.undo()
    assert w.settings == {} and w.title == ""
    doc.undo()
    assert (w.geometry.w, w.geometry.h) == (160, 80)
    doc.undo()
    assert (w.geometry.x, w.geometry.y) == (0, 0)
    doc.undo()
    assert c.widgets == []
    assert not doc.can_undo and doc.undo() is False
    for _ in range(5):
        assert doc.redo()
    assert c.widgets == [w] and w.binding.name == "/battery2" and w.geometry.x == 40
    doc.remove_widget(w.id)
    assert not doc.can_redo
    doc.undo()
    assert c.widgets == [w]
    with pytest.raises(EditError, match="size must be positive"):
        doc.resize_widget(w.id, 0, 10)
    with pytest.raises(EditError, match="no widget"):
        doc.move_widget("w-missing", 1, 1)


def test_unchanged_edit_is_not_an_undo_step(doc):
    w = doc.add_widget(doc.current.id, "std.label")
    doc.move_widget(w.id, 0, 0)
    assert doc.undo_label == "add std.label"


def test_locked_canvas_refuses_widget_edits(doc):
    c = doc.current
    w = doc.add_widget(c.id, "std.button")
    doc.set_locked(c.id, True)
    for edit in (lambda: doc.add_widget(c.id, "std.label"), lambda: doc.move_widget(w.id, 5, 5),
                 lambda: doc.remove_widget(w.id), lambda: doc.reconfigure_widget(w.id, settings={"a": 1})):
        with pytest.raises(CanvasLocked, match="is locked"):
            edit()
    doc.rename_canvas(c.id, "Ops")  # the canvas itself may still be renamed
    doc.undo()
    doc.undo()
    assert not c.locked
    doc.move_widget(w.id, 5, 5)


def test_plugin_settings_undo(doc):
    doc.set_plugin_settings("map.map", {"tiles": "/data/tiles"})
    doc.set_plugin_settings("map.map", {"tiles": "/other"})
    doc.undo()
    assert doc.workspace.plugin_settings == {"map.map": {"tiles": "/data/tiles"}}
    doc.undo()
    assert doc.workspace.plugin_settings == {}


def test_a_failing_listener_does_not_stop_the_others(doc, capsys):
    seen = []

    def bad(change):
        raise RuntimeError("listener bug")

    doc.add_listener(bad)
    remove = doc.add_listener(seen.append)
    doc.create_canvas("X")
    assert [c.what for c in seen] == ["canvas-added"]
    assert "listener bug" in capsys.readouterr().err
    remove()
    doc.create_canvas("Y")
    assert len(seen) == 1


def test_import_adds_a_copy_with_unique_ids(doc):
    c = doc.current
    doc.add_widget(c.id, "std.label")
    imported = doc.add_canvas(c)
    assert imported.id != c.id and imported.name == "Main (2)"
    assert imported.widgets[0].id != c.widgets[0].id
