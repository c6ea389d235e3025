"""The add-widget panel: the three ways to put a widget on a canvas.

1. topic  -> subscribe or publish -> ranked compatible widgets -> settings -> drop
2. service -> call or serve       -> ranked compatible widgets -> settings -> drop
3. widget -> settings (its topic or service picked from compatible ones only) -> drop
4. action (ROS 2) -> send goals   -> ranked compatible widgets -> settings -> drop

The settings page shows a live preview of the widget.  While the draft has problems the preview carries
a warning overlay listing them; once valid it can be dragged onto the canvas or placed with "Place".

A widget picked from the palette starts with the role it most likely serves
(:func:`rcon_core.app.draft.role_preference`), the first of its roles the robot offers a compatible
topic or service for. The Topic/Service chooser lists the targets compatible with the current role first, then those only
compatible with another of the widget's roles (marked ``· to <role>``); choosing one of those switches the
role to it. For topics it ends with *+ New topic…*: a name and a type for a topic the robot does not
have yet (:mod:`rcon_core.app.new_topic`).

When a widget can bind several fields of the chosen type, the *Field* chooser lists them (best first,
with each field's type); it is hidden when there is only one, or when the widget takes the whole message.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import attrs
from qtpy import QtCore, QtGui, QtWidgets

from rcon_core.app.action_type import ActionTypeBox
from rcon_core.app.choosers import DragHandle, ElidingCombo, FieldChooser, NameLabel, TargetChooser, heading
from rcon_core.app.draft import ROLE_TEXT, Candidate, Draft, Target, role_preference, suggested_title
from rcon_core.app.new_topic import NEW_TOPIC, NewTopicBox, add_new_topic_entry, new_topic_index
from rcon_core.app.preview_slot import PreviewSlot
from rcon_core.app.settings_form import SettingsForm, form_label, tune_form
from rcon_core.app.theme import current_touch_px
from rcon_core.app.widget_frame import WidgetFrame
from rcon_core.msgs.names import pkg_type
from rcon_core.plugins import Binding, Role, SettingsError, WidgetSpec
from rcon_core.plugins.children import ChildContext

#: rank_widgets(type_name, role) -> candidates, best first
RankWidgets = Callable[[str, Role], list[Candidate]]
#: targets_for(spec, role) -> compatible topics or services
TargetsFor = Callable[[WidgetSpec, Role], list[Target]]


class AddPanel(QtWidgets.QWidget):
    """A stack of pages walking the operator from a pick to a placed widget."""

    place_requested = QtCore.Signal()  # "Place" tapped: put current_draft on the current canvas
    closed = QtCore.Signal()

    def __init__(
        self,
        rank_widgets: RankWidgets,
        targets_for: TargetsFor,
        build_preview: Callable[[Draft, WidgetFrame], None],
        release_preview: Callable[[], None],
        parent: QtWidgets.QWidget | None = None,
        *,
        child_context: Callable[[Callable[[], Binding | None]], ChildContext] | None = None,
    ) -> None:
        super().__init__(parent)
        self.setObjectName("addPanel")
        self._rank = rank_widgets
        self._targets_for = targets_for
        self._build_preview = build_preview
        self._release_preview = release_preview
        self._child_context = child_context
        self.draft: Draft | None = None
        self.form: SettingsForm | None = None
        self.preview_frame: WidgetFrame | None = None
        self._picked: Target | None = None
        self._role: Role | None = None
        self._is_service = False
        self._pick_target = False
        self._targets: list[Target] = []
        self._roles: list[Role] = []  #: the role chooser's roles, in its order
        self._title_typed = False  #: the operator typed a title: it no longer follows the binding
        self._new_topic_on = False  #: "+ New topic…" is chosen: the target is the operator's new topic

        self.stack = QtWidgets.QStackedWidget()
        self.role_page = self._build_role_page()
        self.widgets_page = self._build_widgets_page()
        self.settings_page = self._build_settings_page()
        for page in (self.role_page, self.widgets_page, self.settings_page):
            self.stack.addWidget(page)
        col = QtWidgets.QVBoxLayout(self)
        col.setContentsMargins(8, 8, 8, 8)
        col.addWidget(self.stack)

    # --------------------------------------------------------------------------------------- pages
    def resizeEvent(self, event: QtGui.QResizeEvent) -> None:  # noqa: N802 - Qt override
        super().resizeEvent(event)
        self.preview_slot.set_room(self.height() // 3)  # the settings below keep the most room

    def _nav(self, back: Callable[[], None] | None) -> QtWidgets.QHBoxLayout:
        row = QtWidgets.QHBoxLayout()
        if back is not None:
            b = QtWidgets.QPushButton("‹ Back")
            b.setObjectName("backButton")
            b.clicked.connect(back)
            row.addWidget(b)
        row.addStretch(1)
        c = QtWidgets.QPushButton("Cancel")
        c.setObjectName("cancelButton")
        c.clicked.connect(self.cancel)
        row.addWidget(c)
        return row

    def _build_role_page(self) -> QtWidgets.QWidget:
        page = QtWidgets.QWidget()
        col = QtWidgets.QVBoxLayout(page)
        self.role_title = NameLabel()
        self.role_title.setObjectName("roleTitle")
        self.role_type = QtWidgets.QLabel()
        self.role_type.setProperty("role", "hint")
        col.addWidget(self.role_title)
        col.addWidget(self.role_type)
        self.action_type_box = ActionTypeBox()  # an action listed without its type: the operator picks it
        self.action_type_box.chosen.connect(self._action_type_chosen)
        col.addWidget(self.action_type_box)
        col.addWidget(QtWidgets.QLabel("What should the widget do?"))
        self.role_buttons: dict[Role, QtWidgets.QPushButton] = {}
        for role in Role:
            text, tip = ROLE_TEXT[role]
            b = QtWidgets.QPushButton(f"{text}  ({role.value})")
            b.setObjectName(f"role_{role.value}")
            b.setToolTip(tip)
            b.clicked.connect(lambda _=False, r=role: self.choose_role(r))
            self.role_buttons[role] = b
            col.addWidget(b)
        col.addStretch(1)
        col.addLayout(self._nav(None))
        return page

    def _build_widgets_page(self) -> QtWidgets.QWidget:
        page = QtWidgets.QWidget()
        col = QtWidgets.QVBoxLayout(page)
        self.widgets_title = heading("")
        self.widgets_title.setObjectName("widgetsTitle")
        self.widgets_name = NameLabel()
        self.widgets_name.setObjectName("widgetsName")
        col.addWidget(self.widgets_title)
        col.addWidget(self.widgets_name)
        self.candidates = QtWidgets.QListWidget()
        self.candidates.setObjectName("candidateList")
        self.candidates.itemClicked.connect(self._candidate_clicked)
        self.candidates.itemActivated.connect(self._candidate_clicked)
        self.no_candidates = QtWidgets.QLabel()
        self.no_candidates.setObjectName("noCandidates")
        self.no_candidates.setWordWrap(True)
        self.no_candidates.setProperty("role", "problem")
        col.addWidget(self.no_candidates)
        col.addWidget(self.candidates, 1)
        col.addLayout(self._nav(lambda: self.stack.setCurrentWidget(self.role_page)))
        return page

    def _build_settings_page(self) -> QtWidgets.QWidget:
        page = QtWidgets.QWidget()
        outer = QtWidgets.QVBoxLayout(page)
        self.settings_title = NameLabel()
        self.settings_title.setObjectName("settingsTitle")
        outer.addWidget(self.settings_title)
        self.settings_error = QtWidgets.QLabel()
        self.settings_error.setProperty("role", "problem")
        self.settings_error.setWordWrap(True)
        self.settings_error.hide()
        outer.addWidget(self.settings_error)
        # the live preview is pinned above the settings (not scrolled with them): in sight while they are
        # changed, also on a 600 px tall screen
        self.preview_slot = PreviewSlot()
        outer.addWidget(self.preview_slot)
        self.settings_scroll = scroll = QtWidgets.QScrollArea()
        scroll.setObjectName("settingsScroll")
        scroll.setWidgetResizable(True)
        scroll.setHorizontalScrollBarPolicy(QtCore.Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        # two rows of fields at least (not Qt's 150 px): with a large text size on a 600 px screen the page
        # keeps its title, preview and buttons without growing the window; the rest scrolls
        scroll.setMinimumHeight(2 * current_touch_px())
        QtWidgets.QScroller.grabGesture(
            scroll.viewport(), QtWidgets.QScroller.ScrollerGestureType.TouchGesture
        )
        inner = QtWidgets.QWidget()
        # as wide as the panel, never wider (fields shrink instead of hiding under the scroll bar)
        inner.setSizePolicy(QtWidgets.QSizePolicy.Policy.Ignored, QtWidgets.QSizePolicy.Policy.Preferred)
        self.settings_col = QtWidgets.QVBoxLayout(inner)
        binding_box = tune_form(QtWidgets.QFormLayout())
        self.role_combo = ElidingCombo("roleCombo")
        self.role_combo.currentIndexChanged.connect(self._role_combo_changed)
        self.target_combo = TargetChooser("targetCombo")
        self.target_combo.currentIndexChanged.connect(self._target_changed)
        self.target_label = form_label("Topic", self.target_combo)
        self.field_combo = FieldChooser("fieldCombo")
        self.field_combo.chosen.connect(self._field_changed)
        self.field_label = form_label("Field", self.field_combo)
        binding_box.addRow(form_label("Role", self.role_combo), self.role_combo)
        binding_box.addRow(self.target_label, self.target_combo)
        self.new_topic = NewTopicBox()
        self.new_topic.changed.connect(self._new_topic_changed)
        binding_box.addRow(self.new_topic)
        binding_box.setRowVisible(self.new_topic, False)
        binding_box.addRow(self.field_label, self.field_combo)
        self.binding_box = binding_box
        self.title_edit = QtWidgets.QLineEdit()
        self.title_edit.setObjectName("titleEdit")
        self.title_edit.textChanged.connect(self._title_changed)
        binding_box.addRow(form_label("Title", self.title_edit), self.title_edit)
        self.settings_col.addLayout(binding_box)
        self.form_slot = QtWidgets.QVBoxLayout()
        self.settings_col.addLayout(self.form_slot)
        self.settings_col.addStretch(1)
        scroll.setWidget(inner)
        outer.addWidget(scroll, 1)
        self.drag_handle = DragHandle(lambda: self.preview_frame)
        self.place_button = QtWidgets.QPushButton("Place")  # one word: it shares a row with Back and Cancel
        self.place_button.setToolTip("Place on the canvas, in the first free spot in sight")
        self.place_button.setObjectName("placeButton")
        self.place_button.setProperty("primary", True)
        self.place_button.clicked.connect(self._place_clicked)
        outer.addWidget(self.drag_handle)
        nav = self._nav(self._settings_back)  # one row: ‹ Back, Place, Cancel (room for the form)
        for i in range(nav.count()):
            item = nav.itemAt(i)
            if item is not None and item.spacerItem() is not None:
                nav.takeAt(i)  # the Place button takes the room between Back and Cancel
                nav.insertWidget(i, self.place_button, 1)
                break
        outer.addLayout(nav)
        return page

    # -------------------------------------------------------------------------------------- entries
    def start_from_topic(self, name: str, type_name: str) -> None:
        """Pathway 1: a topic was picked."""
        self._start_target(Target(name, type_name), service=False)

    def start_from_service(self, name: str, type_name: str) -> None:
        """Pathway 2: a service was picked."""
        self._start_target(Target(name, type_name), service=True)

    def start_from_action(self, name: str, type_name: str) -> None:
        """Pathway 4: a (ROS 2) action was picked."""
        self._start_target(Target(name, type_name), service=False, action=True)
        if not type_name and self._child_context is not None:
            self.action_type_box.open_for(self._child_context(lambda: None).types)
            self.role_buttons[Role.ACTION].setEnabled(False)

    def _action_type_chosen(self, type_name: str) -> None:
        if self._picked is not None:
            self._picked = Target(self._picked.name, type_name)
            self.role_type.setText(type_name)
            self.role_buttons[Role.ACTION].setEnabled(True)

    def _start_target(self, target: Target, service: bool, action: bool = False) -> None:
        self._reset()
        self._picked, self._is_service = target, service
        self.role_title.set_name(target.name)
        self.role_type.setText(target.type or "type unknown")
        for role, button in self.role_buttons.items():
            button.setVisible(role.is_action == action and role.is_service == service)
            button.setEnabled(True)
        self.action_type_box.hide()
        self.stack.setCurrentWidget(self.role_page)
        self.show()

    def start_from_widget(self, spec: WidgetSpec) -> None:
        """Pathway 3: a widget was picked in the palette."""
        self._reset()
        roles = role_preference(spec)
        role = next((r for r in roles if self._targets_for(spec, r)), roles[0])
        self._open_settings(spec, role, None, pick_target=True)
        self.show()

    def choose_role(self, role: Role) -> None:
        assert self._picked is not None
        self._role = role
        self.widgets_title.setText(f"Widgets that can {role.value}")
        self.widgets_name.set_name(self._picked.name)
        self.candidates.clear()
        found = self._rank(self._picked.type, role)
        for cand in found:
            fields = ", ".join(cand.field_paths) if cand.field_paths else "whole message"
            item = QtWidgets.QListWidgetItem(f"{cand.spec.title}  —  {fields}")
            item.setData(QtCore.Qt.ItemDataRole.UserRole, cand)
            item.setToolTip(cand.reason or cand.spec.description)
            self.candidates.addItem(item)
        self.no_candidates.setText(
            "" if found else f"No installed widget can {role.value} {pkg_type(self._picked.type)}."
        )
        self.no_candidates.setVisible(not found)
        self.stack.setCurrentWidget(self.widgets_page)

    def choose_candidate(self, index: int) -> None:
        item = self.candidates.item(index)
        self._candidate_clicked(item)

    def _candidate_clicked(self, item: QtWidgets.QListWidgetItem) -> None:
        cand: Candidate = item.data(QtCore.Qt.ItemDataRole.UserRole)
        assert self._picked is not None
        target = Target(self._picked.name, self._picked.type, cand.field_paths, cand.choices)
        assert self._role is not None
        self._open_settings(cand.spec, self._role, target, pick_target=False)

    # ------------------------------------------------------------------------------------- settings
    def _open_settings(self, spec: WidgetSpec, role: Role, target: Target | None, pick_target: bool) -> None:
        self._clear_settings()
        error = ""
        try:
            settings = spec.make_settings({})
        except SettingsError as exc:
            settings = None
            error = f"{spec.title}: {exc}"
        self.settings_error.setText(error)
        self.settings_error.setVisible(bool(error))
        catalog = self._child_context(lambda: None).plugins if self._child_context is not None else None
        self.draft = Draft(spec=spec, role=role, target=target, settings=settings, title=spec.title,
                           catalog=catalog)
        self.settings_title.set_name(spec.title)
        self._pick_target = pick_target
        self._roles = role_preference(spec) if pick_target else [role]
        self._fill_roles()
        self._title_typed = False
        self.title_edit.blockSignals(True)
        self.title_edit.setText(spec.title)
        self.title_edit.setPlaceholderText(spec.title)
        self.title_edit.blockSignals(False)
        self._fill_targets()
        self._fill_fields()
        if settings is not None:
            context = None
            if self._child_context is not None:
                context = self._child_context(lambda: self.draft.binding if self.draft is not None else None)
            self.form = SettingsForm(settings, context=context)
            self.form.setObjectName("settingsForm")
            self.form.changed.connect(self._settings_changed)
            self.form_slot.addWidget(self.form)
        self.stack.setCurrentWidget(self.settings_page)
        self._rebuild_preview()
        self._scroll_to_top()
        # once more after the layout settled (a form's own first layout pass may move the bar)
        QtCore.QTimer.singleShot(0, self, self._scroll_to_top)

    def _scroll_to_top(self) -> None:
        """A new draft's settings page starts at its top: role, topic and field in sight."""
        self.settings_scroll.verticalScrollBar().setValue(0)

    def _fill_roles(self) -> None:
        assert self.draft is not None
        self.role_combo.blockSignals(True)
        self.role_combo.clear()
        for r in self._roles:
            self.role_combo.addItem(r.value)
            self.role_combo.setItemData(self.role_combo.count() - 1, ROLE_TEXT[r][1],
                                        QtCore.Qt.ItemDataRole.ToolTipRole)
        self.role_combo.setCurrentIndex(self._roles.index(self.draft.role) if self.draft.role in self._roles else -1)
        self.role_combo.setEnabled(self._pick_target and len(self._roles) > 1)
        self.role_combo.blockSignals(False)

    def _fill_targets(self) -> None:
        """The targets compatible with the draft's role, then those only compatible with its other roles
        (choosing one of those switches the role). Keeps the chosen target when it is still offered."""
        assert self.draft is not None
        draft = self.draft
        self.target_label.setText(draft.role.noun.capitalize())
        combo = self.target_combo
        combo.blockSignals(True)
        combo.clear()
        if self._pick_target:
            self._targets = combo.list_targets(draft.spec, draft.role, self._roles, self._targets_for)
            new_index = None  # a widget on a topic may also make a new one (needs the type registry)
            if not draft.role.is_service and not draft.role.is_action and self._child_context is not None:
                new_index = add_new_topic_entry(combo)
            combo.setEnabled(True)
            keep = draft.target
            index = combo.index_of(keep.name, draft.role) if keep is not None else 0
            if self._new_topic_on and new_index is not None:
                index = new_index  # the operator's new topic survives a role change
            combo.setCurrentIndex(index)
            self._show_new_topic(combo.currentData(NEW_TOPIC) is True)
            chosen = self.new_topic.target() if self._new_topic_on else combo.currentData()
            if chosen is not None and keep is not None and keep.name == chosen.name and keep.field_paths:
                if keep.field_paths[0] in (chosen.choices or chosen.field_paths):  # keep the field picked
                    chosen = attrs.evolve(chosen, field_paths=keep.field_paths)
            draft.target = chosen
        else:
            combo.show_fixed(draft.target)
        combo.blockSignals(False)

    def _show_new_topic(self, on: bool) -> None:
        """Show (and fill: the widget's fitting types, also the robot's) or hide the new topic's box."""
        self._new_topic_on = on
        self.binding_box.setRowVisible(self.new_topic, on)
        if on and self.draft is not None and self._child_context is not None:
            context, (spec, role) = self._child_context(lambda: None), (self.draft.spec, self.draft.role)
            self.new_topic.open_for(spec, role, context.types, context.plugins,
                                    [t.type for t in self._targets_for(spec, role)])

    def _new_topic_changed(self) -> None:
        if self.draft is None or not self._new_topic_on:
            return
        self.draft.target = self.new_topic.target()
        self._fill_fields()
        self._rebuild_preview()

    def choose_new_topic(self) -> NewTopicBox:
        """Select *+ New topic…* in the chooser (pathway 3); ValueError when it is not offered here."""
        index = new_topic_index(self.target_combo)
        if index is not None:
            self.target_combo.setCurrentIndex(index)
            return self.new_topic
        raise ValueError("a new topic can only be made for a widget on a topic, chosen from the widget")

    def _fill_fields(self) -> None:
        """The field chooser: every field the widget can use on the target, with its type, best first.
        Hidden when there is no choice to make (one field, or the widget takes the whole message)."""
        assert self.draft is not None
        target = self.draft.target
        paths: list[str] = []
        if target is not None and target.field_paths:
            paths = list(target.choices or target.field_paths)
        shown = self.field_combo.set_fields(
            paths, target.field_paths[0] if target is not None and target.field_paths else "",
            types=self._types(), type_name=target.type if target is not None else "",
            service=self.draft.role.is_service)
        self.binding_box.setRowVisible(self.field_combo, shown)

    def _types(self) -> Any:
        """The app's type registry (through the children context), or None."""
        if self._child_context is None:
            return None
        return getattr(self._child_context(lambda: None), "types", None)

    def choose_target(self, name: str) -> None:
        """Select the compatible topic/service ``name`` (pathway 3); ValueError if it is not offered."""
        self.target_combo.choose(name)

    def choose_field(self, path: str) -> None:
        """Select the field ``path`` of the chosen target; ValueError if the widget cannot use it."""
        self.field_combo.choose(path)

    def _role_combo_changed(self, index: int) -> None:
        if self.draft is None or not 0 <= index < len(self._roles):
            return
        self._set_role(self._roles[index])

    def _set_role(self, role: Role) -> None:
        assert self.draft is not None
        self.draft.role = role
        self._fill_roles()
        self._fill_targets()
        self._fill_fields()
        self._rebuild_preview()

    def _target_changed(self, index: int) -> None:
        if self.draft is None:
            return
        self._show_new_topic(self.target_combo.itemData(index, NEW_TOPIC) is True)
        if self._new_topic_on:
            self._new_topic_changed()
            return
        target = self.target_combo.itemData(index)
        self.draft.target = target
        role = self.target_combo.role_at(index) or self.draft.role
        if target is not None and role is not self.draft.role:
            self._set_role(role)  # only compatible with another role: the widget takes that one
            return
        self._fill_fields()
        self._rebuild_preview()

    def _field_changed(self, path: str) -> None:
        if self.draft is None or self.draft.target is None:
            return
        self.draft.set_field_path(path)
        self._rebuild_preview()

    def _title_changed(self, text: str) -> None:
        if self.draft is not None:
            self._title_typed = bool(text)  # the operator's own title; cleared: suggestions again
            self.draft.title = text
            if self.preview_frame is not None:
                self.preview_frame.set_title(text)

    def _settings_changed(self) -> None:
        if self.draft is not None and self.form is not None:
            self.draft.settings = self.form.value()
            self._rebuild_preview()

    # -------------------------------------------------------------------------------------- preview
    def _suggest_title(self) -> None:
        """Unless the operator typed one, the title follows the binding: ``battery · voltage``."""
        if self.draft is None or self._title_typed:
            return
        target = self.draft.target
        title = (suggested_title(target.name, self.draft.field_path, service=self.draft.role.is_service)
                 if target is not None else "") or self.draft.spec.title
        self.draft.title = title
        if self.title_edit.text() != title:
            self.title_edit.blockSignals(True)
            self.title_edit.setText(title)
            self.title_edit.blockSignals(False)

    def _rebuild_preview(self) -> None:
        self._drop_preview()
        if self.draft is None:
            return
        self._suggest_title()
        frame = WidgetFrame("preview", self.draft.title)
        frame.setObjectName("widgetFrame")
        frame.set_editable(False)
        self._build_preview(self.draft, frame)
        self.preview_frame = frame
        self.preview_slot.set_frame(frame, self.draft.size())
        self._refresh_validity()

    def _drop_preview(self) -> None:
        if self.preview_frame is not None:
            self._release_preview()
            self.preview_slot.set_frame(None)
            self.preview_frame.hide()
            self.preview_frame.deleteLater()
            self.preview_frame = None

    def _refresh_validity(self) -> None:
        problems = self.problems()
        if self.preview_frame is not None:
            self.preview_frame.problems.set_problems(problems)
        ok = not problems
        self.place_button.setEnabled(ok)
        self.drag_handle.setEnabled(ok)
        self.drag_handle.setText("✥ Drag onto the canvas" if ok else f"Not ready: {problems[0]}")
        self.drag_handle.setToolTip("" if ok else "\n".join(problems))

    def problems(self) -> list[str]:
        """The draft's problems, plus what only the form can see against the binding (a Compound child
        on a field the chosen type lacks)."""
        if self.draft is None:
            return ["nothing chosen"]
        out = self.draft.problems()
        new_topic = self.new_topic.problem() if self._new_topic_on else None
        if new_topic:  # what the new topic lacks, instead of "no topic chosen"
            out = [new_topic, *[p for p in out if not p.startswith("no topic")]]
        if self.form is not None:
            out += [p for p in self.form.problems() if p not in out]
        return out

    # ---------------------------------------------------------------------------------------- finish
    def _place_clicked(self) -> None:
        if not self.problems():
            self.place_requested.emit()

    def take_draft(self) -> Draft | None:
        """The draft to place (None unless valid); the panel closes."""
        draft = self.draft
        if draft is None or self.problems():
            return None
        self.cancel()
        return draft

    def _settings_back(self) -> None:
        self._drop_preview()
        if self._picked is not None:
            self.stack.setCurrentWidget(self.widgets_page)
        else:
            self.cancel()

    def cancel(self) -> None:
        self._reset()
        self.hide()
        self.closed.emit()

    def _clear_settings(self) -> None:
        """Drop the settings page's draft-specific content: preview, form, choosers."""
        self._drop_preview()
        if self.form is not None:
            self.form_slot.removeWidget(self.form)
            self.form.hide()
            self.form.deleteLater()
            self.form = None
        self.draft = None
        self._targets = []
        self._roles = []
        for combo in (self.role_combo, self.target_combo, self.field_combo):
            combo.blockSignals(True)
            combo.clear()
            combo.blockSignals(False)
        self.binding_box.setRowVisible(self.field_combo, False)
        self._new_topic_on = False
        self.binding_box.setRowVisible(self.new_topic, False)
        self.new_topic.clear()
        self.title_edit.blockSignals(True)
        self.title_edit.clear()
        self.title_edit.blockSignals(False)
        self.settings_title.set_name("")
        self.settings_error.hide()
        self._scroll_to_top()
        self._refresh_validity()

    def _reset(self) -> None:
        """Back to nothing chosen: no draft, form or preview left over for the next add."""
        self._clear_settings()
        self._picked = None
        self._role = None
        self._pick_target = False
        self.candidates.clear()
