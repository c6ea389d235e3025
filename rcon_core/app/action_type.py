"""The add panel's "which type is this action?" box, for an action the robot listed without its type.

rosapi 2.1.0 lists action servers by name only (``/rosapi/action_type`` came later), so the Actions list
shows such an action as *type unknown*. Tapping it opens the add panel with this box on the role page:
the operator picks the action's type from the action types RCON knows (bundled, contributed by plugins
with ``rcon_register_types``, or learned from the robot), and the widgets that fit it are offered as
usual. Until a type is chosen, *Send goals* stays disabled.
"""

from __future__ import annotations

from typing import Any

from qtpy import QtCore, QtWidgets

from rcon_core.msgs.names import pkg_type


def known_action_types(types: Any) -> list[str]:
    """Every action type the registry knows (``pkg/action/X``), sorted."""
    try:
        return sorted(t for t in types.interfaces() if "/action/" in t)
    except Exception:  # a registry without interfaces(): nothing to offer
        return []


class ActionTypeBox(QtWidgets.QWidget):
    """A hint and a chooser of known action types; ``chosen(type)`` fires when the operator picks one."""

    chosen = QtCore.Signal(str)

    def __init__(self, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.hint = QtWidgets.QLabel("The robot did not tell this action's type (rosapi 2.1.0 cannot): "
                                     "choose it from the action types RCON knows.")
        self.hint.setProperty("role", "hint")
        self.hint.setWordWrap(True)
        self.combo = QtWidgets.QComboBox()
        self.combo.setObjectName("actionTypeCombo")
        self.combo.currentIndexChanged.connect(self._changed)
        col = QtWidgets.QVBoxLayout(self)
        col.setContentsMargins(0, 0, 0, 0)
        col.addWidget(self.hint)
        col.addWidget(self.combo)
        self.hide()

    def open_for(self, types: Any) -> None:
        """Fill the chooser with the registry's action types and show the box."""
        self.combo.blockSignals(True)
        self.combo.clear()
        self.combo.addItem("— choose the action's type —", None)
        for t in known_action_types(types):
            self.combo.addItem(pkg_type(t), t)
            self.combo.setItemData(self.combo.count() - 1, t, QtCore.Qt.ItemDataRole.ToolTipRole)
        self.combo.setCurrentIndex(0)
        self.combo.blockSignals(False)
        self.show()

    def choose(self, type_name: str) -> None:
        """Pick ``type_name`` (as the operator would)."""
        index = self.combo.findData(type_name)
        if index < 0:
            raise ValueError(f"{type_name!r} is not a known action type")
        self.combo.setCurrentIndex(index)

    def _changed(self, index: int) -> None:
        value = self.combo.itemData(index)
        if isinstance(value, str):
            self.chosen.emit(value)
