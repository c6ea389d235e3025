"""Teleop pads offscreen with a real bridge thread and the sim: two fingers on two pads at once, zero on
lift, on focus loss and when hidden. (The README's pictures: docs/make_screenshots.py.)

The pads' publish timers run on a ``ManualClock`` (moved on the bridge thread): while a test waits for a
stream the clock moves a period per poll (:func:`wait`), and before asserting "nothing more" :func:`settle`
runs it half a second forward and waits for a marker sent after it through the same client."""

import time

import pytest
from qtpy import QtCore, QtGui, QtWidgets
from qtpy.QtTest import QTest
from rcon_widgets_sensors.teleop import TeleopModel, TeleopSettings
from rcon_widgets_sensors.teleop_view import TeleopView

from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import Binding, SharedResources, WidgetContext
from rcon_core.testing import ManualClock, flushed_sync, until_sync


class Robot:
    """/cmd_vel as the sim receives it, with receipt times."""

    def __init__(self, sim):
        self.got = []
        sim.run_sync(lambda: sim.subscribe_internal("/cmd_vel", "geometry_msgs/Twist", "/rcon_test_rx",
                                                    lambda m: self.got.append((time.monotonic(), m))))

    def since(self, t):
        return [m for when, m in list(self.got) if when >= t]


def zero(m):
    return not any(m["linear"].values()) and not any(m["angular"].values())


#: the clock the pads' publish timers run on (moved on the bridge thread only)
CLOCK = ManualClock()


def make_pad(threaded_client, settings, node, shared=None):
    """A pad and its view; pads given one ``shared`` store are on one robot link (as in the canvas runtime)."""
    bt, client = threaded_client
    context = WidgetContext(link=id(client), resources=shared) if shared is not None else None
    model = TeleopModel(settings, Binding("/cmd_vel", "geometry_msgs/Twist", "publish"), client.node(node),
                        types=TypeRegistry.standard(), dispatch=bt.call, context=context, ticker_clock=CLOCK)
    bt.call(model.start).result(5)
    view = TeleopView(model)
    return model, view


def wait(qtbot, bt, pred, timeout=10.0):
    """Wait for ``pred`` while the pads' clock moves one 20 Hz period per poll (a held pad keeps sending)."""
    until_sync(lambda: bt.call(CLOCK.advance, 0.05).result(5) or pred(), timeout, qtbot=qtbot)


def settle(qtbot, threaded_client, sim):
    """Before asserting "nothing more": half a second of the pads' timers, then a marker through the same
    client reaching the robot (what the pads sent before it has arrived)."""
    bt, client = threaded_client
    bt.call(CLOCK.advance, 0.5).result(5)
    flushed_sync(bt, client, sim, qtbot=qtbot)


@pytest.fixture
def two_pads(qtbot, threaded_client):
    shared = SharedResources()
    left_m, left = make_pad(threaded_client, TeleopSettings(horizontal="", vertical="linear.x", dead_zone=0), "left",
                            shared)
    right_m, right = make_pad(threaded_client, TeleopSettings(horizontal="-angular.z", vertical="", dead_zone=0),
                              "right", shared)
    win = QtWidgets.QWidget()
    lay = QtWidgets.QHBoxLayout(win)
    lay.addWidget(left)
    lay.addWidget(right)
    qtbot.addWidget(win)
    win.resize(640, 300)
    win.show()
    qtbot.waitExposed(win)
    yield win, left, right
    bt = threaded_client[0]
    for m in (left_m, right_m):
        bt.call(m.stop).result(5)


def centre(view):
    c, r = view.pad()
    return c.toPoint(), r


def test_two_fingers_drive_two_pads_at_once(qtbot, sim_thread, threaded_client, two_pads):
    robot, bt = Robot(sim_thread), threaded_client[0]
    win, left, right = two_pads
    dev = QTest.createTouchDevice()
    lc, lr = centre(left)
    rc, rr = centre(right)
    up = lc - QtCore.QPoint(0, int(lr * 0.8))  # left thumb up: forward
    side = rc + QtCore.QPoint(int(rr * 0.5), 0)  # right thumb right: turn right
    QTest.touchEvent(win, dev).press(0, left.mapTo(win, lc), win).press(1, right.mapTo(win, rc), win).commit()
    QTest.touchEvent(win, dev).move(0, left.mapTo(win, up), win).move(1, right.mapTo(win, side), win).commit()
    wait(qtbot, bt, lambda: any(m["linear"]["x"] > 0.7 and m["angular"]["z"] < -0.4 for m in robot.since(0)))
    assert left.model.active and right.model.active
    left.refresh(left.model.state)
    right.refresh(right.model.state)
    t = time.monotonic()
    QTest.touchEvent(win, dev).release(0, left.mapTo(win, up), win).stationary(1).commit()
    wait(qtbot, bt, lambda: any(m["linear"]["x"] == 0 and m["angular"]["z"] < -0.4 for m in robot.since(t)))
    assert not left.model.active and right.model.active  # the right thumb still turns
    t2 = time.monotonic()
    QTest.touchEvent(win, dev).release(1, right.mapTo(win, side), win).commit()
    wait(qtbot, bt, lambda: any(zero(m) for m in robot.since(t2)))
    settle(qtbot, threaded_client, sim_thread)
    after = robot.since(t2)
    assert zero(after[-1]) and sum(zero(m) for m in after) == 1


