"""Changing a placed widget: Configure's Field chooser rebinding a running widget on the embedded robot
(undoable), the Configure form's look (labels centred on their fields, padded number editors), and the
upper limit of a pinch or corner resize.
"""

from __future__ import annotations

import re

import pytest
from app_helpers import Pinch, window_session
from qtpy import QtCore, QtWidgets
from qtpy.QtTest import QTest

from rcon_core.app.choosers import FieldChooser
from rcon_core.app.draft import Draft, Target
from rcon_core.app.main_window import MainWindow
from rcon_core.app.settings_form import TEXT_INSET
from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import Role

pytest.importorskip("rcon_widgets_std")

pytestmark = pytest.mark.usefixtures("qapp")
NUMBER = re.compile(r"-?\d+(?:\.\d+)?")


@pytest.fixture
def window(qtbot, tmp_path, plugins, sim_thread):
    yield from window_session(qtbot, tmp_path / "config", plugins, url=sim_thread.url,
                              types=TypeRegistry.standard(), wait_connected=True, topics=("/battery",))


@pytest.fixture
def offline(qtbot, tmp_path, plugins):
    yield from window_session(qtbot, tmp_path / "config", plugins, types=TypeRegistry.standard())


def place_label(window: MainWindow, topic: str, type_name: str) -> str:
    """Pathway 1 (topic -> show it -> Label), placed with the field the panel proposes; the widget's id."""
    panel = window.add_panel
    panel.start_from_topic(topic, type_name)
    panel.choose_role(Role.SUBSCRIBE)
    kinds = [panel.candidates.item(i).data(QtCore.Qt.ItemDataRole.UserRole).spec.kind
             for i in range(panel.candidates.count())]
    panel.choose_candidate(kinds.index("std.label"))
    QTest.mouseClick(panel.place_button, QtCore.Qt.MouseButton.LeftButton)
    return window.controller.canvas.widgets[-1].id


def open_configure(window: MainWindow, qtbot, widget_id: str) -> QtWidgets.QDialog:
    """Long-press menu -> Configure…, as a person would."""
    frame = window.controller.surface.frames[widget_id]
    menu = frame.request_menu(frame.mapToGlobal(QtCore.QPoint(10, 10)))
    [configure] = [a for a in menu.actions() if a.objectName() == "configure"]
    configure.trigger()
    menu.close()
    dialog = window.configurer.dialog
    qtbot.waitUntil(dialog.isVisible, timeout=5_000)
    return dialog


def shown_number(window: MainWindow, qtbot, widget_id: str) -> float:
    """The number the running Label shows (its value text), once it shows one."""
    hosted = window.host.hosted[widget_id]
    qtbot.waitUntil(lambda: hosted.view is not None and NUMBER.search(hosted.view.value.text()) is not None,
                    timeout=10_000)
    return float(NUMBER.search(hosted.view.value.text()).group())


def binding_of(window: MainWindow, widget_id: str):
    return window.controller.canvas.widget(widget_id).binding


# ------------------------------------------------------------------------------------- the field
def test_configure_rebinds_a_running_label_to_another_field_and_undo_restores_it(window, qtbot, sim_thread):
    wid = place_label(window, "/battery", "sensor_msgs/BatteryState")
    assert binding_of(window, wid).field_paths == ("percentage",)
    percent = shown_number(window, qtbot, wid)
    assert 0.0 <= percent <= 100.0  # the battery's 0..1 charge, shown in % (issue 21.12)
    first_model = window.host.hosted[wid].model

    dialog = open_configure(window, qtbot, wid)
    field = dialog.findChild(FieldChooser, "configureField")
    assert field.isVisible() and field.current_path() == "percentage"
    entries = [field.itemText(i) for i in range(field.count())]
    assert entries[0] == "percentage · float32" and "voltage · float32" in entries
    # the same fields the add panel offers a Label on BatteryState
    [label] = [c for c in window.rank_widgets("sensor_msgs/BatteryState", Role.SUBSCRIBE) if c.spec.kind == "std.label"]
    assert tuple(field.paths()) == label.choices
    with pytest.raises(ValueError, match="not a field"):
        field.choose("no_such_field")
    field.choose("voltage")
    title = dialog.findChild(QtWidgets.QLineEdit, "configureTitle")
    title.setText("Volts")
    QTest.mouseClick(dialog.findChild(QtWidgets.QDialogButtonBox).button(
        QtWidgets.QDialogButtonBox.StandardButton.Ok), QtCore.Qt.MouseButton.LeftButton)

    binding = binding_of(window, wid)
    assert binding.field_paths == ("voltage",) and binding.name == "/battery" and binding.role is Role.SUBSCRIBE
    qtbot.waitUntil(lambda: window.host.hosted[wid].model is not first_model, timeout=10_000)  # rebuilt
    qtbot.waitUntil(lambda: not window.host.hosted[wid].view.value.text().endswith("%"),
                    timeout=10_000)  # volts, not the charge in %
    assert shown_number(window, qtbot, wid) == pytest.approx(sim_thread.robot.voltage, abs=0.5)
    assert window.controller.canvas.widget(wid).title == "Volts"

    # Ctrl+Z right after OK (the keyboard is back on the window): one undo step brings back field and title
    QtWidgets.QApplication.processEvents()
    assert QtWidgets.QApplication.activeWindow() is window
    QTest.keyClick(window, QtCore.Qt.Key.Key_Z, QtCore.Qt.KeyboardModifier.ControlModifier)
    assert binding_of(window, wid).field_paths == ("percentage",)
    assert window.controller.canvas.widget(wid).title == "battery · percentage"  # the title it got from its binding
    qtbot.waitUntil(lambda: window.host.hosted[wid].view is not None
                    and window.host.hosted[wid].view.value.text().endswith("%"), timeout=10_000)
    assert window.host.hosted[wid].model.binding.field_paths == ("percentage",)


