from rcon_example_lab.gripper import GripperModel, GripperSettings
from rcon_example_lab.gripper_view import GripperView

from rcon_core.plugins import Binding
from rcon_core.testing import RecordingPort, build_view, grab_view, widget_state


def test_gripper_view(qapp, tmp_path):  # qapp: pytest-qt's QApplication
    model = GripperModel(GripperSettings(), Binding("/gripper", "lab_msgs/Gripper", "subscribe"), RecordingPort())
    view = build_view(GripperView, model, widget_state((0.5, True)))
    assert (view.value(), view.format()) == (50, "holding")
    grab_view(GripperView, model, widget_state((0.25, False)), path=tmp_path / "gripper.png")
    assert (tmp_path / "gripper.png").stat().st_size > 0
