"""A topic that does not exist yet: the operator types its name and picks its type.

The add panel's *Topic* chooser (the widget pathway) ends with **+ New topic…**; choosing it shows this
box under the chooser: a name field and a type search. The types offered are those the widget can use in
its role (the matcher decides, as for any topic), from two places: the local type registry (every message
type RCON knows) and the robot's own types (those of the topics it lists now). Each is listed by its
short name, ``BatteryState  ·  sensor_msgs`` (the type name whole, its package after it), so a narrow
panel cuts the package, never the type's name. The search looks in the whole name (``battery``,
``sensor_msgs/Bat``).

A name is checked as a ROS graph name (:func:`topic_name_problem`): ``chat`` becomes ``/chat``; empty
segments, a trailing slash, spaces or a segment starting with a digit are refused with the reason. The
box emits ``changed`` whenever the pick changes; :meth:`NewTopicBox.target` is the resulting
:class:`~rcon_core.app.draft.Target`, or None while the name or the type is missing or wrong
(:meth:`NewTopicBox.problem` says which).
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterable
from typing import Any

from qtpy import QtCore, QtWidgets

from rcon_core.app.draft import Target
from rcon_core.app.settings_form import form_label, tune_form
from rcon_core.plugins import Role, WidgetSpec

__all__ = ["NEW_TOPIC", "add_new_topic_entry", "new_topic_index", "NewTopicBox", "topic_name_problem", "normalize_topic_name", "compatible_types", "new_target",
           "type_label"]

_SEGMENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
#: registry entries that are parts of services and actions, not messages one publishes on a topic
_PART_SUFFIXES = ("_Request", "_Response", "_Event")
_PART_MARKERS = ("_SendGoal_", "_GetResult_", "_FeedbackMessage")


#: item data role marking the target chooser's "+ New topic…" entry
NEW_TOPIC = QtCore.Qt.ItemDataRole.UserRole + 2


def add_new_topic_entry(combo: QtWidgets.QComboBox) -> int:
    """Append the chooser's *+ New topic…* entry (no target as its data); returns its index."""
    combo.addItem("+ New topic…", None)
    index = combo.count() - 1
    combo.setItemData(index, True, NEW_TOPIC)
    combo.setItemData(index, "A topic the robot does not have yet: type its name, pick its type",
                      QtCore.Qt.ItemDataRole.ToolTipRole)
    return index


def new_topic_index(combo: QtWidgets.QComboBox) -> int | None:
    """The index of the chooser's *+ New topic…* entry, None when it has none."""
    return next((i for i in range(combo.count()) if combo.itemData(i, NEW_TOPIC) is True), None)


def normalize_topic_name(name: str) -> str:
    """``chat`` -> ``/chat``; surrounding blanks dropped."""
    name = name.strip()
    return name if not name or name.startswith("/") else f"/{name}"


def topic_name_problem(name: str) -> str | None:
    """Why ``name`` (after :func:`normalize_topic_name`) cannot be a topic's name, or None."""
    name = normalize_topic_name(name)
    if not name:
        return "type the new topic's name (e.g. /chat)"
    if name == "/":
        return "'/' alone is not a topic name"
    if name.endswith("/"):
        return f"{name!r} ends with '/'"
    for segment in name[1:].split("/"):
        if not segment:
            return f"{name!r} has an empty part ('//')"
        if not _SEGMENT.fullmatch(segment):
            return (f"{segment!r} in {name!r}: a part of a topic name holds letters, digits and '_' only, "
                    "and does not start with a digit")
    return None


def _is_message(name: str) -> bool:
    return not name.endswith(_PART_SUFFIXES) and not any(m in name for m in _PART_MARKERS)


def type_label(type_name: str) -> str:
    """``sensor_msgs/msg/BatteryState`` -> ``BatteryState  ·  sensor_msgs``: the type name first and whole."""
    parts = type_name.split("/")
    return f"{parts[-1]}  ·  {parts[0]}" if len(parts) > 1 else type_name


def compatible_types(spec: WidgetSpec, role: Role, types: Any, plugins: Any,
                     robot_types: Iterable[str] = ()) -> list[str]:
    """Every message type ``spec`` can use in ``role``: the robot's types (as the robot spells them) and
    the registry's (as the registry's flavour sends them), one entry per type, sorted by short name."""
    from rcon_core.matcher import match
    from rcon_core.msgs.names import normalize

    out: dict[str, str] = {}  # canonical -> spelling to bind

    def consider(name: str, spelling: str) -> None:
        try:
            key = normalize(name)
        except ValueError:
            return
        if key in out:
            return
        try:
            fits = any(m.spec.kind == spec.kind for m in match(name, role, types, plugins))
        except ValueError:
            return
        if fits:
            out[key] = spelling

    for name in robot_types:
        consider(name, name)
    if types is not None:
        for name in types.names():
            if _is_message(name):
                consider(name, types.wire_name(name))
    return sorted(out.values(), key=lambda n: (n.rsplit("/", 1)[-1].lower(), n))


def new_target(spec: WidgetSpec, role: Role, name: str, type_name: str, types: Any, plugins: Any) -> Target:
    """The new topic as a target, with the fields ``spec`` binds on its type (as for a listed topic)."""
    from rcon_core.matcher import match

    for m in match(type_name, role, types, plugins):
        if m.spec.kind == spec.kind:
            return Target(name, type_name, (m.field_path,) if m.field_path else (), tuple(m.field_paths))
    return Target(name, type_name)


