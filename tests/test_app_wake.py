"""A model's new state reaches the screen at once from any thread, not at the window's next pass over every
widget (that pass runs every ``FULL_PASS_EVERY``, for ageing): an image decoded in a worker thread, or any
value a model sets outside the bridge loop's message handling, wakes the GUI itself. And a view that fails to
show a value is the widget's own problem: the pass goes on with the others."""

from __future__ import annotations

import threading

import pytest
from app_helpers import window_session

from rcon_core.app import main_window
from rcon_core.canvas import Binding, Geometry
from rcon_core.plugins import Role

pytestmark = pytest.mark.usefixtures("qapp")
pytest.importorskip("rcon_widgets_std")


@pytest.fixture
def window(qtbot, tmp_path, sim_thread, plugins):
    yield from window_session(qtbot, tmp_path / "config", plugins, url=sim_thread.url, wait_connected=True)


def test_a_value_set_off_the_loop_is_painted_without_the_ageing_pass(window, qtbot, monkeypatch):
    doc = window.doc
    inst = doc.add_widget(doc.current.id, "std.label",
                          Binding("/rcon_test/silent", "std_msgs/Float64", Role.SUBSCRIBE, ("data",)),
                          Geometry(16, 16, 240, 120), {})
    qtbot.waitUntil(lambda: inst.id in window.host.hosted and window.host.hosted[inst.id].model is not None
                    and window.host.hosted[inst.id].model.running, timeout=10_000)
    hosted = window.host.hosted[inst.id]
    qtbot.waitUntil(lambda: hosted.painted_seq == hosted.model.state.seq, timeout=5_000)
    monkeypatch.setattr(main_window, "FULL_PASS_EVERY", 1e9)  # from now on only wake-ups repaint
    window._last_full_pass = 0.0  # noqa: SLF001 - restart the (now endless) interval
    for value in (1.5, 2.5, 3.5):
        # as a worker thread would: the model makes its value outside the loop, nobody else pokes the GUI
        t = threading.Thread(target=hosted.model.on_message, args=({"data": value},))
        t.start()
        t.join(5)
        seq = hosted.model.state.seq
        qtbot.waitUntil(lambda seq=seq: hosted.painted_seq >= seq, timeout=3_000)
        assert hosted.view is not None


def test_a_view_that_fails_to_show_a_value_does_not_stop_the_others(window, qtbot, caplog):
    """One widget's view raising in ``refresh`` is counted, logged and shown on its own badge (ERROR with the
    reason); the other widgets of the same pass keep repainting, and the widget recovers when it can show
    again."""
    doc = window.doc
    ids = [doc.add_widget(doc.current.id, "std.label",
                          Binding(f"/rcon_test/v{i}", "std_msgs/Float64", Role.SUBSCRIBE, ("data",)),
                          Geometry(16 + 256 * i, 16, 240, 120), {}).id for i in range(2)]
    qtbot.waitUntil(lambda: all(i in window.host.hosted and window.host.hosted[i].model is not None
                                and window.host.hosted[i].model.running for i in ids), timeout=10_000)
    bad, good = (window.host.hosted[i] for i in ids)
    original = bad.view.refresh

    def broken(state):
        raise ValueError("cannot draw " + "x" * 5000)  # a long text: logged and shown bounded

    bad.view.refresh = broken
    try:
        for value in (1.0, 2.0, 3.0):
            bad.model.on_message({"data": value})
            good.model.on_message({"data": value})
            seq = good.model.state.seq
            qtbot.waitUntil(lambda seq=seq: good.painted_seq >= seq, timeout=3_000)
        qtbot.waitUntil(lambda: window.host.view_errors >= 1, timeout=3_000)
        assert bad.frame.badge.kind == "problem" and bad.frame.badge.status == "ERROR"
        assert "cannot draw" in bad.frame.badge.toolTip()
        assert len(bad.frame.badge.toolTip()) < 400
        assert any("cannot draw" in r.getMessage() and len(r.getMessage()) < 600 for r in caplog.records)
        assert good.frame.badge.kind != "problem"
    finally:
        bad.view.refresh = original
    bad.model.on_message({"data": 4.0})
    qtbot.waitUntil(lambda: bad.view_error is None and bad.painted_seq == bad.model.state.seq, timeout=3_000)
    qtbot.waitUntil(lambda: bad.frame.badge.kind != "problem", timeout=3_000)