def test_focus_loss_and_hiding_send_the_zero(qtbot, sim_thread, threaded_client, two_pads):
    robot, bt = Robot(sim_thread), threaded_client[0]
    win, left, _right = two_pads
    lc, lr = centre(left)
    QTest.mousePress(left, QtCore.Qt.MouseButton.LeftButton, pos=lc)
    QTest.mouseMove(left, lc - QtCore.QPoint(0, int(lr * 0.9)))
    wait(qtbot, bt, lambda: any(m["linear"]["x"] > 0.8 for m in robot.since(0)))
    t = time.monotonic()
    QtWidgets.QApplication.sendEvent(
        left, QtGui.QFocusEvent(QtCore.QEvent.Type.FocusOut, QtCore.Qt.FocusReason.ActiveWindowFocusReason))
    wait(qtbot, bt, lambda: any(zero(m) for m in robot.since(t)))
    assert not left.model.active
    QTest.mouseMove(left, lc - QtCore.QPoint(0, int(lr * 0.5)))  # still dragging: ignored (no longer held)
    settle(qtbot, threaded_client, sim_thread)
    assert not any(m["linear"]["x"] > 0 for m in robot.since(t))
    QTest.mouseRelease(left, QtCore.Qt.MouseButton.LeftButton, pos=lc)
    # again, and this time the pad is hidden (its canvas goes to the background)
    QTest.mousePress(left, QtCore.Qt.MouseButton.LeftButton, pos=lc)
    QTest.mouseMove(left, lc - QtCore.QPoint(0, int(lr * 0.9)))
    t2 = time.monotonic()
    wait(qtbot, bt, lambda: any(m["linear"]["x"] > 0.8 for m in robot.since(t2)))
    t3 = time.monotonic()
    win.hide()
    wait(qtbot, bt, lambda: any(zero(m) for m in robot.since(t3)))
    settle(qtbot, threaded_client, sim_thread)
    assert zero(robot.since(t3)[-1]) and not left.model.active


def offline_pad(dry_run: bool | None):
    """A pad run as the app runs an unconnected widget or a control's preview: on the offline client,
    link down; ``dry_run`` as the app would set it for the add panel's preview (None: not set at all)."""
    from rcon_core.app.link import OFFLINE

    model = TeleopModel(TeleopSettings(), Binding("/cmd_vel", "geometry_msgs/Twist", "publish"),
                        OFFLINE.node("preview-pad"), types=TypeRegistry.standard())
    if dry_run is not None:
        model.dry_run = dry_run
    model.set_link(False)
    model.start()
    return model, TeleopView(model)


def test_preview_pad_says_it_is_a_preview_not_link_down(qtbot):
    model, view = offline_pad(dry_run=True)
    qtbot.addWidget(view)
    view.resize(300, 300)
    view.show()
    view.refresh(model.state)
    assert model.state.link_down and view.status_text() == "preview: not driving the robot"
    c, _r = centre(view)
    QTest.mousePress(view, QtCore.Qt.MouseButton.LeftButton, QtCore.Qt.KeyboardModifier.NoModifier, c + QtCore.QPoint(0, -60))
    view.refresh(model.state)
    assert view.status_text() == "preview: not driving the robot" and not model.active
    QTest.mouseRelease(view, QtCore.Qt.MouseButton.LeftButton, QtCore.Qt.KeyboardModifier.NoModifier, c)
    model.stop()


@pytest.mark.parametrize("dry_run", [None, False])
def test_offline_pad_on_the_canvas_still_says_link_down(qtbot, dry_run):
    model, view = offline_pad(dry_run)
    qtbot.addWidget(view)
    view.refresh(model.state)
    assert view.status_text() == "link down: stopped"
    model.stop()


