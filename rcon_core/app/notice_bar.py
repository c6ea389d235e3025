"""A bar that tells the operator something and offers what to do about it.

Non-blocking (no modal dialog on a tablet in the field): a message, optional action buttons and a
dismiss button. ``kind`` "problem" is red (a layout that is not saved), "info" is blue.

It floats over the bottom edge of its host (:meth:`NoticeBar.float_over`; the window puts it over the
canvas column) instead of taking a row in a layout: a notice that pushed the window's content down would
move the control under the operator's finger just before the next tap. The bottom of the canvas column
keeps the connection bar, the canvas tabs, the mode switch, the side panel and the add panel uncovered.
"""

from __future__ import annotations

from collections.abc import Callable

from qtpy import QtCore, QtWidgets


class NoticeBar(QtWidgets.QFrame):
    """One notice at a time; :meth:`show_notice` replaces the previous one."""

    def __init__(self, name: str, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.setObjectName(f"{name}Bar")
        self.kind = ""
        self.label = QtWidgets.QLabel()
        self.label.setObjectName(name)
        self.label.setWordWrap(True)
        self.label.setTextInteractionFlags(QtCore.Qt.TextInteractionFlag.TextSelectableByMouse)
        self._row = QtWidgets.QHBoxLayout(self)
        self._row.setContentsMargins(0, 0, 8, 0)
        self._row.setSpacing(8)
        self._row.addWidget(self.label, 1)
        self.buttons: dict[str, QtWidgets.QPushButton] = {}
        self.dismiss_button = QtWidgets.QPushButton("Dismiss")
        self.dismiss_button.setObjectName(f"{name}Dismiss")
        self.dismiss_button.clicked.connect(self.dismiss)
        self._row.addWidget(self.dismiss_button)
        self.hide()

    def float_over(self, host: QtWidgets.QWidget) -> None:
        """Float over the bottom edge of ``host`` (full width), following its size; takes no room."""
        self.setParent(host)
        self._host = host
        host.installEventFilter(self)
        self._place()

    def eventFilter(self, obj: QtCore.QObject, event: QtCore.QEvent) -> bool:  # noqa: N802 - Qt override
        if obj is getattr(self, "_host", None) and event.type() in (QtCore.QEvent.Type.Resize,
                                                                      QtCore.QEvent.Type.LayoutRequest):
            self._place()
        return super().eventFilter(obj, event)

    def _place(self) -> None:
        host = getattr(self, "_host", None)
        if host is None:
            return
        width = host.width()
        height = self.heightForWidth(width) if self.hasHeightForWidth() else -1
        height = max(height, self.sizeHint().height(), self.minimumSizeHint().height())
        self.setGeometry(0, max(0, host.height() - height), width, height)
        self.raise_()

    def show_notice(self, text: str, kind: str = "problem",
                    actions: list[tuple[str, Callable[[], object]]] | None = None) -> None:
        for button in self.buttons.values():
            self._row.removeWidget(button)
            button.deleteLater()
        self.buttons = {}
        for label, fn in actions or []:
            button = QtWidgets.QPushButton(label)
            button.setObjectName("noticeAction")
            button.clicked.connect(lambda _=False, fn=fn: fn())
            self._row.insertWidget(self._row.count() - 1, button)
            self.buttons[label] = button
        self.kind = kind
        colour = "#b00000" if kind == "problem" else "#0040a0"
        self.setStyleSheet(f"QFrame#{self.objectName()} {{ background: {colour}; }}"
                           f" QLabel {{ background: {colour}; color: #ffffff; font-weight: bold;"
                           " padding: 8px 12px; }")
        self.label.setText(text)
        self.show()
        self._place()

    def dismiss(self) -> None:
        self.kind = ""
        self.hide()
