"""Side panel listing the robot's parameters, by node (ROS 2) or namespace (ROS 1), with search and edit.

Every rosapi call runs on the bridge thread (``client.params``, see ``rcon_core/bridge/params.py``); its
answer is queued and the GUI thread is woken to take it (:class:`~rcon_core.app.frame_clock.Waker`, a
posted event), so the GUI never waits on the network.
The list is fetched when the panel is first shown while connected and when the operator taps Refresh
(parameters change rarely and a robot may hold hundreds: no polling).

Editing: tap a parameter, type the new value and tap Set. The text is read as YAML and must have the
current value's kind (``params.parse_like``: an int where an int is, ``true``/``false`` for a bool, a list
of the same kind of items for a list; a string needs no quotes; an int is taken where a float is). A text
that does not fit is refused on the spot, naming what was expected. A good value is written only after the
operator confirms ("Set /kingfisher:max_speed to 2.5?"); then it is read back, and a value the node did not
take (ROS 2 nodes silently refuse undeclared names and other types) is reported as refused, not as set.

While the operator lock is on, Set asks for the PIN first (``gate``, the window's lock; issue 21.2). A robot
marked view-only refuses the write on its link (``rcon_core.bridge.guard``): the editor says so when it
opens, and a write that gets that far is shown refused with the link's sentence (issue 21.1).
"""

from __future__ import annotations

import asyncio
import logging
import queue
from collections.abc import Callable
from typing import Any

from qtpy import QtCore, QtWidgets

from rcon_core.app.frame_clock import Waker
from rcon_core.app.operator_lock import Guard, no_guard
from rcon_core.bridge import ViewOnlyError
from rcon_core.bridge import params as P
from rcon_core.bridge.params import ParamRejectedError

log = logging.getLogger(__name__)

NAME_ROLE = QtCore.Qt.ItemDataRole.UserRole
#: at most this many get_param calls in flight at once while listing
CONCURRENT_GETS = 16
#: confirm(question, detail, yes, then): the main window's two-button question
Confirm = Callable[[str, str, str, Callable[[], object]], object]
#: gate(what, then): runs ``then`` now, or after the operator PIN while the lock is on
Gate = Guard


async def fetch_params(client: Any) -> tuple[bool, dict[str, dict[str, Any]]]:
    """``(ros2, {owner: {name: value}})`` of every parameter (bridge thread)."""
    params = client.params
    ros2 = await params.ros2()
    groups = await params.by_owner()
    gate = asyncio.Semaphore(CONCURRENT_GETS)

    async def one(name: str) -> Any:
        async with gate:
            try:
                return await params.get(name, default=None)
            except Exception as exc:  # one unreadable parameter does not hide the others
                return _Unreadable(str(exc))

    names = [n for owned in groups.values() for n in owned]
    values = await asyncio.gather(*(one(n) for n in names))
    by_name = dict(zip(names, values, strict=True))
    return ros2, {owner: {n: by_name[n] for n in owned} for owner, owned in groups.items()}


class _Unreadable:
    def __init__(self, why: str) -> None:
        self.why = why

    def __repr__(self) -> str:
        return f"(unreadable: {self.why})"


def value_text(value: Any) -> str:
    """A value as the operator reads and types it (YAML flow style)."""
    if isinstance(value, _Unreadable):
        return repr(value)
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return value
    if value is None:
        return "(not set)"
    import yaml

    return yaml.safe_dump(value, default_flow_style=True, width=10_000).strip().removesuffix("...").strip()


def _children(head: QtWidgets.QTreeWidgetItem) -> list[QtWidgets.QTreeWidgetItem]:
    kids = (head.child(j) for j in range(head.childCount()))
    return [kid for kid in kids if kid is not None]


