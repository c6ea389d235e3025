"""Side panel: every widget the plugin manager found, grouped by what it is for (the spec's category)."""

from __future__ import annotations

from qtpy import QtCore, QtWidgets

from rcon_core.plugins import WidgetSpec

KIND_ROLE = QtCore.Qt.ItemDataRole.UserRole
#: the lower-case text a search looks in: title, kind, description, category, accepted types
SEARCH_ROLE = QtCore.Qt.ItemDataRole.UserRole + 1
#: the group of widgets whose spec names no category
OTHER = "Other"

NO_WIDGETS = (
    "No widget plugins are installed, so there is nothing to add yet. Install a widget package "
    "(for example rcon-widgets-std) and restart RCON."
)


def search_text(spec: WidgetSpec) -> str:
    """Everything a search for a widget may hit, lower-case."""
    accepts = " ".join(spec.accepts.describe())
    parts = (spec.title, spec.kind, spec.description, spec.category, spec.package, accepts)
    return " ".join(p for p in parts if p).lower()


def tooltip(spec: WidgetSpec) -> str:
    lines = [spec.title]
    if spec.description:
        lines.append(spec.description)
    accepts = spec.accepts.describe()
    if accepts:
        lines.append("Accepts: " + ", ".join(accepts))
    lines.append(f"{spec.kind} · from {spec.package or 'an unnamed package'}")
    return "\n".join(lines)


class PalettePanel(QtWidgets.QWidget):
    """Lists widget kinds; ``picked(kind)`` fires when one is tapped."""

    picked = QtCore.Signal(str)

    def __init__(self, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.filter = QtWidgets.QLineEdit()
        self.filter.setObjectName("widgetFilter")
        self.filter.setPlaceholderText("Search widgets (name, type, what it does)…")
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
        self.no_match = QtWidgets.QLabel("No widget matches the search.")
        self.no_match.setProperty("role", "hint")
        self.no_match.hide()
        col = QtWidgets.QVBoxLayout(self)
        col.setContentsMargins(0, 0, 0, 0)
        col.addWidget(self.filter)
        col.addWidget(self.empty)
        col.addWidget(self.no_match)
        col.addWidget(self.tree, 1)
        self._items: dict[str, QtWidgets.QTreeWidgetItem] = {}
        self.groups: dict[str, QtWidgets.QTreeWidgetItem] = {}
        self.set_specs([])

    def set_specs(self, specs: list[WidgetSpec]) -> None:
        self.tree.clear()
        self._items = {}
        self.groups = {}
        # groups by category, alphabetically, "Other" last; widgets by title inside a group
        ordered = sorted(specs, key=lambda s: (not s.category, (s.category or "").lower(), s.title.lower()))
        for spec in ordered:
            category = spec.category or OTHER
            group = self.groups.get(category)
            if group is None:
                group = QtWidgets.QTreeWidgetItem([category])
                group.setFlags(QtCore.Qt.ItemFlag.ItemIsEnabled)
                font = group.font(0)
                font.setBold(True)
                group.setFont(0, font)
                self.groups[category] = group
                self.tree.addTopLevelItem(group)
            # the title, with where it comes from on a second line
            item = QtWidgets.QTreeWidgetItem([f"{spec.title}\n{spec.package}" if spec.package else spec.title])
            item.setData(0, KIND_ROLE, spec.kind)
            item.setData(0, SEARCH_ROLE, search_text(spec))
            item.setToolTip(0, tooltip(spec))
            group.addChild(item)
            self._items[spec.kind] = item
        self.tree.expandAll()
        self.empty.setVisible(not specs)
        self.tree.setVisible(bool(specs))
        self.filter.setVisible(bool(specs))
        self._apply_filter(self.filter.text())

    def item(self, kind: str) -> QtWidgets.QTreeWidgetItem | None:
        return self._items.get(kind)

    def _apply_filter(self, text: str) -> None:
        words = text.lower().split()
        for item in self._items.values():
            hay = item.data(0, SEARCH_ROLE) or ""
            item.setHidden(not all(w in hay for w in words))
        shown = 0
        for group in self.groups.values():  # a group with no match is hidden, not left empty
            children = (group.child(i) for i in range(group.childCount()))
            visible = any(child is not None and not child.isHidden() for child in children)
            group.setHidden(not visible)
            shown += visible
        self.no_match.setVisible(bool(self._items) and bool(words) and not shown)

    def _clicked(self, item: QtWidgets.QTreeWidgetItem, _col: int = 0) -> None:
        kind = item.data(0, KIND_ROLE)
        if kind:
            self.picked.emit(kind)
