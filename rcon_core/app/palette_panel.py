"""Side panel: every widget the plugin manager found, grouped by package."""

from __future__ import annotations

from qtpy import QtCore, QtWidgets

from rcon_core.plugins import WidgetSpec

KIND_ROLE = QtCore.Qt.ItemDataRole.UserRole

NO_WIDGETS = (
    "No widget plugins are installed, so there is nothing to add yet. Install a widget package "
    "(for example rcon-widgets-std) and restart RCON."
)


class PalettePanel(QtWidgets.QWidget):
    """Lists widget kinds; ``picked(kind)`` fires when one is tapped."""

    picked = QtCore.Signal(str)

    def __init__(self, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.filter = QtWidgets.QLineEdit()
        self.filter.setObjectName("widgetFilter")
        self.filter.setPlaceholderText("Search widgets…")
        self.filter.setClearButtonEnabled(True)
        self.filter.textChanged.connect(self._apply_filter)
        self.tree = QtWidgets.QTreeWidget()
        self.tree.setObjectName("paletteList")
        self.tree.setHeaderHidden(True)
        self.tree.itemClicked.connect(self._clicked)
        self.tree.itemActivated.connect(self._clicked)
        QtWidgets.QScroller.grabGesture(
            self.tree.viewport(), QtWidgets.QScroller.ScrollerGestureType.LeftMouseButtonGesture
        )
        self.empty = QtWidgets.QLabel(NO_WIDGETS)
        self.empty.setObjectName("paletteEmpty")
        self.empty.setWordWrap(True)
        self.empty.setProperty("role", "hint")
        col = QtWidgets.QVBoxLayout(self)
        col.setContentsMargins(0, 0, 0, 0)
        col.addWidget(self.filter)
        col.addWidget(self.empty)
        col.addWidget(self.tree, 1)
        self._items: dict[str, QtWidgets.QTreeWidgetItem] = {}
        self.set_specs([])

    def set_specs(self, specs: list[WidgetSpec]) -> None:
        self.tree.clear()
        self._items = {}
        groups: dict[str, QtWidgets.QTreeWidgetItem] = {}
        for spec in sorted(specs, key=lambda s: (s.package or "", s.title.lower())):
            package = spec.package or "other"
            group = groups.get(package)
            if group is None:
                group = QtWidgets.QTreeWidgetItem([package])
                group.setFlags(QtCore.Qt.ItemFlag.ItemIsEnabled)
                font = group.font(0)
                font.setBold(True)
                group.setFont(0, font)
                groups[package] = group
                self.tree.addTopLevelItem(group)
            item = QtWidgets.QTreeWidgetItem([spec.title])
            item.setData(0, KIND_ROLE, spec.kind)
            item.setToolTip(0, f"{spec.kind}: {spec.description}" if spec.description else spec.kind)
            group.addChild(item)
            self._items[spec.kind] = item
        self.tree.expandAll()
        self.empty.setVisible(not specs)
        self.tree.setVisible(bool(specs))
        self.filter.setVisible(bool(specs))

    def item(self, kind: str) -> QtWidgets.QTreeWidgetItem | None:
        return self._items.get(kind)

    def _apply_filter(self, text: str) -> None:
        words = text.lower().split()
        for kind, item in self._items.items():
            hay = f"{kind} {item.text(0)}".lower()
            item.setHidden(not all(w in hay for w in words))

    def _clicked(self, item: QtWidgets.QTreeWidgetItem, _col: int = 0) -> None:
        kind = item.data(0, KIND_ROLE)
        if kind:
            self.picked.emit(kind)
