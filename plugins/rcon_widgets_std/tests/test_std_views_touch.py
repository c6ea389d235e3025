"""View behaviour a touch operator relies on: tapping a slider's track, seeing a button's or switch's
answer on the control itself, default sizes that fit what the widget shows."""

from __future__ import annotations

import pytest
from qtpy import QtCore, QtWidgets
from rcon_widgets_std import view_common
from rcon_widgets_std.button import ButtonModel, ButtonSettings, CallStatus
from rcon_widgets_std.button_view import ButtonView
from rcon_widgets_std.compound import ChildSpec, CompoundModel, CompoundSettings
from rcon_widgets_std.compound_view import CompoundView
from rcon_widgets_std.label import LabelModel, LabelSettings
from rcon_widgets_std.label_view import LabelView
from rcon_widgets_std.plugin import specs
from rcon_widgets_std.slider import SliderModel, SliderSettings
from rcon_widgets_std.slider_view import SliderView
from rcon_widgets_std.switch import SwitchModel, SwitchSettings, SwitchValue
from rcon_widgets_std.switch_view import SwitchView
from std_qtkit import LiveBridge
from std_testkit import STD, build

from rcon_core.app.geometry import on_grid
from rcon_core.app.theme import stylesheet
from rcon_core.app.widget_frame import WidgetFrame, frame_min_size
from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import Binding, WidgetContext
from rcon_core.testing import flushed_sync, qt_flushed, until_sync

SPECS = {spec.kind: spec for spec in specs()}


def placed(qtbot, kind: str, view: QtWidgets.QWidget, title: str, editable: bool = False,
           size: tuple[int, int] | None = None) -> WidgetFrame:
    """``view`` in the app's frame and theme, shown: at the size the app places ``kind`` with (its default
    size, on the grid, at least the frame's minimum), or at ``size`` exactly (a frame squeezed smaller)."""
    canvas = QtWidgets.QWidget()  # a canvas: the frame is a child, sized like the app sizes it
    canvas.setStyleSheet(stylesheet(touch=48))
    canvas.resize(800, 600)
    frame = WidgetFrame("w-test", title, canvas)
    frame.set_view(view)
    frame.set_editable(editable)
    if size is None:
        w, h = (int(v) for v in SPECS[kind].default_size)
        size = on_grid(QtCore.QRect(0, 0, w, h), frame_min_size()).size().toTuple()
    frame.setGeometry(0, 0, *size)
    qtbot.addWidget(canvas)
    canvas.show()
    qtbot.waitExposed(canvas)
    QtWidgets.QApplication.processEvents()
    frame.held_by = canvas  # the test keeps the frame, the frame keeps its canvas alive
    return frame


def _caption_room(view: QtWidgets.QWidget, main: QtWidgets.QWidget, caption: QtWidgets.QWidget) -> int:
    """Pixels to spare in ``view`` below ``main`` at its minimum and ``caption`` (negative: no room)."""
    m = view.layout().contentsMargins()
    need = main.minimumSizeHint().height() + view.layout().spacing() + caption.sizeHint().height()
    return view.height() - need - m.top() - m.bottom()


@pytest.fixture
def live(sim_url):
    bridge = LiveBridge(sim_url)
    yield bridge
    bridge.close()


def _slider(live, mode: str, topic: str) -> SliderModel:
    m = SliderModel(SliderSettings(minimum=0, maximum=2, step=0.1, publish_mode=mode, follow_topic=False),
                    build(SliderModel, None, topic, "std_msgs/Float64", "publish", "data").binding,
                    live.node(f"slider-{mode}"), types=TypeRegistry.standard(), dispatch=live.thread.call)
    live.thread.call(m.start).result(5)
    return m


