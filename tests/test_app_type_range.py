"""A slider on an int8 field set up to 500: what the field's type holds is checked against the binding where
the widget is set up, in the real window against the sim (a topic of ``std_msgs/Int8``): the add panel
does not place it (its Place button and drag handle say why), and Configure does not save it."""

from __future__ import annotations

import pytest
from app_helpers import TIMEOUT_MS, choose_kind, tap, tap_topic, window_session
from qtpy import QtWidgets

from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import Role

pytest.importorskip("rcon_widgets_std")

pytestmark = pytest.mark.usefixtures("qapp")

GEAR = "/gear"
INT8 = "a int8 holds (-128..127)"


@pytest.fixture
def window(qtbot, tmp_path, sim_thread, plugins):
    sim_thread.run_sync(lambda: sim_thread.advertise_internal(GEAR, "std_msgs/Int8", "/gearbox"))
    yield from window_session(qtbot, tmp_path / "config", plugins, url=sim_thread.url,
                              types=TypeRegistry.standard(), wait_connected=True, topics=(GEAR,))


def spin(parent: QtWidgets.QWidget, name: str) -> QtWidgets.QDoubleSpinBox:
    box = parent.findChild(QtWidgets.QDoubleSpinBox, f"setting_{name}")
    assert box is not None, name
    return box


def test_the_add_panel_does_not_place_a_slider_beyond_what_its_int8_field_holds(window, qtbot):
    tap_topic(window, GEAR)
    panel = choose_kind(window, Role.PUBLISH, "std.slider")
    assert panel.draft.binding.type == "std_msgs/Int8"
    spin(panel.form, "maximum").setValue(500)
    qtbot.waitUntil(lambda: not panel.place_button.isEnabled(), timeout=TIMEOUT_MS)
    assert f"maximum 500 is beyond what {INT8}" in panel.problems()
    assert INT8 in panel.drag_handle.toolTip() and not panel.drag_handle.isEnabled()
    assert panel.take_draft() is None and window.controller.canvas.widgets == []  # nothing placed

    spin(panel.form, "maximum").setValue(100)  # within the type: placed
    qtbot.waitUntil(panel.place_button.isEnabled, timeout=TIMEOUT_MS)
    tap(panel.place_button)
    [placed] = window.controller.canvas.widgets
    assert placed.settings["maximum"] == 100


def test_configure_does_not_save_a_slider_beyond_what_its_int8_field_holds(window, qtbot):
    tap_topic(window, GEAR)
    panel = choose_kind(window, Role.PUBLISH, "std.slider")
    spin(panel.form, "maximum").setValue(100)
    qtbot.waitUntil(panel.place_button.isEnabled, timeout=TIMEOUT_MS)
    tap(panel.place_button)
    [placed] = window.controller.canvas.widgets
    window.configurer.open(placed.id)
    dialog = window.configurer.dialog
    qtbot.waitUntil(dialog.isVisible, timeout=TIMEOUT_MS)
    spin(dialog, "minimum").setValue(-300)
    box = dialog.findChild(QtWidgets.QDialogButtonBox)
    tap(box.button(QtWidgets.QDialogButtonBox.StandardButton.Ok))
    problem = dialog.findChild(QtWidgets.QLabel, "configureProblem")
    assert dialog.isVisible() and f"minimum -300 is beyond what {INT8}" in problem.text()
    assert window.controller.canvas.widget(placed.id).settings.get("minimum", 0.0) == 0.0  # nothing saved
    dialog.reject()