def test_cancel_keeps_the_field_and_a_single_field_offers_no_choice(window, qtbot):
    wid = place_label(window, "/battery", "sensor_msgs/BatteryState")
    dialog = open_configure(window, qtbot, wid)
    dialog.findChild(FieldChooser, "configureField").choose("temperature")
    dialog.reject()
    assert binding_of(window, wid).field_paths == ("percentage",)

    wid = place_label(window, "/speed_limit", "std_msgs/Float64")  # std_msgs/Float64: data only
    dialog = open_configure(window, qtbot, wid)
    field = dialog.findChild(FieldChooser, "configureField")
    assert not field.isVisible() and field.paths() == ["data"]
    dialog.accept()
    assert binding_of(window, wid).field_paths == ("data",)


# ------------------------------------------------------------------------------------- the form's look
def test_configure_labels_are_centred_on_their_fields_and_numbers_are_padded(window, qtbot):
    wid = place_label(window, "/battery", "sensor_msgs/BatteryState")
    dialog = open_configure(window, qtbot, wid)
    QtWidgets.QApplication.processEvents()
    labels = [lbl for lbl in dialog.findChildren(QtWidgets.QLabel) if lbl.buddy() is not None and lbl.isVisible()]
    assert {lbl.text() for lbl in labels} >= {"Field", "Title", "Decimals", "Scale", "Stale after (s)"}
    for lbl in labels:
        field = lbl.buddy()
        label_mid = lbl.mapTo(dialog, lbl.rect().center()).y()
        field_mid = field.mapTo(dialog, field.rect().center()).y()
        text_mid = label_mid - lbl.height() // 2 + lbl.contentsRect().center().y()
        assert abs(text_mid - field_mid) <= 2, (lbl.text(), text_mid, field_mid)
    # label column shared by the dialog's own rows and the settings form
    xs = {lbl.buddy().mapTo(dialog, QtCore.QPoint(0, 0)).x() for lbl in labels}
    assert len(xs) == 1, xs
    # a number's text starts as far in from the border as a line edit's
    spin = dialog.findChild(QtWidgets.QAbstractSpinBox, "setting_decimals")
    inner = spin.findChild(QtWidgets.QLineEdit)
    assert inner.x() + inner.textMargins().left() >= TEXT_INSET


# ------------------------------------------------------------------------------------- resize limits
def placed_frame(window: MainWindow):
    spec = window.plugins.widget("std.label")
    draft = Draft(spec, Role.SUBSCRIBE, Target("/battery", "sensor_msgs/BatteryState", ("percentage",)),
                  spec.make_settings({}), "Label")
    inst = window.controller.add_draft(draft, QtCore.QPoint(32, 32))
    return inst, window.controller.surface.frames[inst.id]


def test_a_20x_pinch_stops_at_the_visible_canvas(offline, qtbot):
    inst, frame = placed_frame(offline)
    start = frame.geometry()
    view = offline.controller.surface.scroll_area.viewport().size()
    for state, scale in ((QtCore.Qt.GestureState.GestureStarted, 1.0),
                         (QtCore.Qt.GestureState.GestureUpdated, 8.0),
                         (QtCore.Qt.GestureState.GestureFinished, 20.0)):
        frame.pinch_gesture(Pinch(state, scale))
    cap = frame.max_size()
    assert cap.width() <= view.width() and cap.height() <= view.height()
    saved = offline.controller.canvas.widget(inst.id).geometry
    assert saved.w <= cap.width() and saved.h <= cap.height()
    assert saved.w > start.width() * 2  # it did grow, up to the limit
    assert saved.w == cap.width() or saved.h == cap.height()  # one side reached the visible size
    assert saved.w / saved.h == pytest.approx(start.width() / start.height(), rel=0.15)  # aspect kept
    assert frame.geometry().x() >= 0 and frame.geometry().y() >= 0


def test_a_corner_drag_stops_at_the_visible_canvas_and_never_below_the_minimum(offline, qtbot):
    _inst, frame = placed_frame(offline)
    start = frame.geometry()
    frame.resize_corner("br", start, QtCore.QPoint(5000, 5000))
    cap = frame.max_size()
    assert (frame.width(), frame.height()) == (cap.width(), cap.height())
    assert frame.geometry().topLeft() == start.topLeft()  # the opposite corner stayed
    big = frame.geometry()
    frame.resize_corner("tl", big, QtCore.QPoint(5000, 5000))  # past the opposite corner
    low = frame.min_size()
    assert frame.width() >= low.width() and frame.height() >= low.height()
    assert frame.geometry().bottomRight() == big.bottomRight()
    # a window smaller than the widget: a resize never makes it jump to the smaller limit
    offline.resize(700, 500)
    QtWidgets.QApplication.processEvents()
    assert frame.max_size().width() < big.width()
    frame.resize_corner("br", big, QtCore.QPoint(-16, 0))
    assert frame.width() == big.width() - 16 and frame.height() == big.height()
    frame.resize_corner("br", big, QtCore.QPoint(400, 400))
    assert (frame.width(), frame.height()) == (big.width(), big.height())  # grows no further
