"""The gripper widget's Qt view: imported only when a canvas shows it.

The app builds it as ``GripperView(model)`` and calls ``refresh(state)`` when ``state.seq`` moved.
"""

from qtpy import QtWidgets


class GripperView(QtWidgets.QProgressBar):
    def __init__(self, model, parent=None):
        super().__init__(parent)
        self.model = model
        self.setRange(0, 100)

    def refresh(self, state):
        fraction, grasping = state.value or (0.0, False)
        self.setValue(round(fraction * 100))
        self.setFormat("holding" if grasping else "%p% open")
