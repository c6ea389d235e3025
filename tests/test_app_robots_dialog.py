"""Canvas ▾ → Robots… as an operator uses it (issue 21.10), on the real window against two sims: one tap
on a cell types in it (a hint says so), and OK keeps the running widgets as they are (a half-typed
form, the map's trail) unless what changed concerns them."""

from __future__ import annotations

import pytest
from app_helpers import TIMEOUT_MS, entry_point_plugins, open_window, tap
from qtpy import QtWidgets
from qtpy.QtTest import QTest
from test_app_fleet import fleet_layout

from rcon_core.bridge import ConnectionState
from rcon_core.canvas import Binding
from rcon_core.canvas.robots import Robot
from rcon_core.testing import qt_flushed

pytestmark = pytest.mark.usefixtures("qapp")

MAP = ("Map", "map.gps", Binding("/gps/fix", "sensor_msgs/NavSatFix", "subscribe"), {"trail_spacing_m": 0.0},
       (16, 16, 320, 240))
NOTE = ("Note", "std.textfield", Binding("/note", "std_msgs/String", "publish", ("data",)), {}, (352, 16, 320, 112))
BATTERY = ("Battery", "std.label", Binding("/battery", "sensor_msgs/BatteryState", "subscribe", ("percentage",),
                                           robot="r-2"), {}, (352, 144, 240, 112))


@pytest.fixture
def window(qtbot, tmp_path, sim_fleet_threads):
    for name in ("rcon_widgets_std", "rcon_widgets_map"):
        pytest.importorskip(name)
    alpha, bravo = sim_fleet_threads(2)
    fleet_layout(tmp_path / "config", [Robot("r-1", "Alpha"), Robot("r-2", "Bravo", url=bravo.url)],
                 [MAP, NOTE, BATTERY])
    win = open_window(qtbot, tmp_path / "config", entry_point_plugins(), url=alpha.url, wait_connected=True)
    qtbot.waitUntil(lambda: win.fleet_ui.chips.chips["r-2"].state is ConnectionState.CONNECTED, timeout=TIMEOUT_MS)
    yield win
    win.shutdown()


def ok_button(dialog) -> QtWidgets.QPushButton:
    return dialog.findChild(QtWidgets.QDialogButtonBox).button(QtWidgets.QDialogButtonBox.StandardButton.Ok)


def tap_cell(table: QtWidgets.QTableWidget, row: int, col: int) -> None:
    rect = table.visualRect(table.model().index(row, col))
    tap(table.viewport(), rect.center())


def test_one_tap_on_a_cell_types_in_it_and_a_hint_says_so(qtbot, window):
    window.canvas_actions["robots"].trigger()
    dialog = window.fleet_ui.robots_dialog
    qtbot.waitUntil(dialog.isVisible, timeout=TIMEOUT_MS)
    assert dialog.hint.isVisible() and "Tap a cell" in dialog.hint.text()
    table = dialog.table
    tap_cell(table, 1, 0)  # Bravo's name: one tap
    qtbot.waitUntil(lambda: table.state() == QtWidgets.QAbstractItemView.State.EditingState, timeout=TIMEOUT_MS)
    [editor] = [e for e in table.findChildren(QtWidgets.QLineEdit) if e.isVisible()]  # the cell's editor
    editor.selectAll()
    QTest.keyClicks(editor, "Bravo two")
    tap(ok_button(dialog))  # still typing: OK takes what the cell holds
    assert [r.name for r in window.controller.workspace.robots] == ["Alpha", "Bravo two"]


def test_ok_keeps_the_running_widgets_unless_what_changed_concerns_them(qtbot, window):
    hosted = {w.title: window.host.hosted[w.id] for w in window.controller.canvas.widgets}
    qtbot.waitUntil(lambda: all(h.view is not None for h in hosted.values()), timeout=TIMEOUT_MS)
    map_, note = hosted["Map"], hosted["Note"]
    qtbot.waitUntil(lambda: map_.model.state.value is not None and len(map_.model.state.value.main.points) >= 3,
                    timeout=TIMEOUT_MS)
    window.lock_button.click()  # Operate: the form takes typing
    tap(note.view.edit)
    QTest.keyClicks(note.view.edit, "half typed")
    before = {title: (h.model, h.view) for title, h in hosted.items()}

    def robots_ok(**row) -> None:
        window.canvas_actions["robots"].trigger()
        dialog = window.fleet_ui.robots_dialog
        qtbot.waitUntil(dialog.isVisible, timeout=TIMEOUT_MS)
        if row:
            dialog.set_row(1, **row)
        tap(ok_button(dialog))
        qtbot.waitUntil(lambda: not dialog.isVisible(), timeout=TIMEOUT_MS)
        # a restart, if one were made, would have reached the window by now: the GUI's events, then the
        # bridge thread's (every link runs there), then what that posted back to the GUI
        qt_flushed(qtbot)
        window.link.thread.call(lambda: None).result(5)
        qt_flushed(qtbot)
        window._pump()

    trail = len(map_.model.state.value.main.points)
    robots_ok()  # nothing changed
    robots_ok(name="Bravo two")  # another robot's name: Alpha's widgets do not care
    assert {title: (h.model, h.view) for title, h in hosted.items()} == before
    assert note.view.edit.text() == "half typed"
    assert len(map_.model.state.value.main.points) >= trail  # the trail goes on
    # Bravo becomes view-only: every widget runs on ports that know it (the form is rebuilt)
    robots_ok(view_only=True)
    qtbot.waitUntil(lambda: hosted["Battery"].model is not before["Battery"][0], timeout=TIMEOUT_MS)