class NewTopicBox(QtWidgets.QFrame):
    """The new topic's name and type (see the module docstring)."""

    changed = QtCore.Signal()

    def __init__(self, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.setObjectName("newTopicBox")
        self._target_for: Callable[[str, str], Target] | None = None
        col = QtWidgets.QVBoxLayout(self)
        col.setContentsMargins(0, 0, 0, 0)
        self.name_edit = QtWidgets.QLineEdit()
        self.name_edit.setObjectName("newTopicName")
        self.name_edit.setPlaceholderText("New topic's name, e.g. /chat")
        self.name_edit.setAccessibleName("New topic name")
        self.name_edit.textChanged.connect(self._changed)
        self.search = QtWidgets.QLineEdit()
        self.search.setObjectName("newTopicSearch")
        self.search.setPlaceholderText("Search types, e.g. String")
        self.search.setAccessibleName("Search message types")
        self.search.textChanged.connect(self._filter)
        self.type_list = QtWidgets.QListWidget()
        self.type_list.setObjectName("newTopicTypes")
        self.type_list.setHorizontalScrollBarPolicy(QtCore.Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        self.type_list.setTextElideMode(QtCore.Qt.TextElideMode.ElideRight)  # the package goes first
        self.type_list.currentItemChanged.connect(lambda *_: self._changed())
        self.type_list.setMinimumHeight(150)
        self.problem_label = QtWidgets.QLabel()
        self.problem_label.setObjectName("newTopicProblem")
        self.problem_label.setProperty("role", "problem")
        self.problem_label.setWordWrap(True)
        form = tune_form(QtWidgets.QFormLayout())
        form.addRow(form_label("Name", self.name_edit), self.name_edit)
        form.addRow(form_label("Type", self.search), self.search)
        col.addLayout(form)
        col.addWidget(self.type_list)
        col.addWidget(self.problem_label)

    def open_for(self, spec: WidgetSpec, role: Role, types: Any, plugins: Any, robot_types: Iterable[str]) -> None:
        """Offer the types ``spec`` can use in ``role`` (:func:`compatible_types`)."""
        self.offer(compatible_types(spec, role, types, plugins, robot_types),
                   lambda name, type_name: new_target(spec, role, name, type_name, types, plugins))

    def offer(self, type_names: list[str], target_for: Callable[[str, str], Target]) -> None:
        """List ``type_names`` (keeping the one chosen when still offered); ``target_for(name, type)``
        makes the target (with the fields the widget binds on that type)."""
        self._target_for = target_for
        keep = self.chosen_type()
        self.type_list.blockSignals(True)
        self.type_list.clear()
        for name in type_names:
            item = QtWidgets.QListWidgetItem(type_label(name))
            item.setData(QtCore.Qt.ItemDataRole.UserRole, name)
            item.setToolTip(name)
            self.type_list.addItem(item)
            if name == keep:
                self.type_list.setCurrentItem(item)
        self.type_list.blockSignals(False)
        self._filter(self.search.text())
        self._changed()

    def _filter(self, text: str) -> None:
        needle = text.strip().lower()
        for i in range(self.type_list.count()):
            item = self.type_list.item(i)
            name = item.data(QtCore.Qt.ItemDataRole.UserRole)
            item.setHidden(bool(needle) and needle not in name.lower())

    def type_names(self, visible_only: bool = True) -> list[str]:
        """The types listed (those the search lets through, unless told otherwise)."""
        return [self.type_list.item(i).data(QtCore.Qt.ItemDataRole.UserRole) for i in range(self.type_list.count())
                if not (visible_only and self.type_list.item(i).isHidden())]

    def item_for(self, type_name: str) -> QtWidgets.QListWidgetItem:
        """The list row of ``type_name``; KeyError if it is not offered."""
        for i in range(self.type_list.count()):
            item = self.type_list.item(i)
            if item.data(QtCore.Qt.ItemDataRole.UserRole) == type_name:
                return item
        raise KeyError(f"{type_name!r} is not a type this widget can use (offered: {self.type_names(False)})")

    def chosen_type(self) -> str:
        item = self.type_list.currentItem()
        return item.data(QtCore.Qt.ItemDataRole.UserRole) if item is not None and not item.isHidden() else ""

    def topic_name(self) -> str:
        return normalize_topic_name(self.name_edit.text())

    def problem(self) -> str | None:
        """What is missing or wrong (the name first), or None when the new topic is complete."""
        named = topic_name_problem(self.name_edit.text())
        if named:
            return named
        if not self.chosen_type():
            return "pick the new topic's type" if self.type_list.count() else "no message type fits this widget"
        return None

    def target(self) -> Target | None:
        """The new topic as a target, or None until its name and type are good."""
        if self.problem() is not None or self._target_for is None:
            return None
        return self._target_for(self.topic_name(), self.chosen_type())

    def clear(self) -> None:
        """Forget the name and the search (the next widget starts afresh)."""
        self.name_edit.clear()
        self.search.clear()

    def _changed(self) -> None:
        problem = self.problem()
        self.problem_label.setText(problem or f"New topic {self.topic_name()} ({self.chosen_type()})")
        self.problem_label.setProperty("role", "problem" if problem else "hint")
        self.problem_label.style().unpolish(self.problem_label)
        self.problem_label.style().polish(self.problem_label)
        self.changed.emit()
