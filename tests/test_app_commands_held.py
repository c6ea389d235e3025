"""Commands held behind an unanswered service call, in the real window against a ROS 2 sim: a test client
serves ``/slow`` and does not answer; the operator taps a button that calls it. rosbridge 2.1.0 would hold
every later frame of the window's connection behind that call (``rcon_core/bridge/held.py``), so after
half a second the connection bar says so, the teleop pad stops, says why and sends nothing even with a
finger on it; once the call is answered the bar clears and the pad drives again (after the finger is put
down anew)."""

from __future__ import annotations

import asyncio
from collections.abc import Iterator

import pytest
from app_helpers import TIMEOUT_MS, all_sent, snap, tap, window_session
from qtpy import QtCore
from qtpy.QtTest import QTest

from rcon_core.bridge import BridgeClient
from rcon_core.bridge.threaded import BridgeThread
from rcon_core.canvas import Binding, Geometry
from rcon_core.plugins import Role
from rcon_core.sim import SimServer

pytest.importorskip("rcon_widgets_std")
pytest.importorskip("rcon_widgets_sensors")

pytestmark = pytest.mark.usefixtures("qapp")

HELD = "commands held: the robot's bridge is still busy with /slow"
LEFT = QtCore.Qt.MouseButton.LeftButton


class SlowService:
    """``/slow`` (std_srvs/Trigger) served by a client of its own, answering only when told."""

    def __init__(self, url: str) -> None:
        self.thread = BridgeThread().start()
        self.client = BridgeClient(url, reconnect=False)
        self.thread.run(self.client.connect()).result(10)
        self.calls = 0
        self._gate: asyncio.Event | None = None

        def advertise() -> None:
            self._gate = asyncio.Event()
            self.client.node("slow").advertise_service("/slow", "std_srvs/Trigger", self._handle)

        self.thread.call(advertise)

    async def _handle(self, _request: dict) -> dict:
        self.calls += 1
        assert self._gate is not None
        await self._gate.wait()
        return {"success": True, "message": "late"}

    def answer(self) -> None:
        self.thread.call(lambda: self._gate.set())

    def close(self) -> None:
        self.thread.run(self.client.close()).result(10)
        self.thread.stop()


@pytest.fixture
def sim2() -> Iterator[SimServer]:
    with SimServer.in_thread(host="127.0.0.1", port=0, ros2=True) as server:
        yield server


@pytest.fixture
def slow(sim2) -> Iterator[SlowService]:
    service = SlowService(sim2.url)
    yield service
    service.close()


@pytest.fixture
def window(qtbot, tmp_path, sim2, slow, plugins):
    yield from window_session(qtbot, tmp_path / "cfg", plugins, url=sim2.url, wait_connected=True,
                              services=("/slow",))


def place(window, qtbot, kind, binding, rect, settings, title=""):
    spec = window.plugins.widget(kind)
    w = window.doc.add_widget(window.controller.canvas.id, kind, binding, Geometry(*rect),
                              spec.settings_to_dict(spec.make_settings(settings)), title)
    return w.id


def view_of(window, qtbot, widget_id):
    hosted = window.host.hosted[widget_id]
    qtbot.waitUntil(lambda: hosted.view is not None and hosted.view.isVisible()
                    and getattr(hosted.model, "types_ready", True), timeout=TIMEOUT_MS)
    return hosted.view


def pad_says(qtbot, pad, ok) -> None:
    try:
        qtbot.waitUntil(lambda: ok(pad.status_text()), timeout=TIMEOUT_MS)
    except Exception:
        raise AssertionError(f"the pad says {pad.status_text()!r}") from None


def test_an_unanswered_call_stops_the_pad_and_the_bar_says_commands_are_held(window, qtbot, sim2, slow):
    pad_id = place(window, qtbot, "sensors.teleop", Binding("/cmd_vel", "geometry_msgs/Twist", Role.PUBLISH),
                   (16, 16, 272, 320), {"max_linear": 1.0, "max_angular": 1.0})
    button_id = place(window, qtbot, "std.button", Binding("/slow", "std_srvs/Trigger", Role.CALL),
                      (304, 16, 240, 160), {}, "Slow")
    window.controller.set_locked(True)  # Operate mode: the views take the taps
    pad = view_of(window, qtbot, pad_id)
    button = view_of(window, qtbot, button_id)
    pad_says(qtbot, pad, lambda text: text.startswith("idle"))

    # a finger on the pad drives, then the operator taps the button that calls /slow
    centre, radius = pad.pad()
    c = centre.toPoint()
    QTest.mousePress(pad, LEFT, pos=c)
    QTest.mouseMove(pad, c - QtCore.QPoint(0, int(radius * 0.8)))
    sim2.wait_for_published_sync("/cmd_vel", lambda m: m["linear"]["x"] > 0.3, timeout=10)
    tap(button.button)
    qtbot.waitUntil(lambda: slow.calls == 1, timeout=TIMEOUT_MS)

    # half a second on: the bar says so, the pad stops (one zero, to end whatever waits behind the call)
    bar = window.connection
    qtbot.waitUntil(lambda: bar.message.text() == f"⚠ {HELD}", timeout=TIMEOUT_MS)
    pad_says(qtbot, pad, lambda text: text == "⚠ not sending: bridge busy with /slow")  # short: a pad is narrow
    sim2.wait_for_published_sync("/cmd_vel", lambda m: m["linear"]["x"] == 0.0, timeout=10)
    all_sent(qtbot, window, sim2)  # (a rosapi call: on a 2.1.0 robot it too would wait behind /slow)
    before = len(sim2.published("/cmd_vel"))
    QTest.mouseMove(pad, c - QtCore.QPoint(int(radius * 0.5), int(radius * 0.5)))  # the finger moves on
    QTest.mouseRelease(pad, LEFT, pos=c)
    QTest.mousePress(pad, LEFT, pos=c)  # and is put down again: still nothing while held
    QTest.mouseMove(pad, c - QtCore.QPoint(0, int(radius * 0.8)))
    all_sent(qtbot, window, sim2)
    assert len(sim2.published("/cmd_vel")) == before  # nothing more went out to wait behind the call
    assert pad.model.state.value.commands_held == HELD
    snap(window, "commands-held")

    # the call is answered: the bar clears, the pad drives again once the finger is put down anew
    slow.answer()
    qtbot.waitUntil(lambda: bar.message.text() == "", timeout=TIMEOUT_MS)
    qtbot.waitUntil(lambda: not pad.model.state.value.commands_held, timeout=TIMEOUT_MS)
    QTest.mouseRelease(pad, LEFT, pos=c)
    QTest.mousePress(pad, LEFT, pos=c)
    QTest.mouseMove(pad, c - QtCore.QPoint(0, int(radius * 0.8)))
    sim2.wait_for_published_sync("/cmd_vel", lambda m: m["linear"]["x"] > 0.3, timeout=10)
    QTest.mouseRelease(pad, LEFT, pos=c)
    sim2.wait_for_published_sync("/cmd_vel", lambda m: m["linear"]["x"] == 0.0, timeout=10)
