"""What widgets show and send is true, on the real window against the sim: a typed ``nan`` is refused
with a reason (not sent as ``null``)."""

from __future__ import annotations

import pytest
from app_helpers import choose_kind, entry_point_plugins, snap, tap, tap_topic, window_session
from qtpy import QtWidgets
from qtpy.QtTest import QTest

from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import PluginManager, Role

pytestmark = pytest.mark.usefixtures("qapp")


@pytest.fixture(scope="module")
def plugins() -> PluginManager:
    pytest.importorskip("rcon_widgets_std")
    return entry_point_plugins()


@pytest.fixture
def window(qtbot, tmp_path, sim_thread, plugins):
    yield from window_session(qtbot, tmp_path / "config", plugins, url=sim_thread.url,
                              types=TypeRegistry.standard(), wait_connected=True, topics=("/speed_limit",))


def place(window, qtbot, topic: str, role: Role, kind: str, settings: dict | None = None):
    """Add a widget from the topic list with the add panel's Place button; returns (instance, hosted),
    running in Operate mode."""
    tap_topic(window, topic)
    panel = choose_kind(window, role, kind)
    for name, value in (settings or {}).items():
        [box] = [b for b in panel.settings_page.findChildren(QtWidgets.QCheckBox, f"setting_{name}")]
        if box.isChecked() != value:
            panel.settings_scroll.ensureWidgetVisible(box)
            box.click()
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
    snap(window, "textfield-nan-refused")
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
