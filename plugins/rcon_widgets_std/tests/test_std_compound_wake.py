"""Issue 24.5: the Compound's children are hosted like any widget. A child's change moves the compound's
``seq`` and wakes the front end through the compound's port at once; the compound view repaints the child
in the host's ``refresh`` and keeps no repaint clock of its own (it polled its children every 100 ms)."""

from __future__ import annotations

from qtpy import QtCore
from rcon_widgets_std.compound import ChildSpec, CompoundModel, CompoundSettings
from rcon_widgets_std.compound_view import CompoundView
from std_testkit import STD

from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import Binding, WidgetContext
from rcon_core.testing import RecordingPort


def test_a_child_wakes_the_front_end_and_is_repainted_without_a_clock(qtbot):
    port = RecordingPort()
    settings = CompoundSettings(children=[ChildSpec("std.slider", "linear.x", {"minimum": -1, "maximum": 1, "step": 0.1}),
                                          ChildSpec("std.stepper", "angular.z")])
    m = CompoundModel(settings, Binding("/rcon_test/wake", "geometry_msgs/Twist", "publish"), port,  # a topic of its own: a slider remembers its last value per topic
                      types=TypeRegistry.standard(), context=WidgetContext(STD))
    m.start()  # the type is known: the children are built and started
    assert len(m.children) == 2
    view = CompoundView(m)
    qtbot.addWidget(view)
    view.refresh(m.state)
    assert not [t for t in view.findChildren(QtCore.QTimer) if t.isActive() and t.interval() == 100]
    slider, slider_view = view.child_views[0]
    slider_model = slider.model
    before_seq, before_changes = m.state.seq, port.changes
    slider_model.release(0.5)  # the child changes (here from the test's thread, as from the bridge thread)
    assert m.state.seq > before_seq and port.changes > before_changes  # the compound woke the front end
    assert slider_view.value.text() != "0.50"  # nothing repaints by itself...
    view.refresh(m.state)  # ...the host refreshes the compound once its seq moved
    assert slider_view.value.text() == "0.50"