def test_a_narrow_pad_shows_the_start_of_its_status_line_whole_never_both_ends_cut(qtbot):
    """A pad narrower than its status line (a fleet tile's): the painted line keeps its beginning and ends in
    "…" within the pad, instead of being centred and cut at both edges; a wide pad shows it whole."""
    model, view = offline_pad(dry_run=True)
    qtbot.addWidget(view)
    view.show()
    full = view.status_text()
    fm = QtGui.QFontMetrics(view._small_font())  # the pad's small text, as paintEvent sets it
    narrow = max(view.minimumWidth(), fm.horizontalAdvance(full) * 2 // 3)
    view.resize(narrow, 160)
    view.grab()  # paints it
    shown = view.status_shown
    assert fm.horizontalAdvance(full) > view.width() - 8, "the test needs a line that does not fit"
    assert shown != full and shown.endswith("…") and full.startswith(shown[:-1])
    assert fm.horizontalAdvance(shown) <= view.width() - 8
    view.resize(fm.horizontalAdvance(full) + 40, 300)
    view.grab()
    assert view.status_shown == full
    model.stop()


def test_at_a_large_text_size_the_axis_words_go_on_two_rows_whole_and_above_the_pad(qtbot):
    """200 % text on a tablet's pad (about 260 px wide): the words had been cut to "↑ forw…" and "turn ri…"
    in a row 16 px tall that clipped their tops. Now they go on two rows, each whole and as tall as the
    text, and the pad's disc starts below them; at the normal size they share one row as before."""
    model, view = offline_pad(dry_run=True)
    qtbot.addWidget(view)
    view.resize(260, 360)
    view.show()
    view.grab()
    assert view.label_rows() == 1 and view.axis_labels[0] == "↑ forward" and view.axis_labels[2] == "turn right →"
    font = QtGui.QFont(view.font())
    font.setPixelSize(28)  # the theme's font at 200 % text
    view.setFont(font)
    fm = QtGui.QFontMetricsF(view._small_font())
    words = fm.horizontalAdvance("↑ forward"), fm.horizontalAdvance("turn right →")
    # as in the app's 200 % screenshot: too narrow for both words side by side (each in its half of the
    # row), wide enough for each alone
    view.resize(int(2 * max(words)) + 8, 360)
    assert max(words) + 8 < view.width()
    view.grab()
    line = QtGui.QFontMetrics(view._small_font()).height()
    assert line > 16  # taller than the old fixed row
    assert view.label_rows() == 2
    v_word, _v_fine, h_word, _h_fine = view.axis_labels
    assert (v_word, h_word) == ("↑ forward", "turn right →")  # whole, no "…"
    assert fm.horizontalAdvance(v_word) <= view.width() - 8 and fm.horizontalAdvance(h_word) <= view.width() - 8
    c, r = view.pad()
    assert c.y() - r >= 2 * line  # the disc starts under the second row
    painted = view.grab().toImage()
    # the second row is painted: dark text pixels in the right half between line and 2 * line
    dpr = painted.devicePixelRatio()
    dark = sum(1 for x in range(view.width() // 2, view.width() - 4) for y in range(line + 2, 2 * line - 2)
               if QtGui.QColor(painted.pixel(int(x * dpr), int(y * dpr))).lightness() < 100)
    assert dark > 20
    model.stop()


def test_the_small_print_beside_the_axis_words_follows_the_text_size(qtbot):
    """The field names ("linear.x") are 0.65 times the axis words at every text size; they had stayed at a
    6 pt floor (the theme's font is in pixels, its point size -1), a speck at 200 % text."""
    model, view = offline_pad(dry_run=True)
    qtbot.addWidget(view)
    for px in (14, 28):
        font = QtGui.QFont(view.font())
        font.setPixelSize(px)
        view.setFont(font)
        words, fine = view._small_font().pixelSize(), view._fine_font().pixelSize()
        assert fine == max(8, round(words * 0.65)), (px, words, fine)
    assert view._fine_font().pixelSize() >= 14  # at 28 px: 22 px words, 14 px small print (6 pt is 8 px)
    model.stop()


def test_a_status_line_too_long_for_the_pad_drops_its_closing_remark_before_cutting_words(qtbot):
    """A fleet tile's pad showed "touch to drive ≤ 1.5 m/s (s…"; now the remark in brackets goes first
    ("touch to drive ≤ 1.5 m/s"), then (a pad at 200 % text) all but the limit ("≤ 1.5 m/s"), and only a
    line still too long is cut with "…"."""
    from rcon_widgets_sensors.teleop_view import fit_status

    view = QtWidgets.QWidget()
    qtbot.addWidget(view)
    fm = QtGui.QFontMetrics(view.font())
    full = "touch to drive ≤ 1.5 m/s (safety envelope)"
    short = "touch to drive ≤ 1.5 m/s"
    assert fit_status(full, fm, fm.horizontalAdvance(full) + 2) == full  # fits: whole
    assert fit_status(full, fm, fm.horizontalAdvance(short) + 2) == short  # the remark dropped, no "…"
    limit = "≤ 1.5 m/s"
    assert fit_status(full, fm, fm.horizontalAdvance(limit) + 2) == limit
    idle = "idle · touch to drive (10 Hz)"  # no limit: its beginning and "…"
    cut = fit_status(idle, fm, fm.horizontalAdvance("idle · touch") + 2)
    assert cut.endswith("…") and idle.startswith(cut[:-1]) and "(" not in cut
    assert fm.horizontalAdvance(cut) <= fm.horizontalAdvance("idle · touch") + 2
    tiny = fit_status(full, fm, fm.horizontalAdvance(limit) // 2)  # not even the limit fits
    assert tiny.endswith("…") and short.startswith(tiny[:-1])
    # a remark in the middle stays (the reason a pad stopped): only its end is cut
    stopped = "stopped (lost focus): lift your finger"
    assert fit_status(stopped, fm, fm.horizontalAdvance(stopped) - 10).startswith("stopped (lost")
