"""Side panel listing the robot's topics, services and actions (name, type, live rate), with a filter.

Each row is the name over its type. A narrow column cuts each line on its own (:class:`NameTypeDelegate`):
the name in the middle (both ends of a topic name tell), the type by its package first
(``sensor_msgs/BatteryState`` -> ``sensor_…/BatteryState`` -> ``…/BatteryState``), so the type's own name
is never cut while anything else can give way.

Decision: at most ``MAX_ROWS`` rows, changed by differences
    10^5 topics froze the panel 6.3 s at every change (the whole list cleared and built again, and a Qt
    list of 10^5 rows costs its whole length on every change). The list shows the first ``MAX_ROWS``
    entries that match the search (in name order) and says how many there are in all ("Showing the first
    1,000 of 100,000 topics: search to find the others"); a new catalogue changes only the rows that
    differ, and a search over a long list is done a slice per pass (``PASS_BUDGET`` seconds each, one
    pass per frame). An empty list says why it is empty (:meth:`CatalogList.set_status`: connecting,
    listing, lost, or the robot has none).
"""

from __future__ import annotations

import time
from collections.abc import Iterator

from qtpy import QtCore, QtGui, QtWidgets

from rcon_core.msgs.names import pkg_type

NAME_ROLE = QtCore.Qt.ItemDataRole.UserRole
#: the second line of an entry whose type the robot did not tell
UNKNOWN = "type unknown"
TYPE_ROLE = QtCore.Qt.ItemDataRole.UserRole + 1
#: rows a list shows at most (the first that match the search, in name order)
MAX_ROWS = 1000
#: seconds of searching per pass over a long list (then the next frame goes on)
PASS_BUDGET = 0.010


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
        self._hints = {
            "offline": empty or f"No {what} yet: connect to a robot.",
            "connecting": f"No {what} yet: connecting to the robot…",
            "listing": f"Listing the robot's {what}…",
            "listed": empty or f"The robot lists no {what}.",
            "lost": f"The link to the robot is lost: its {what} are listed again when it is back.",
        }
        self.status = "offline"
        #: under the list when it does not show every entry: how many there are, and how to find them
        self.more = QtWidgets.QLabel("")
        self.more.setObjectName(f"{what}More")
        self.more.setProperty("role", "hint")
        self.more.setWordWrap(True)
        self.more.hide()
        col = QtWidgets.QVBoxLayout(self)
        col.setContentsMargins(0, 0, 0, 0)
        col.addWidget(self.filter)
        col.addWidget(self.empty)
        col.addWidget(self.tree, 1)
        col.addWidget(self.more)
        self._items: dict[str, QtWidgets.QTreeWidgetItem] = {}  # the rows shown, by name
        self._shown: list[tuple[str, str]] = []  # (name, type) of the rows shown, in their order
        self._entries: list[tuple[str, str]] = []  # every entry of the catalogue (sorted by name)
        self._given: object = None  # the list last given (the same object again costs nothing)
        self._with_rate = with_rate
        self._rated: set[str] = set()  # rows showing a rate
        self._words: list[str] = []
        self._search: Iterator[None] | None = None  # a search over a long list, a slice per pass
        self._work = QtCore.QTimer(self)
        self._work.setSingleShot(True)
        self._work.setInterval(16)  # a frame: the window paints between two slices
        self._work.timeout.connect(self._go_on)
        #: how many entries match the search (all of them without one), for the note under the list
        self.matching = 0

    # ------------------------------------------------------------------------------------- status
    def set_status(self, status: str) -> None:
        """What an empty list says: "offline", "connecting", "listing", "listed" (the robot has none) or
        "lost" (the link dropped)."""
        if status == self.status or status not in self._hints:
            return
        self.status = status
        self.empty.setText(self._hints[status])

    def set_listed_hint(self, text: str) -> None:
        """What the list says when the robot lists none (a Foxglove robot's actions: what it cannot do)."""
        self._hints["listed"] = text
        if self.status == "listed":
            self.empty.setText(text)

    @property
    def filling(self) -> bool:
        """Whether a search over a long list is still going on (a slice per pass)."""
        return self._search is not None

    @property
    def total(self) -> int:
        """Entries in the catalogue (shown or not)."""
        return len(self._entries)

    # ------------------------------------------------------------------------------------ entries
    def set_entries(self, entries: list[tuple[str, str]]) -> None:
        """Show ``entries`` (sorted by name), keeping the selection and the search: the first
        ``MAX_ROWS`` that match, changing only the rows that differ (see the module docstring)."""
        if entries is self._given or entries == self._entries:  # the same catalogue again: nothing to do
            return
        self._given = entries
        self._entries = list(entries)
        self.empty.setVisible(not self._entries)
        self._refresh_window()

    def _refresh_window(self) -> None:
        self._search = None
        if not self._words:  # no search: the first rows, at once
            self._show(self._entries[:MAX_ROWS], len(self._entries))
            return
        self._search = self._searching()
        self._go_on()

    def _searching(self) -> Iterator[None]:
        found: list[tuple[str, str]] = []
        matched = 0
        words = self._words
        for i, (name, type_name) in enumerate(self._entries):
            hay = f"{name} {type_name}".lower()
            if all(w in hay for w in words):
                matched += 1
                if len(found) < MAX_ROWS:
                    found.append((name, type_name))
            if i % 1000 == 999:
                yield
        self._show(found, matched)

    def _go_on(self) -> None:
        """Search on for at most ``PASS_BUDGET``; the rest in the next pass."""
        search = self._search
        if search is None:
            return
        deadline = time.perf_counter() + PASS_BUDGET
        try:
            while time.perf_counter() < deadline:
                next(search)
        except StopIteration:
            if self._search is search:
                self._search = None
            return
        if not self._work.isActive():
            self._work.start()

    def _show(self, rows: list[tuple[str, str]], matching: int) -> None:
        """Make the tree show ``rows`` (at most ``MAX_ROWS``): rows kept stay, the others are taken out or
        put in at their place; the selection stays when its row does."""
        self.matching = matching
        self._say_more(len(rows), matching)
        if rows == self._shown:
            return
        selected = self.current()
        wanted = dict(rows)
        tree = self.tree
        for at in range(len(self._shown) - 1, -1, -1):  # from the end: the indexes before stay right
            name, type_name = self._shown[at]
            if wanted.get(name) != type_name:
                tree.takeTopLevelItem(at)
                self._items.pop(name, None)
                self._rated.discard(name)
        run: list[QtWidgets.QTreeWidgetItem] = []  # new rows next to each other go in in one call
        for at, (name, type_name) in enumerate(rows):
            if name in self._items:
                if run:
                    tree.insertTopLevelItems(at - len(run), run)
                    run = []
                continue
            item = self._items[name] = self._make(name, type_name)
            run.append(item)
        if run:
            tree.insertTopLevelItems(len(rows) - len(run), run)
        if selected is not None and (chosen := self._items.get(selected[0])) is not None:
            chosen.setSelected(True)
        self._shown = list(rows)

    def _make(self, name: str, type_name: str) -> QtWidgets.QTreeWidgetItem:
        item = QtWidgets.QTreeWidgetItem([f"{name}\n{pkg_type(type_name) or UNKNOWN}"])
        item.setData(0, NAME_ROLE, name)
        item.setData(0, TYPE_ROLE, type_name)
        item.setToolTip(0, f"{name}\n{type_name}")
        return item

    def _say_more(self, shown: int, matching: int) -> None:
        if not matching and self._words and self._entries:
            text = f"No {self.what} match “{' '.join(self._words)}” (of {len(self._entries):,})."
        elif matching > shown:
            which = f" matching “{' '.join(self._words)}”" if self._words else ""
            text = (f"Showing the first {shown:,} of {matching:,} {self.what}{which}: search to find the "
                    "others.")
        else:
            text = ""
        if text != self.more.text():
            self.more.setText(text)
        self.more.setVisible(bool(text))

    # -------------------------------------------------------------------------------------- rates
    def set_rates(self, rates: dict[str, float]) -> None:
        """The rate of each listed topic that has one (rows that had one and have none lose it); only the
        rows shown are touched."""
        if not self._with_rate:
            return
        for name in [n for n in self._rated if n not in rates]:
            item = self._items.get(name)
            if item is not None and item.text(1):
                item.setText(1, "")
            self._rated.discard(name)
        for name, hz in rates.items():
            item = self._items.get(name)
            if item is None:
                continue
            text = "" if hz is None else (f"{hz:.0f} Hz" if hz >= 10 else f"{hz:.1f} Hz")
            if item.text(1) != text:
                item.setText(1, text)
            self._rated.add(name)

    def current(self) -> tuple[str, str] | None:
        item = self.tree.currentItem()
        if item is None:
            return None
        return item.data(0, NAME_ROLE), item.data(0, TYPE_ROLE)

    def item(self, name: str) -> QtWidgets.QTreeWidgetItem | None:
        """The row of ``name`` when it is shown."""
        return self._items.get(name)

    def _apply_filter(self, text: str) -> None:
        """Show the entries holding every word (name or type), the first ``MAX_ROWS`` of them; over a
        long list the search goes on a slice per pass."""
        self._words = text.lower().split()
        self._refresh_window()

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

