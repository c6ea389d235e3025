"""The add panel's choosers and labels, also used by the Configure dialog (kept out of ``add_panel.py``).

* :class:`NameLabel`: one name (topic, service, widget) on one line, elided in the middle;
* :class:`ElidingCombo`: a combo box whose current text is cut with "…" rather than mid-letter;
* :class:`FieldChooser`: which field of the message a widget binds, each with its type;
* :class:`TargetChooser`: the topic, service or action a widget binds, compatible ones only;
* :class:`DragHandle`: dragged onto a canvas, drops the draft there.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

from qtpy import QtCore, QtGui, QtWidgets

from rcon_core.app.canvas_surface import DRAFT_MIME
from rcon_core.app.draft import Target, field_type
from rcon_core.app.elided_label import OneLineLabel
from rcon_core.app.settings_form import guard_wheel
from rcon_core.app.theme import current_touch_px
from rcon_core.plugins import Role, WidgetSpec

__all__ = ["DragHandle", "heading", "ElidingCombo", "FieldChooser", "NameLabel", "TARGET_ROLE", "TargetChooser", "type_tail"]

#: item data role of the target chooser holding the role a target is compatible with
TARGET_ROLE = QtCore.Qt.ItemDataRole.UserRole + 1


def heading(text: str) -> QtWidgets.QLabel:
    """A wrapped heading label."""
    label = QtWidgets.QLabel(text)
    label.setProperty("role", "heading")
    label.setWordWrap(True)
    return label


class NameLabel(OneLineLabel):
    """A heading showing one name (a topic, a service, a widget) on one line, never broken at a slash:
    elided in the middle when the panel is too narrow, the full name in its tooltip."""

    def __init__(self, name: str = "") -> None:
        super().__init__()
        self.setProperty("role", "heading")
        self.full_name = ""
        self.set_name(name)

    def set_name(self, name: str) -> None:
        self.full_name = name
        self.setToolTip(name)
        self.setAccessibleName(name)
        self._elide()

    def _elide(self) -> None:
        width = self.contentsRect().width()
        text = self.full_name
        if self.isVisible() and width > 0:
            text = self.fontMetrics().elidedText(text, QtCore.Qt.TextElideMode.ElideMiddle, width)
        if text != self.text():
            self.setText(text)


def type_tail(type_name: str) -> str:
    """``sensor_msgs/msg/BatteryState`` -> ``BatteryState``: what fits in a chooser; builtins as they are."""
    return type_name.rsplit("/", 1)[-1]


class ElidingCombo(QtWidgets.QComboBox):
    """A combo box that shows its current text cut with "…" when the panel is too narrow (instead of
    clipping it mid-letter), the whole text in its tooltip. Touch-sized like every combo (theme)."""

    def __init__(self, name: str) -> None:
        super().__init__()
        self.setObjectName(name)
        self.setSizeAdjustPolicy(QtWidgets.QComboBox.SizeAdjustPolicy.AdjustToMinimumContentsLengthWithIcon)
        self.setMinimumContentsLength(8)
        self.currentTextChanged.connect(self.setToolTip)
        guard_wheel(self)
        # the popup's entries touch-sized too (style sheet item rules need a styled delegate)
        self.setItemDelegate(QtWidgets.QStyledItemDelegate(self))
        self.view().setStyleSheet(f"QAbstractItemView::item {{ min-height: {current_touch_px()}px; }}")

    def paintEvent(self, event: QtGui.QPaintEvent) -> None:
        painter = QtWidgets.QStylePainter(self)
        opt = QtWidgets.QStyleOptionComboBox()
        self.initStyleOption(opt)
        painter.drawComplexControl(QtWidgets.QStyle.ComplexControl.CC_ComboBox, opt)
        field = self.style().subControlRect(QtWidgets.QStyle.ComplexControl.CC_ComboBox, opt,
                                            QtWidgets.QStyle.SubControl.SC_ComboBoxEditField, self)
        opt.currentText = self.fontMetrics().elidedText(opt.currentText, QtCore.Qt.TextElideMode.ElideRight,
                                                        max(0, field.width() - 4))
        painter.drawControl(QtWidgets.QStyle.ControlElement.CE_ComboBoxLabel, opt)


class FieldChooser(ElidingCombo):
    """The *Field* chooser: which field of the message a widget shows or sets, listed with each field's
    type (``voltage · float32``), best first. Used by the add panel and by Configure on a placed widget.

    ``chosen(path)`` is emitted when the operator picks a field (not when the list is filled).
    """

    chosen = QtCore.Signal(str)

    def __init__(self, name: str = "fieldCombo") -> None:
        super().__init__(name)
        self.setAccessibleDescription("Which field of the message the widget shows or sets")
        self.currentIndexChanged.connect(self._index_changed)

    def set_fields(self, paths: Sequence[str], current: str, *, types: Any = None, type_name: str = "",
                   service: bool = False) -> bool:
        """List ``paths`` (``current`` first when it is not among them) and select ``current``; each with its
        type when ``types`` knows ``type_name``. Returns whether there is a choice to make (2+ fields)."""
        listed = list(dict.fromkeys(paths))
        if current and current not in listed:
            listed.insert(0, current)
        self.blockSignals(True)
        self.clear()
        for path in listed:
            tp = field_type(types, type_name, path, service) if types is not None and type_name else ""
            self.addItem(f"{path} · {type_tail(tp)}" if tp else path, path)
            self.setItemData(self.count() - 1, f"{path}: {tp or 'type unknown'}", QtCore.Qt.ItemDataRole.ToolTipRole)
        if listed:
            self.setCurrentIndex(listed.index(current) if current in listed else 0)
        self.blockSignals(False)
        self.setToolTip(self.currentText())
        return len(listed) > 1

    def paths(self) -> list[str]:
        return [self.itemData(i) for i in range(self.count())]

    def current_path(self) -> str | None:
        """The selected field path (None when the list is empty)."""
        return self.currentData()

    def choose(self, path: str) -> None:
        """Select ``path``; ValueError if it is not offered."""
        index = self.findData(path)
        if index < 0:
            raise ValueError(f"{path!r} is not a field this widget can use here (offered: {self.paths()})")
        self.setCurrentIndex(index)

    def _index_changed(self, index: int) -> None:
        path = self.itemData(index)
        if path is not None:
            self.chosen.emit(path)


class TargetChooser(ElidingCombo):
    """The *Topic* (Service, Action) chooser: ``— choose —``, the targets compatible with the draft's
    role, then those compatible only with another of the widget's roles (marked ``· to <role>``; the
    role each entry binds in is :meth:`role_at`)."""

    def list_targets(self, spec: WidgetSpec, role: Role, roles: Sequence[Role],
                     targets_for: Callable[[WidgetSpec, Role], list[Target]]) -> list[Target]:
        """Fill the list (signals are the caller's to block); returns the targets compatible with ``role``."""
        self.clear()
        targets = targets_for(spec, role)
        self.addItem("— choose —", None)
        for t in targets:
            self.addItem(f"{t.name}  ({type_tail(t.type)})", t)
            self.setItemData(self.count() - 1, role.value, TARGET_ROLE)
        offered = {t.name for t in targets}
        for other in roles:
            if other is role:
                continue
            for t in targets_for(spec, other):
                if t.name in offered:
                    continue
                offered.add(t.name)
                self.addItem(f"{t.name}  ({type_tail(t.type)})  · to {other.value}", t)
                i = self.count() - 1
                self.setItemData(i, other.value, TARGET_ROLE)
                self.setItemData(i, f"Choosing this makes the widget {other.value} instead of {role.value}",
                                 QtCore.Qt.ItemDataRole.ToolTipRole)
        self.setEnabled(True)
        return targets

    def show_fixed(self, target: Target | None) -> None:
        """Only ``target`` (chosen before the widget: a topic picked first), not changeable here."""
        self.clear()
        self.addItem(f"{target.name}  ({type_tail(target.type)})" if target else "—", target)
        self.setEnabled(False)

    def role_at(self, index: int) -> Role | None:
        tagged = self.itemData(index, TARGET_ROLE)  # a plain str: Qt drops the enum
        return Role.parse(tagged) if tagged else None

    def index_of(self, name: str, role: Role) -> int:
        """The entry of target ``name`` in ``role`` (0, ``— choose —``, when it is not offered)."""
        return next((i for i in range(1, self.count()) if self.itemData(i) is not None
                     and self.itemData(i).name == name and self.itemData(i, TARGET_ROLE) == role.value), 0)

    def choose(self, name: str) -> None:
        """Select the compatible target ``name``; ValueError if it is not offered."""
        for i in range(1, self.count()):
            t = self.itemData(i)
            if t is not None and t.name == name:
                self.setCurrentIndex(i)
                return
        offered = [t.name for i in range(1, self.count()) if (t := self.itemData(i))]
        raise ValueError(f"{name!r} is not compatible with this widget (offered: {offered})")


class DragHandle(QtWidgets.QLabel):
    """Press and drag this onto a canvas to drop the draft there."""

    def __init__(self, preview: Callable[[], QtWidgets.QWidget | None]) -> None:
        super().__init__("✥ Drag onto the canvas")
        self.setObjectName("dragHandle")
        self.preview = preview  #: the draft's preview frame (its picture is dragged), if any
        self.setAlignment(QtCore.Qt.AlignmentFlag.AlignCenter)
        self.setWordWrap(True)  # "Not ready: <the first problem>" wraps instead of being cut at both ends
        self.setSizePolicy(QtWidgets.QSizePolicy.Policy.Ignored, QtWidgets.QSizePolicy.Policy.Preferred)
        self.setStyleSheet("padding: 4px 8px; border:3px dashed palette(link); color:palette(link); font-weight:bold;"
                           " border-radius:6px;")
        self._press: QtCore.QPoint | None = None

    def mousePressEvent(self, event: QtGui.QMouseEvent) -> None:
        self._press = event.position().toPoint()

    def mouseMoveEvent(self, event: QtGui.QMouseEvent) -> None:
        if self._press is None or not self.isEnabled():
            return
        if (event.position().toPoint() - self._press).manhattanLength() < 10:
            return
        self._press = None
        drag = QtGui.QDrag(self)
        mime = QtCore.QMimeData()
        mime.setData(DRAFT_MIME, QtCore.QByteArray(b"draft"))
        drag.setMimeData(mime)
        preview = self.preview()
        if preview is not None:
            pix = preview.grab().scaledToWidth(min(240, max(60, preview.width())))
            drag.setPixmap(pix)
            drag.setHotSpot(QtCore.QPoint(12, 12))
        drag.exec(QtCore.Qt.DropAction.CopyAction)
