"""issue 22.4: one widget whose hooks raise leaves every other widget alone. A widget whose
``problems()`` raised stopped every widget on the canvas from refreshing (the host's ``apply`` raised
before its refresh pass) and STALE badges froze; its ``set_link`` raising kept the link state from the
widgets after it. Every hook of a widget is now isolated like ``refresh``: counted, logged with a
bounded text, shown on that widget's badge."""

from __future__ import annotations

import pytest
from app_helpers import entry_point_plugins, window_session
from fragile_widget import FragilePlugin

from rcon_core.canvas import Binding, Geometry

pytest.importorskip("rcon_widgets_std")
pytestmark = pytest.mark.usefixtures("qapp")


@pytest.fixture(params=[{"problems"}, None], ids=["problems-raises", "every-hook-raises"])
def window(request, qtbot, tmp_path, sim_url):
    plugins = entry_point_plugins()
    plugins.register(FragilePlugin(request.param), "fragile")
    yield from window_session(qtbot, tmp_path, plugins, url=sim_url, wait_connected=True)


def place(window, kind, binding, x, title):
    return window.doc.add_widget(window.controller.canvas.id, kind, binding, Geometry(x, 24, 240, 160), {}, title)


def test_a_widget_whose_hooks_raise_leaves_the_others_refreshing(window, qtbot):
    fragile = place(window, "test.fragile", Binding("/odom", "nav_msgs/Odometry", "subscribe"), 24, "Fragile")
    battery = place(window, "std.label", Binding("/battery", "sensor_msgs/BatteryState", "subscribe",
                                                 ("percentage",)), 288, "Battery")
    host = window.host
    qtbot.waitUntil(lambda: host.hosted[battery.id].view is not None and host.hosted[fragile.id].view is not None,
                    timeout=10_000)
    label = host.hosted[battery.id]
    qtbot.waitUntil(lambda: label.model.state.count > 0 and label.view.value.text() not in ("", "–"),
                    timeout=10_000)
    frame = host.hosted[fragile.id].frame
    qtbot.waitUntil(lambda: frame.badge.status == "ERROR", timeout=10_000)
    assert "problems() blew up" in frame.badge.toolTip()
    assert host.hook_errors >= 1
    # the fragile view is shown and refreshed too: only its problem list could not be had
    qtbot.waitUntil(lambda: host.hosted[fragile.id].view.refreshed > 0, timeout=10_000)
    count = label.model.state.count
    qtbot.waitUntil(lambda: label.model.state.count > count + 2, timeout=10_000)
    window._pump(None)  # a full pass over every widget: no hook raises out of it
    # the link drops: the widgets after the fragile one hear it (its set_link raises)
    window.link.disconnect()
    qtbot.waitUntil(lambda: label.model.state.link_down, timeout=10_000)
    qtbot.waitUntil(lambda: label.frame.badge.status == "LINK DOWN", timeout=10_000)
