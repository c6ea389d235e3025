"""The Label view built and rendered through RCON's view test harness (rcon_core.testing), as a lab would
test its own view: a model on a port that reaches no robot, a state, a PNG."""

from qtpy import QtGui
from rcon_widgets_std.label import LabelModel, LabelSettings
from rcon_widgets_std.label_view import LabelView

from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import Binding
from rcon_core.testing import RecordingPort, build_view, grab_view


def test_label_view_through_the_harness(qapp, tmp_path):
    model = LabelModel(LabelSettings(decimals=1, units="%", scale=100),
                       Binding("/battery", "sensor_msgs/BatteryState", "subscribe", "percentage"), RecordingPort(),
                       types=TypeRegistry.standard())
    model.on_message({"percentage": 0.5})
    view = build_view(LabelView, model, size=(200, 120))
    assert view.value.text() == "50.0 %"
    image = grab_view(LabelView, model, size=(200, 120), path=tmp_path / "label.png")
    assert (image.width(), image.height()) == (200, 120)
    assert QtGui.QImage(str(tmp_path / "label.png")).size() == image.size()
    colours = {image.pixel(x, y) for x in range(0, 200, 5) for y in range(0, 120, 5)}
    assert len(colours) > 2, "the view drew nothing"
