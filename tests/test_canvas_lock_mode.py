"""Locking as a mode switch (operator mode): notified and saved, but not an undo step."""

from rcon_core.canvas import Binding, CanvasLocked, Document, Workspace


def test_lock_as_mode_switch_is_not_undone():
    doc = Document(Workspace.new("Ops"))
    c = doc.current
    seen = []
    doc.add_listener(lambda change: seen.append((change.what, change.canvas_id)))
    w = doc.add_widget(c.id, "std.label", Binding("/battery", "sensor_msgs/BatteryState", "subscribe"))
    doc.set_locked(c.id, True, undoable=False)
    assert c.locked and seen[-1] == ("canvas-locked", c.id)
    assert doc.undo_label == "add std.label"  # the lock did not become the last undo step
    try:
        doc.move_widget(w.id, 5, 5)
        raise AssertionError("a locked canvas accepted an edit")
    except CanvasLocked:
        pass
    doc.set_locked(c.id, False, undoable=False)
    assert not c.locked
    assert doc.undo() and c.widgets == []  # undo reaches the layout edit directly
    assert not c.locked
    doc.set_locked(c.id, True)  # the default stays an undoable edit
    assert doc.undo_label == "lock canvas"
