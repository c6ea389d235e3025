"""The slot on the add panel's settings page that holds the live preview's frame (sizing only).

As wide as the panel allows, never wider; its height follows the widget's default aspect, clamped, and
at most a third of the panel on a short screen (then narrower, keeping the widget's shape).
"""

from __future__ import annotations

from qtpy import QtGui, QtWidgets


class PreviewSlot(QtWidgets.QWidget):
    """Holds the preview frame: as wide as the panel allows, never wider, its height following the
    widget's default aspect (clamped, and at most :attr:`room` on a short screen: then narrower, keeping
    its shape), so a big widget shows scaled down instead of cut."""

    MIN_H, MAX_H = 150, 320  # room for the "not configured" warning listing a few problems
    room = MAX_H  #: the most height the panel can give (set by the panel from its own height)

    def __init__(self) -> None:
        super().__init__()
        self.setObjectName("previewSlot")
        self.setSizePolicy(QtWidgets.QSizePolicy.Policy.Ignored, QtWidgets.QSizePolicy.Policy.Fixed)
        self.col = QtWidgets.QVBoxLayout(self)
        self.col.setContentsMargins(0, 0, 0, 0)
        self.aspect = 0.5  # height / width
        self.frame: QtWidgets.QWidget | None = None
        self.setFixedHeight(0)

    def set_frame(self, frame: QtWidgets.QWidget | None, size: tuple[float, float] = (160.0, 80.0)) -> None:
        if self.frame is not None:
            self.col.removeWidget(self.frame)
        self.frame = frame
        if frame is not None:
            w, h = size
            self.aspect = (h / w) if w > 0 and h > 0 else 0.5
            frame.setMinimumSize(60, self.MIN_H)  # explicit: the view's own minimum never widens the panel
            frame.setSizePolicy(QtWidgets.QSizePolicy.Policy.Ignored, QtWidgets.QSizePolicy.Policy.Ignored)
            self.col.addWidget(frame)
        self._fit()

    def resizeEvent(self, event: QtGui.QResizeEvent) -> None:
        super().resizeEvent(event)
        self._fit()

    def set_room(self, room: int) -> None:
        self.room = max(self.MIN_H, min(self.MAX_H, room))
        self._fit()

    def _fit(self) -> None:
        if self.frame is None:
            self.setFixedHeight(0)
            return
        height = int(max(self.MIN_H, min(self.room, self.width() * self.aspect)))
        # capped by the room: narrower too, so a square widget stays square (centred)
        side = max(0, (self.width() - round(height / self.aspect)) // 2) if self.aspect > 0 else 0
        self.col.setContentsMargins(side, 0, side, 0)
        if height != self.height() or self.minimumHeight() != height:
            self.setFixedHeight(height)