def _track_point(view: SliderView, fraction: float) -> QtCore.QPoint:
    """A point on the slider's track at ``fraction`` of its length (away from the handle at 0)."""
    s = view.slider
    opt = QtWidgets.QStyleOptionSlider()
    s.initStyleOption(opt)
    cc, style = QtWidgets.QStyle.ComplexControl.CC_Slider, s.style()
    groove = style.subControlRect(cc, opt, QtWidgets.QStyle.SubControl.SC_SliderGroove, s)
    handle = style.subControlRect(cc, opt, QtWidgets.QStyle.SubControl.SC_SliderHandle, s)
    span = groove.width() - handle.width()
    return QtCore.QPoint(round(groove.x() + handle.width() / 2 + span * fraction), s.height() // 2)


def _sent(sim_thread, topic: str, value: float) -> bool:
    return any(abs(msg["data"] - value) < 1e-9 for msg in sim_thread.published(topic))


def test_tapping_the_slider_track_jumps_there_and_publishes_on_release(qtbot, live, sim_thread):
    m = _slider(live, "release", "/rcon_test/tap_release")
    view = SliderView(m)
    qtbot.addWidget(view)
    view.resize(300, 120)
    view.show()
    qtbot.waitExposed(view)
    left = QtCore.Qt.MouseButton.LeftButton
    qtbot.mousePress(view.slider, left, pos=_track_point(view, 0.8))
    assert view.slider.value() == 16, "a tap moves to where it lands, not one page step"
    assert view.slider.isSliderDown() and view.value.text() == "1.60"
    qt_flushed(qtbot)  # what the press set going has run, and a marker sent after it reached the robot
    flushed_sync(live.thread, live.client, sim_thread, qtbot=qtbot)
    assert not _sent(sim_thread, "/rcon_test/tap_release", 1.6), "on-release mode sent while the finger is down"
    qtbot.mouseRelease(view.slider, left, pos=_track_point(view, 0.8))
    until_sync(lambda: _sent(sim_thread, "/rcon_test/tap_release", 1.6),
               what="1.6 sent on release", qtbot=qtbot)
    assert not view.slider.isSliderDown()
    live.thread.call(m.stop).result(5)


def test_tapping_the_slider_track_in_continuous_mode_publishes_while_held(qtbot, live, sim_thread):
    m = _slider(live, "continuous", "/rcon_test/tap_cont")
    view = SliderView(m)
    qtbot.addWidget(view)
    view.resize(300, 120)
    view.show()
    qtbot.waitExposed(view)
    left = QtCore.Qt.MouseButton.LeftButton
    qtbot.mousePress(view.slider, left, pos=_track_point(view, 0.3))
    assert view.slider.value() == 6
    until_sync(lambda: _sent(sim_thread, "/rcon_test/tap_cont", 0.6), what="0.6 sent while held", qtbot=qtbot)
    assert view.slider.isSliderDown()
    qtbot.mouseRelease(view.slider, left, pos=_track_point(view, 0.3))
    live.thread.call(m.stop).result(5)


def test_tapping_the_slider_handle_itself_does_not_move_it(qtbot, live, sim_thread):
    m = _slider(live, "release", "/rcon_test/tap_handle")
    view = SliderView(m)
    qtbot.addWidget(view)
    view.resize(300, 120)
    view.show()
    qtbot.waitExposed(view)
    view.slider.setValue(10)
    left = QtCore.Qt.MouseButton.LeftButton
    qtbot.mousePress(view.slider, left, pos=_track_point(view, 0.5))
    qtbot.mouseRelease(view.slider, left, pos=_track_point(view, 0.5))
    assert view.slider.value() == 10
    live.thread.call(m.stop).result(5)


# -- Button and Switch: the answer on the control itself -----------------------------------------------
def test_button_face_says_calling_then_the_answer_then_its_label(qtbot, live, sim_thread, monkeypatch):
    monkeypatch.setattr(view_common, "FLASH_MS", 300)
    m = ButtonModel(ButtonSettings(text="Dock"), build(ButtonModel, None, "/dock", "std_srvs/Trigger", "call").binding,
                    live.node("button"), types=TypeRegistry.standard(), dispatch=live.thread.call)
    live.thread.call(m.start).result(5)
    view = ButtonView(m)
    frame = placed(qtbot, "std.button", view, "Dock", size=(160, 90))  # short: the reply line is hidden
    assert view.result.isHidden() and view.button.text() == "Dock"
    view.button.pressed.emit()
    pressed = m.state  # busy, unless the sim answered already (the deterministic case is below)
    view.refresh(pressed)
    if pressed.value.busy:
        assert view.button.text() == "Dock…", "the face shows the call in flight"
    until_sync(lambda: m.state.value is not None and not m.state.value.busy, what="the answer", qtbot=qtbot)
    view.refresh(m.state)
    assert view.button.text().startswith("✓ dock"), view.button.text()
    assert view_common.OK in view.button.styleSheet(), "a success is green"
    until_sync(lambda: view.button.text() == "Dock", what="the label back after the flash", qtbot=qtbot)
    assert view.button.styleSheet() == ""
    view.button.pressed.emit()  # the sim is docking (or docked) now: a second dock is refused
    until_sync(lambda: m.state.value is not None and not m.state.value.busy,
               what="the second answer", qtbot=qtbot)
    view.refresh(m.state)
    if m.state.value.phase == "failed":
        assert view.button.text().startswith("✗") and view_common.BAD in view.button.styleSheet()
    assert frame.isVisible()
    live.thread.call(m.stop).result(5)


def test_button_face_busy_then_a_long_answer_elided_and_a_rebuilt_view_does_not_flash_an_old_one(qtbot):
    m = build(ButtonModel, ButtonSettings(text="Dock"), "/dock", "std_srvs/Trigger", "call")
    view = ButtonView(m)
    frame = placed(qtbot, "std.button", view, "Dock")
    m.set_value(CallStatus("busy", "/dock"))
    view.refresh(m.state)
    assert view.button.text() == "Dock…", "the face shows the call in flight"
    m.set_value(CallStatus("failed", "/dock", "the robot is not anywhere near the docking station", 0, 0.1))
    m.set_error("/dock: the robot is not anywhere near the docking station")
    view.refresh(m.state)
    face = view.button.text()
    assert face.startswith("✗ the robot") and face.endswith("…")
    assert view.button.fontMetrics().horizontalAdvance(face) <= view.button.width()
    again = ButtonView(m)  # the canvas was switched away and back: the same old answer
    frames = [frame, placed(qtbot, "std.button", again, "Dock")]
    again.refresh(m.state)
    assert again.button.text() == "Dock" and len(frames) == 2


def test_button_and_switch_default_sizes_fit_the_reply_line(qtbot):
    button = ButtonView(build(ButtonModel, ButtonSettings(text="Dock"), "/dock", "std_srvs/Trigger", "call"))
    frames = [placed(qtbot, "std.button", button, "Dock", editable=True)]
    assert button.result.isVisible() and _caption_room(button, button.button, button.result) >= 8
    switch = SwitchView(build(SwitchModel, SwitchSettings(), "/lights/set", "std_srvs/SetBool", "call",
                              "request.data"))
    frames.append(placed(qtbot, "std.switch", switch, "Lights", editable=True))
    assert switch.reply.isVisible() and _caption_room(switch, switch.button, switch.reply) >= 8


def test_switch_flashes_the_answer_on_its_face_only_when_the_reply_line_is_hidden(qtbot, monkeypatch):
    monkeypatch.setattr(view_common, "FLASH_MS", 300)
    m = build(SwitchModel, SwitchSettings(on_text="Lights on", off_text="Lights off"), "/lights/set",
              "std_srvs/SetBool", "call", "request.data")
    short = SwitchView(m)
    frames = [placed(qtbot, "std.switch", short, "Lights", size=(208, 90))]
    roomy = SwitchView(m)
    frames.append(placed(qtbot, "std.switch", roomy, "Lights"))
    assert short.reply.isHidden() and roomy.reply.isVisible()
    m.set_value(SwitchValue(False, True, True))
    for view in (short, roomy):
        view.refresh(m.state)
        assert view.button.text() == "Lights on…"
    m.set_value(SwitchValue(True, False, None, "lights on"))
    for view in (short, roomy):
        view.refresh(m.state)
    assert short.button.text() == "✓ lights on" and view_common.OK in short.button.styleSheet()
    assert roomy.button.text() == "● Lights on" and roomy.reply.text() == "lights on"
    until_sync(lambda: short.button.text() == "● Lights on", what="the state back on the face", qtbot=qtbot)
    m.set_value(SwitchValue(True, True, False))
    short.refresh(m.state)
    m.set_value(SwitchValue(True, False, None, "interlock open"))
    m.set_error("/lights/set refused: interlock open")
    short.refresh(m.state)
    assert short.button.text() == "✗ interlock open" and view_common.BAD in short.button.styleSheet()
    assert all(f.isVisible() for f in frames)


# -- Label: its default size holds a typical title ------------------------------------------------------
@pytest.mark.parametrize("title", ["Battery voltage", "Battery percentage"])
def test_label_default_size_fits_a_typical_title(qtbot, title):
    m = build(LabelModel, LabelSettings(decimals=2, units="V"), "/battery", "sensor_msgs/BatteryState",
              "subscribe", "voltage")
    view = LabelView(m)
    frame = placed(qtbot, "std.label", view, title, editable=True)  # edit mode: the title clears the handles
    label = frame.title
    room = label.contentsRect().width() - 2 * 6  # the theme's title padding
    assert label.fontMetrics().horizontalAdvance(title) <= room, f"{title!r} cut at the default size"


# -- Compound: children never below their minimum; a default size that fits them ---------------------
def _compound(children, columns=1):
    settings = CompoundSettings(columns=columns, children=children)
    m = CompoundModel(settings, Binding("/cmd_vel", "geometry_msgs/Twist", "publish"), None,
                      types=TypeRegistry.standard(), context=WidgetContext(STD))
    m.build_children()
    return m


TWO = [ChildSpec("std.slider", "linear.x", {"minimum": -1, "maximum": 1}), ChildSpec("std.stepper", "angular.z")]
THREE = [*TWO, ChildSpec("std.textfield", "linear.y"), ChildSpec("std.slider", "linear.z")]


def _fits_without_scrolling(view: CompoundView, what: str) -> None:
    """Every child at least its minimum and all of them inside the scroll area's viewport."""
    port = view.scroll_area.viewport()
    for box in view.child_boxes:
        corner = box.mapTo(port, QtCore.QPoint(box.width(), box.height()))
        assert corner.x() <= port.width() and corner.y() <= port.height(), f"{what}: a child needs scrolling"
        need = box.minimumSizeHint()
        assert box.height() >= need.height() and box.width() >= need.width(), f"{what}: a child squeezed"


def test_compound_in_a_small_frame_keeps_children_at_their_minimum_and_scrolls(qtbot):
    view = CompoundView(_compound(TWO))
    frame = placed(qtbot, "std.compound", view, "Compound", size=(300, 250))  # the tester's frame
    for box in view.child_boxes:
        need = box.minimumSizeHint()
        assert box.height() >= need.height() and box.width() >= need.width(), "a child squeezed below its minimum"
    bar = view.scroll_area.verticalScrollBar()
    assert bar.maximum() > 0, "what does not fit scrolls"
    bar.setValue(bar.maximum())
    QtWidgets.QApplication.processEvents()
    last = view.child_boxes[-1]
    bottom = last.mapTo(view.scroll_area.viewport(), QtCore.QPoint(0, last.height()))
    assert bottom.y() <= view.scroll_area.viewport().height(), "the last child can be scrolled into view"
    assert view.button.isVisible() and frame.isVisible()


@pytest.mark.parametrize(("children", "columns"), [(TWO, 1), (TWO, 2), (THREE, 2), (THREE, 1)])
def test_compound_preferred_size_and_size_hint_show_every_child_without_scrolling(qtbot, children, columns):
    m = _compound(children, columns)
    w, h = m.settings.preferred_size()
    assert (w, h) >= SPECS["std.compound"].default_size or h > SPECS["std.compound"].default_size[1]
    view = CompoundView(m)
    frame = placed(qtbot, "std.compound", view, "Compound", size=(int(w), int(h)))
    _fits_without_scrolling(view, f"{len(children)} children in {columns} column(s) at {w}x{h}")
    hint = view.sizeHint()
    bare = CompoundView(m)  # the view alone at its own hint: nothing scrolls either
    qtbot.addWidget(bare)
    bare.setStyleSheet(stylesheet(touch=48))
    bare.show()
    QtWidgets.QApplication.processEvents()  # polished by the theme: its real hint
    bare.resize(bare.sizeHint())
    QtWidgets.QApplication.processEvents()
    _fits_without_scrolling(bare, "the view at its sizeHint")
    assert hint.height() > 200
    assert frame.isVisible()


def test_compound_preferred_size_grows_with_its_children():
    small = CompoundSettings(children=TWO[:1]).preferred_size()
    two = CompoundSettings(children=TWO).preferred_size()
    four = CompoundSettings(children=THREE).preferred_size()
    wide = CompoundSettings(children=THREE, columns=2).preferred_size()
    assert small[1] <= two[1] < four[1] and wide[0] > four[0] and wide[1] < four[1]
    assert CompoundSettings().preferred_size() == SPECS["std.compound"].default_size