class ParamsPanel(QtWidgets.QWidget):
    """The Parameters tab. ``link`` is the app's :class:`~rcon_core.app.link.RobotConnection`."""

    def __init__(self, link: Any, confirm: Confirm, parent: QtWidgets.QWidget | None = None, *,
                 gate: Gate = no_guard) -> None:
        super().__init__(parent)
        self.link = link
        self.confirm = confirm
        #: the operator lock's PIN gate (the window's lock; by default nothing is asked)
        self.gate: Gate = gate
        self.ros2 = False
        self.values: dict[str, Any] = {}
        self.loaded_for: Any = None  # the client the list was fetched from
        self.busy = False
        #: (handler, outcome) from the bridge thread, taken on the GUI thread when the waker fires
        self._inbox: queue.SimpleQueue[tuple[Callable[[Any], None], Any]] = queue.SimpleQueue()
        self._waker = Waker(lambda _keys: self._take(), self)
        self.filter = QtWidgets.QLineEdit()
        self.filter.setObjectName("paramsFilter")
        self.filter.setPlaceholderText("Search parameters…")
        self.filter.setClearButtonEnabled(True)
        self.filter.textChanged.connect(self._apply_filter)
        self.refresh_button = QtWidgets.QPushButton("⟳ Refresh")
        self.refresh_button.setObjectName("paramsRefresh")
        self.refresh_button.clicked.connect(self.refresh)
        top = QtWidgets.QHBoxLayout()
        top.addWidget(self.filter, 1)
        top.addWidget(self.refresh_button)
        self.tree = QtWidgets.QTreeWidget()
        self.tree.setObjectName("paramsList")
        # each row is the parameter's name over its value: the column is narrow, both may be long
        self.tree.setHeaderLabels(["Parameter / value"])
        self.tree.setUniformRowHeights(True)
        self.tree.setIndentation(14)
        self.tree.setHorizontalScrollBarPolicy(QtCore.Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        self.tree.setTextElideMode(QtCore.Qt.TextElideMode.ElideMiddle)
        self.tree.itemClicked.connect(self._picked)
        self.tree.itemActivated.connect(self._picked)
        QtWidgets.QScroller.grabGesture(self.tree.viewport(),
                                        QtWidgets.QScroller.ScrollerGestureType.LeftMouseButtonGesture)
        self.status = QtWidgets.QLabel("Connect to a robot to see its parameters.")
        self.status.setObjectName("paramsStatus")
        self.status.setProperty("role", "hint")
        self.status.setWordWrap(True)
        # the editor of the parameter tapped last
        self.editor = QtWidgets.QFrame()
        self.editor.setObjectName("paramEditor")
        self.edit_name = QtWidgets.QLabel()
        self.edit_name.setObjectName("paramName")
        self.edit_name.setWordWrap(True)
        self.edit_kind = QtWidgets.QLabel()
        self.edit_kind.setProperty("role", "hint")
        self.edit_value = QtWidgets.QLineEdit()
        self.edit_value.setObjectName("paramValue")
        self.edit_value.returnPressed.connect(self.set_clicked)
        self.edit_problem = QtWidgets.QLabel()
        self.edit_value.textChanged.connect(lambda _t: self.edit_problem.setText(""))
        self.set_button = QtWidgets.QPushButton("Set…")
        self.set_button.setObjectName("paramSet")
        self.set_button.setProperty("primary", True)
        self.set_button.clicked.connect(self.set_clicked)
        self.edit_problem.setObjectName("paramProblem")
        self.edit_problem.setProperty("role", "problem")
        self.edit_problem.setWordWrap(True)
        row = QtWidgets.QHBoxLayout()
        row.addWidget(self.edit_value, 1)
        row.addWidget(self.set_button)
        box = QtWidgets.QVBoxLayout(self.editor)
        box.setContentsMargins(0, 6, 0, 0)
        for w in (self.edit_name, self.edit_kind):
            box.addWidget(w)
        box.addLayout(row)
        box.addWidget(self.edit_problem)
        self.editor.hide()
        col = QtWidgets.QVBoxLayout(self)
        col.setContentsMargins(0, 0, 0, 0)
        col.addLayout(top)
        col.addWidget(self.status)
        col.addWidget(self.tree, 1)
        col.addWidget(self.editor)
        self._editing: str | None = None

    # -- fetching ---------------------------------------------------------------------------------
    def _run(self, coro_fn: Callable[[Any], Any], handler: Callable[[Any], None]) -> bool:
        """Run ``coro_fn(client)`` on the bridge thread; ``handler((ok, result_or_error))`` on the GUI one."""
        client = self.link.client
        if client is None:
            self.status.setText("Connect to a robot to see its parameters.")
            return False
        future = self.link.thread.run(coro_fn(client))

        def done(fut: Any) -> None:  # bridge thread
            exc = fut.exception()
            self._inbox.put((handler, (False, exc) if exc is not None else (True, fut.result())))
            self._waker.poke()

        future.add_done_callback(done)
        return True

    def _take(self) -> None:
        while True:
            try:
                handler, outcome = self._inbox.get_nowait()
            except queue.Empty:
                return
            try:
                handler(outcome)
            except Exception:  # one bad answer must not stop the others
                log.exception("parameters panel: handling an answer failed")

    def follow(self, link: Any) -> None:
        """Show ``link``'s robot's parameters (the side panel's robot changed)."""
        if self.link is not link:
            self.link = link
            self.client_changed(link.client)

    def client_changed(self, client: Any) -> None:
        """A new robot (or none): the old list goes; fetched again at once when the panel is in sight."""
        self.tree.clear()
        self.values = {}
        self.editor.hide()
        self._editing = None
        self.loaded_for = None
        self.status.setText("Connect to a robot to see its parameters." if client is None else
                            "Tap Refresh to list the robot's parameters.")
        if client is not None and self.isVisible():
            QtCore.QTimer.singleShot(0, self, self.refresh)

    def showEvent(self, event: Any) -> None:  # noqa: N802 - Qt override
        super().showEvent(event)
        if self.loaded_for is not self.link.client and self.link.client is not None and not self.busy:
            self.refresh()

    def refresh(self) -> None:
        """Fetch every parameter again (the operator's Refresh)."""
        if self.busy:
            return
        client = self.link.client
        if self._run(fetch_params, self._listed):
            self.busy = True
            self.loaded_for = client
            self.refresh_button.setEnabled(False)
            self.status.setText("Loading parameters…")

    def _listed(self, outcome: tuple[bool, Any]) -> None:
        self.busy = False
        self.refresh_button.setEnabled(True)
        ok, got = outcome
        if not ok:
            self.loaded_for = None
            self.status.setText(f"Could not list parameters: {got}")
            return
        self.ros2, groups = got
        self._fill(groups)
        count = sum(len(v) for v in groups.values())
        owners = "node" if self.ros2 else "namespace"
        self.status.setText(f"{count} parameters in {len(groups)} {owners}{'s' if len(groups) != 1 else ''}"
                            if count else "The robot has no parameters.")

    def _fill(self, groups: dict[str, dict[str, Any]]) -> None:
        expanded = {head.text(0) for head in self._heads() if head.isExpanded()}
        self.tree.clear()
        self.values = {}
        for owner, owned in groups.items():
            head = QtWidgets.QTreeWidgetItem([owner, ""])
            head.setFirstColumnSpanned(True)
            self.tree.addTopLevelItem(head)
            for name, value in owned.items():
                _owner, short = P.split(name, self.ros2)
                item = QtWidgets.QTreeWidgetItem([""])
                item.setData(0, NAME_ROLE, name)
                self._show_value(item, short, value)
                head.addChild(item)
                self.values[name] = value
            head.setExpanded(not expanded or owner in expanded)
        self._apply_filter(self.filter.text())

    @staticmethod
    def _show_value(item: QtWidgets.QTreeWidgetItem, short: str, value: Any) -> None:
        text = value_text(value) if value != "" else '""  (empty)'
        item.setText(0, f"{short}\n{text}")
        item.setToolTip(0, f"{item.data(0, NAME_ROLE)}\n{text}")

    def shown_value(self, name: str) -> str | None:
        """The value text the row of ``name`` shows (None when not listed)."""
        row = self.item(name)
        return None if row is None else row.text(0).split("\n", 1)[1]

    def item(self, name: str) -> QtWidgets.QTreeWidgetItem | None:
        """The row of parameter ``name`` (tests, and the editor)."""
        for head in self._heads():
            for child in _children(head):
                if child.data(0, NAME_ROLE) == name:
                    return child
        return None

    def _heads(self) -> list[QtWidgets.QTreeWidgetItem]:
        """The tree's top-level rows (one per node or namespace)."""
        heads = (self.tree.topLevelItem(i) for i in range(self.tree.topLevelItemCount()))
        return [head for head in heads if head is not None]

    def _apply_filter(self, text: str) -> None:
        words = text.lower().split()
        for head in self._heads():
            shown = 0
            for child in _children(head):
                hay = child.text(0).replace("\n", " ").lower() + " " + child.data(0, NAME_ROLE).lower()
                hit = all(w in hay for w in words)
                child.setHidden(not hit)
                shown += hit
            head.setHidden(shown == 0 and bool(words))
            if words and shown:
                head.setExpanded(True)

    # -- editing ----------------------------------------------------------------------------------
    def _picked(self, item: QtWidgets.QTreeWidgetItem, _col: int = 0) -> None:
        name = item.data(0, NAME_ROLE)
        if name is None:
            item.setExpanded(not item.isExpanded())
            return
        self.edit(name)

    def edit(self, name: str) -> None:
        """Open the editor on parameter ``name``."""
        value = self.values.get(name)
        self._editing = name
        self.edit_name.setText(name)
        editable = P.kind(value) in ("bool", "int", "float", "string", "list")
        self.edit_kind.setText(f"{P.kind(value)}: type a new value, then Set" if editable
                               else f"{P.kind(value)}: not editable here")
        self.edit_value.setText(value_text(value))
        self.edit_value.setEnabled(editable)
        self.set_button.setEnabled(editable)
        self.edit_problem.setText(self._view_only(name) or "")
        self.editor.show()

    def _view_only(self, name: str) -> str | None:
        """The link's sentence when the robot is view-only (its link refuses the write), else None."""
        guard = getattr(self.link.client, "guard", None)
        return guard.sentence(f"setting parameter {name}") if guard is not None and guard.view_only else None

    def set_clicked(self) -> None:
        name = self._editing
        if name is None:
            return
        current = self.values.get(name)
        try:
            value = P.parse_like(self.edit_value.text(), current)
        except ValueError as exc:
            self.edit_problem.setText(f"Not set: {exc}")
            return
        if value == current and P.kind(value) == P.kind(current):
            self.edit_problem.setText("That is the value it has already.")
            return
        refused = self._view_only(name)
        if refused:
            self.edit_problem.setText(refused)
            return
        self.gate(f"set {name}", lambda: self.confirm(
            f"Set {name}?", f"{value_text(current)}  →  {value_text(value)}\n\nThe robot uses the new value at "
            "once.", "Set it", lambda: self._write(name, value)))

    def _write(self, name: str, value: Any) -> None:
        async def write(client: Any) -> Any:
            await client.params.set(name, value, verify=True)
            return value

        def written(outcome: tuple[bool, Any]) -> None:
            ok, got = outcome
            if ok:
                self.values[name] = got
                row = self.item(name)
                if row is not None:
                    self._show_value(row, P.split(name, self.ros2)[1], got)
                self.status.setText(f"✓ {name} set to {value_text(got)}")
            elif isinstance(got, ViewOnlyError):  # the robot's link refused it: its sentence says why
                self.status.setText(f"✗ {got}")
                self.edit_problem.setText(str(got))
            else:
                what = "refused" if isinstance(got, ParamRejectedError) else "failed"
                self.status.setText(f"✗ Setting {name} {what}: {got}")
                self.edit_problem.setText(f"Not set: {got}")

        if self._run(write, written):
            self.status.setText(f"Setting {name}…")
