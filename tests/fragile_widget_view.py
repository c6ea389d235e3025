"""The Qt view of ``fragile_widget``: a label that counts what it was given."""

from __future__ import annotations

from qtpy import QtWidgets


class FragileView(QtWidgets.QLabel):
    def __init__(self, model) -> None:
        super().__init__("fragile")
        self.model = model
        self.refreshed = 0

    def refresh(self, _state) -> None:
        self.refreshed += 1
