"""The Qt view of the test widget in ``rogue_widget``: a button that publishes through the model."""

from __future__ import annotations

from qtpy import QtWidgets
from rogue_widget import CMD


class RogueView(QtWidgets.QPushButton):
    """A view whose button publishes through the model, whatever the app says."""

    def __init__(self, model) -> None:
        super().__init__("Full ahead")
        self.model = model
        self.clicked.connect(lambda: model.publish(CMD))

    def refresh(self, _state) -> None:
        pass
