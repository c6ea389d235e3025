"""issue 15.8: a stored setting of the wrong type shows the promised "not configured" warning with a
sentence, not ERROR "could not be shown: expected float @ $.minimum", and is logged once."""

from __future__ import annotations

import logging

import pytest
from app_helpers import entry_point_plugins, window_session
from qtpy import QtWidgets

from rcon_core.canvas import Binding, Canvas, Geometry, WidgetInstance, Workspace, new_id

pytest.importorskip("rcon_widgets_std")
pytestmark = pytest.mark.usefixtures("qapp")


def layout() -> Workspace:
    canvas = Canvas(new_id("c"), "Ops")
    canvas.widgets.append(WidgetInstance(new_id("w"), "std.slider",
                                         Binding("/speed_limit", "std_msgs/Float64", "publish", ("data",)),
                                         Geometry(32, 32, 320, 160), {"minimum": "low", "maximum": 2.0}, "Speed"))
    return Workspace([canvas], canvas.id)


@pytest.fixture
def window(qtbot, tmp_path, sim_thread, caplog):
    caplog.set_level(logging.INFO)
    yield from window_session(qtbot, tmp_path / "config", entry_point_plugins(), url=sim_thread.url,
                              demo=layout, wait_connected=True)


def test_a_wrong_type_in_settings_is_not_configured(window, qtbot, caplog):
    [frame] = window.controller.surface.frames.values()
    qtbot.waitUntil(lambda: frame.problems.isVisible(), timeout=10_000)
    text = frame.problems.text()
    assert text.startswith("⚠ Not configured")
    assert "invalid settings: minimum must be a number (got 'low')" in text
    assert frame.badge.status != "ERROR"
    placeholders = [w.text() for w in frame.findChildren(QtWidgets.QLabel, "placeholder")]
    assert not any("could not be shown" in t for t in placeholders)
    records = caplog.get_records("setup") + caplog.get_records("call")
    said = [r for r in records if "minimum must be a number" in r.getMessage()]
    assert len(said) == 1 and said[0].levelno == logging.INFO
