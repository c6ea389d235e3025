"""What widgets show and send is true, on the real window against the sim: a typed ``nan`` is refused
with a reason (not sent as ``null``); a latched map that delivered once is not called STALE; the demo's
speed-limit slider does not show a limit nobody set."""

from __future__ import annotations

import pytest
from app_helpers import choose_kind, open_window, snap, tap, tap_topic, window_session
from qtpy import QtWidgets
from qtpy.QtCore import Qt
from qtpy.QtTest import QTest

from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import Role

pytestmark = pytest.mark.usefixtures("qapp")
pytest.importorskip("rcon_widgets_std")


@pytest.fixture(params=[(1280, 800), (1024, 600)], ids=["1280x800", "1024x600"])
def window(request, qtbot, tmp_path, sim_thread, plugins):
    yield from window_session(qtbot, tmp_path / "config", plugins, url=sim_thread.url, size=request.param,
                              types=TypeRegistry.standard(), wait_connected=True, topics=("/speed_limit",))


def place(window, qtbot, topic: str, role: Role, kind: str, settings: dict | None = None):
    """Add a widget from the topic list with the add panel's Place button, ``settings`` set in its form
    (a tap on a check box, typing into a number box); returns (instance, hosted), running in Operate mode."""
    tap_topic(window, topic)
    panel = choose_kind(window, role, kind)
    for name, value in (settings or {}).items():
        [editor] = [e for e in panel.settings_page.findChildren(QtWidgets.QWidget, f"setting_{name}")]
        panel.settings_scroll.ensureWidgetVisible(editor)
        QtWidgets.QApplication.processEvents()
        if isinstance(editor, QtWidgets.QCheckBox):
            if editor.isChecked() != value:
                editor.click()
        else:
            line = editor.findChild(QtWidgets.QLineEdit)
            tap(line)
            QTest.keyClick(line, Qt.Key.Key_A, Qt.KeyboardModifier.ControlModifier)
            QTest.keyClicks(line, str(value))
            QTest.keyClick(line, Qt.Key.Key_Tab)
            assert editor.value() == value
    tap(panel.place_button)
    inst = window.controller.canvas.widgets[-1]
    tap(window.lock_button)
    hosted = window.host.hosted[inst.id]
    qtbot.waitUntil(lambda: hosted.view is not None and hosted.model is not None and hosted.model.running,
                    timeout=10_000)
    qtbot.waitUntil(hosted.view.isVisible, timeout=5_000)
    return inst, hosted


def type_and_send(view, text: str) -> None:
    view.edit.clear()
    tap(view.edit)
    QTest.keyClicks(view.edit, text)
    tap(view.button)


def test_a_typed_nan_is_refused_with_a_reason_and_nothing_is_sent(window, qtbot, sim_thread):
    _inst, hosted = place(window, qtbot, "/speed_limit", Role.PUBLISH, "std.textfield")
    view = hosted.view
    for text, named in (("nan", "nan"), ("inf", "inf"), ("-.inf", "-inf"), ("null", "null")):
        type_and_send(view, text)
        qtbot.waitUntil(lambda: "finite" in view.status.text(), timeout=5_000)
        assert view.status.text().startswith(f"not sent: data: {named} is not a finite number")
    snap(window, f"textfield-nan-refused-{window.width()}")
    type_and_send(view, "1.25")
    got = sim_thread.wait_for_published_sync("/speed_limit", timeout=10)
    assert got == {"data": 1.25}
    assert all(m["data"] is not None for m in sim_thread.published("/speed_limit"))  # no null went out


def test_nan_goes_out_only_where_the_widget_allows_it(window, qtbot, sim_thread):
    _inst, hosted = place(window, qtbot, "/speed_limit", Role.PUBLISH, "std.textfield",
                          {"allow_nonfinite": True})
    assert hosted.model.settings.allow_nonfinite
    type_and_send(hosted.view, "nan")
    sim_thread.wait_for_published_sync("/speed_limit", timeout=10)  # sent, as the operator asked
    assert "finite" not in hosted.view.status.text()


def test_a_latched_map_that_delivered_once_is_not_called_stale(window, qtbot, sim_thread):
    inst, hosted = place(window, qtbot, "/map", Role.SUBSCRIBE, "sensors.image", {"stale_after": 0.5})
    assert hosted.model.settings.stale_after == 0.5
    qtbot.waitUntil(lambda: hosted.model.state.count >= 1 and hosted.view.frame is not None, timeout=10_000)
    qtbot.wait(1500)  # three times the widget's stale_after, and the view's own 1 s
    state = hosted.model.state
    assert state.count == 1 and state.age > 1.0  # one map, long ago: the sim sends it once (latched)
    assert state.static and not state.stale
    window.host.refresh()
    snap(window, f"latched-map-not-stale-{window.width()}")
    badge = hosted.frame.badge
    assert badge.kind != "stale" and "STALE" not in badge.status
    assert hosted.view.stale_for() is None  # no "STALE · no new frame" over the map either


@pytest.mark.parametrize("size", [(1280, 800), (1024, 600)])
def test_the_demo_speed_limit_reads_not_set_until_a_limit_is_sent(qtbot, tmp_path, sim_thread, plugins,
                                                                   monkeypatch, size):
    from rcon_widgets_std import slider

    from rcon_core.app.demo import demo_workspace

    monkeypatch.setattr(slider, "_LAST_VALUES", {})  # nothing sent in this session (other tests send some)
    window = open_window(qtbot, tmp_path / "config", plugins, url=sim_thread.url, size=size,
                         demo=lambda: demo_workspace(plugins), wait_connected=True)
    try:
        [inst] = [w for w in window.controller.canvas.widgets if w.title == "Speed limit"]
        hosted = window.host.hosted[inst.id]
        qtbot.waitUntil(lambda: hosted.view is not None and hosted.model.running, timeout=10_000)
        window.controller.surface.reveal(hosted.frame.geometry())
        qtbot.waitUntil(lambda: hosted.view.value.isVisible() and hosted.view.value.text() == "not set",
                        timeout=5_000)
        assert sim_thread.robot.speed_limit is None  # the robot has none: a number here would be a lie
        # a round trip on the link: whatever the robot sent before its answer has been received
        link = window.link
        assert link.thread.run(link.client.call_service("/rosapi/get_time", {})).result(10)
        window.host.refresh()
        assert hosted.view.value.text() == "not set"
        snap(window, f"speed-limit-not-set-{size[0]}")
        track = hosted.view.slider
        tap(track, track.rect().center())  # the middle of 0..1.5 m/s (the demo robot's safety envelope)
        qtbot.waitUntil(lambda: sim_thread.robot.speed_limit is not None, timeout=10_000)
        limit = sim_thread.robot.speed_limit
        assert 0.5 < limit < 1.0
        window.host.refresh()
        qtbot.waitUntil(lambda: hosted.view.value.text() == f"{limit:.1f} m/s", timeout=5_000)
        snap(window, f"speed-limit-set-{size[0]}")
    finally:
        window.shutdown()
