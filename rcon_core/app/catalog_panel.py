"""Side panel listing the robot's topics, services and actions (name, type, live rate), with a filter.

Each row is the name over its type. A narrow column cuts each line on its own (:class:`NameTypeDelegate`):
the name in the middle (both ends of a topic name tell), the type by its package first
(``sensor_msgs/BatteryState`` -> ``sensor_…/BatteryState`` -> ``…/BatteryState``), so the type's own name
is never cut while anything else can give way."""

from __future__ import annotations

from qtpy import QtCore, QtGui, QtWidgets

from rcon_core.msgs.names import pkg_type

NAME_ROLE = QtCore.Qt.ItemDataRole.UserRole
#: the second line of an entry whose type the robot did not tell
UNKNOWN = "type unknown"
TYPE_ROLE = QtCore.Qt.ItemDataRole.UserRole + 1


class CatalogList(QtWidgets.QWidget):
    """One filterable list (topics, services or actions). ``picked(name, type)`` fires on tap."""

    picked = QtCore.Signal(str, str)

    def __init__(self, what: str, with_rate: bool, parent: QtWidgets.QWidget | None = None, *,
                 empty: str = "") -> None:
        super().__init__(parent)
        self.what = what
        self.filter = QtWidgets.QLineEdit()
        self.filter.setObjectName(f"{what}Filter")
        self.filter.setPlaceholderText(f"Search {what}…")
        self.filter.setClearButtonEnabled(True)
        self.filter.textChanged.connect(self._apply_filter)
        self.tree = QtWidgets.QTreeWidget()
        self.tree.setObjectName(f"{what}List")
        self.tree.setRootIsDecorated(False)
        self.tree.setUniformRowHeights(True)
        # the name with its type on a second line: the panel is narrow, names are long
        label = what[:-1].capitalize()  # "topics" -> "Topic"
        self.tree.setHeaderLabels([f"{label} / type", "Rate"] if with_rate else [f"{label} / type"])
        header = self.tree.header()
        header.setSectionResizeMode(0, QtWidgets.QHeaderView.ResizeMode.Stretch)
        header.setStretchLastSection(False)
        if with_rate:
            header.setSectionResizeMode(1, QtWidgets.QHeaderView.ResizeMode.Fixed)
            header.resizeSection(1, 76)
        self.tree.setHorizontalScrollBarPolicy(QtCore.Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        self.tree.setTextElideMode(QtCore.Qt.TextElideMode.ElideMiddle)
        self.delegate = NameTypeDelegate(self.tree)
        self.tree.setItemDelegateForColumn(0, self.delegate)
        self.tree.itemClicked.connect(self._clicked)
        self.tree.itemActivated.connect(self._clicked)
        QtWidgets.QScroller.grabGesture(
            self.tree.viewport(), QtWidgets.QScroller.ScrollerGestureType.LeftMouseButtonGesture
        )
        self.empty = QtWidgets.QLabel(empty or f"No {what} yet: connect to a robot.")
        self.empty.setProperty("role", "hint")
        self.empty.setWordWrap(True)
        col = QtWidgets.QVBoxLayout(self)
        col.setContentsMargins(0, 0, 0, 0)
        col.addWidget(self.filter)
        col.addWidget(self.empty)
        col.addWidget(self.tree, 1)
        self._items: dict[str, QtWidgets.QTreeWidgetItem] = {}
        self._with_rate = with_rate

    def set_entries(self, entries: list[tuple[str, str]]) -> None:
        """Replace the list (keeps the selection and the filter)."""
        names = {n for n, _ in entries}
        if names == set(self._items) and all(self._items[n].data(0, TYPE_ROLE) == t for n, t in entries):
            return
        selected = self.current()
        self.tree.clear()
        self._items = {}
        for name, type_name in entries:
            item = QtWidgets.QTreeWidgetItem([f"{name}\n{pkg_type(type_name) or UNKNOWN}"])
            item.setData(0, NAME_ROLE, name)
            item.setData(0, TYPE_ROLE, type_name)
            item.setToolTip(0, f"{name}\n{type_name}")
            self.tree.addTopLevelItem(item)
            self._items[name] = item
            if selected and selected[0] == name:
                item.setSelected(True)
        self.empty.setVisible(not entries)
        self._apply_filter(self.filter.text())

    def set_rates(self, rates: dict[str, float]) -> None:
        if not self._with_rate:
            return
        for name, item in self._items.items():
            hz = rates.get(name)
            text = "" if hz is None else (f"{hz:.0f} Hz" if hz >= 10 else f"{hz:.1f} Hz")
            if item.text(1) != text:
                item.setText(1, text)

    def current(self) -> tuple[str, str] | None:
        item = self.tree.currentItem()
        if item is None:
            return None
        return item.data(0, NAME_ROLE), item.data(0, TYPE_ROLE)

    def item(self, name: str) -> QtWidgets.QTreeWidgetItem | None:
        return self._items.get(name)

    def _apply_filter(self, text: str) -> None:
        words = text.lower().split()
        for name, item in self._items.items():
            hay = f"{name} {item.data(0, TYPE_ROLE)}".lower()
            item.setHidden(not all(w in hay for w in words))

    def _clicked(self, item: QtWidgets.QTreeWidgetItem, _col: int = 0) -> None:
        self.picked.emit(item.data(0, NAME_ROLE), item.data(0, TYPE_ROLE))


def elide_type(metrics: QtGui.QFontMetrics, type_name: str, width: int) -> str:
    """``type_name`` (short form) fitted into ``width`` px: the package is cut first, the type's own name
    last (and then only at its end)."""
    full = pkg_type(type_name)
    if metrics.horizontalAdvance(full) <= width or "/" not in full:
        return full if metrics.horizontalAdvance(full) <= width else metrics.elidedText(
            full, QtCore.Qt.TextElideMode.ElideRight, width)
    package, name = full.rsplit("/", 1)
    room = width - metrics.horizontalAdvance(f"/{name}")
    if room >= metrics.horizontalAdvance("…"):
        return metrics.elidedText(package, QtCore.Qt.TextElideMode.ElideRight, room) + f"/{name}"
    return metrics.elidedText(name, QtCore.Qt.TextElideMode.ElideRight, width)


class NameTypeDelegate(QtWidgets.QStyledItemDelegate):
    """Paints a catalog row's two lines, each cut on its own (see the module docstring)."""

    def lines(self, index: QtCore.QModelIndex | QtCore.QPersistentModelIndex,
              option: QtWidgets.QStyleOptionViewItem) -> str:
        """The text painted for the row at ``index`` given ``option``'s rect and font."""
        opt = QtWidgets.QStyleOptionViewItem(option)
        self.initStyleOption(opt, index)
        name, type_name = index.data(NAME_ROLE), index.data(TYPE_ROLE)
        if name is None or type_name is None:
            return opt.text
        widget = opt.widget
        style = widget.style() if widget is not None else QtWidgets.QApplication.style()
        text_rect = style.subElementRect(QtWidgets.QStyle.SubElement.SE_ItemViewItemText, opt, widget)
        width = max(0, text_rect.width() - 8)  # the style's own text margins
        fm = opt.fontMetrics
        line_break = "\u2028"  # what the item delegate makes of "\\n": the style breaks lines only there
        shown = elide_type(fm, type_name, width) if type_name else UNKNOWN
        return f"{fm.elidedText(name, QtCore.Qt.TextElideMode.ElideMiddle, width)}{line_break}{shown}"

    def paint(self, painter: QtGui.QPainter, option: QtWidgets.QStyleOptionViewItem,
              index: QtCore.QModelIndex | QtCore.QPersistentModelIndex) -> None:
        opt = QtWidgets.QStyleOptionViewItem(option)
        self.initStyleOption(opt, index)
        opt.text = self.lines(index, option)
        widget = opt.widget
        style = widget.style() if widget is not None else QtWidgets.QApplication.style()
        style.drawControl(QtWidgets.QStyle.ControlElement.CE_ItemViewItem, opt, painter, widget)

