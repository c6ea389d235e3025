"""The add-widget panel: the three ways to put a widget on a canvas.

1. topic  -> subscribe or publish -> ranked compatible widgets -> settings -> drop
2. service -> call or serve       -> ranked compatible widgets -> settings -> drop
3. widget -> settings (its topic or service picked from compatible ones only) -> drop

The settings page shows a live preview of the widget.  While the draft has problems the preview carries
a warning overlay listing them; once valid it can be dragged onto the canvas or placed with "Place".
"""

from __future__ import annotations

from collections.abc import Callable

from qtpy import QtCore, QtGui, QtWidgets

from rcon_core.app.canvas_surface import DRAFT_MIME
from rcon_core.app.catalog_panel import short_type
from rcon_core.app.children_editor import ChildContext
from rcon_core.app.draft import Candidate, Draft, Target
from rcon_core.app.settings_form import SettingsForm
from rcon_core.app.widget_frame import WidgetFrame
from rcon_core.plugins import Binding, Role, SettingsError, WidgetSpec

ROLE_TEXT = {
    Role.SUBSCRIBE: ("Show it", "subscribe: a widget displays the messages"),
    Role.PUBLISH: ("Send on it", "publish: a widget sends messages"),
    Role.CALL: ("Call it", "call: a widget sends requests and shows the answer"),
    Role.SERVE: ("Answer it", "serve: a widget answers requests from the robot"),
}

#: rank_widgets(type_name, role) -> candidates, best first
RankWidgets = Callable[[str, Role], list[Candidate]]
#: targets_for(spec, role) -> compatible topics or services
TargetsFor = Callable[[WidgetSpec, Role], list[Target]]


def _heading(text: str) -> QtWidgets.QLabel:
    label = QtWidgets.QLabel(text)
    label.setProperty("role", "heading")
    label.setWordWrap(True)
    return label


class DragHandle(QtWidgets.QLabel):
    """Press and drag this onto a canvas to drop the draft there."""

    def __init__(self, panel: AddPanel) -> None:
        super().__init__("✥ Drag onto the canvas")
        self.setObjectName("dragHandle")
        self.panel = panel
        self.setAlignment(QtCore.Qt.AlignmentFlag.AlignCenter)
        self.setStyleSheet("border:3px dashed #0040a0; color:#0040a0; font-weight:bold; border-radius:6px;")
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
        preview = self.panel.preview_frame
        if preview is not None:
            pix = preview.grab().scaledToWidth(min(240, max(60, preview.width())))
            drag.setPixmap(pix)
            drag.setHotSpot(QtCore.QPoint(12, 12))
        drag.exec(QtCore.Qt.DropAction.CopyAction)


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
        self._targets: list[Target] = []

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
        self.role_title = _heading("")
        self.role_type = QtWidgets.QLabel()
        self.role_type.setProperty("role", "hint")
        col.addWidget(self.role_title)
        col.addWidget(self.role_type)
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
        self.widgets_title = _heading("")
        col.addWidget(self.widgets_title)
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
        self.settings_title = _heading("")
        outer.addWidget(self.settings_title)
        scroll = QtWidgets.QScrollArea()
        scroll.setWidgetResizable(True)
        scroll.setHorizontalScrollBarPolicy(QtCore.Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        QtWidgets.QScroller.grabGesture(
            scroll.viewport(), QtWidgets.QScroller.ScrollerGestureType.TouchGesture
        )
        inner = QtWidgets.QWidget()
        # as wide as the panel, never wider (fields shrink instead of hiding under the scroll bar)
        inner.setSizePolicy(QtWidgets.QSizePolicy.Policy.Ignored, QtWidgets.QSizePolicy.Policy.Preferred)
        self.settings_col = QtWidgets.QVBoxLayout(inner)
        binding_box = QtWidgets.QFormLayout()
        binding_box.setRowWrapPolicy(QtWidgets.QFormLayout.RowWrapPolicy.WrapLongRows)
        self.role_combo = QtWidgets.QComboBox()
        self.role_combo.setObjectName("roleCombo")
        self.role_combo.setSizeAdjustPolicy(QtWidgets.QComboBox.SizeAdjustPolicy.AdjustToMinimumContentsLengthWithIcon)
        self.role_combo.currentIndexChanged.connect(self._role_combo_changed)
        self.target_combo = QtWidgets.QComboBox()
        self.target_combo.setObjectName("targetCombo")
        self.target_combo.setSizeAdjustPolicy(
            QtWidgets.QComboBox.SizeAdjustPolicy.AdjustToMinimumContentsLengthWithIcon
        )
        self.target_combo.setMinimumContentsLength(12)
        self.target_combo.currentIndexChanged.connect(self._target_changed)
        self.target_label = QtWidgets.QLabel("Topic")
        binding_box.addRow("Role", self.role_combo)
        binding_box.addRow(self.target_label, self.target_combo)
        self.title_edit = QtWidgets.QLineEdit()
        self.title_edit.setObjectName("titleEdit")
        self.title_edit.textChanged.connect(self._title_changed)
        binding_box.addRow("Title", self.title_edit)
        self.settings_col.addLayout(binding_box)
        # the live preview first, so it is in sight while the settings below are changed
        self.settings_col.addWidget(QtWidgets.QLabel("Preview"))
        self.preview_slot = QtWidgets.QVBoxLayout()
        self.settings_col.addLayout(self.preview_slot)
        self.form_slot = QtWidgets.QVBoxLayout()
        self.settings_col.addLayout(self.form_slot)
        self.settings_col.addStretch(1)
        scroll.setWidget(inner)
        outer.addWidget(scroll, 1)
        self.drag_handle = DragHandle(self)
        self.place_button = QtWidgets.QPushButton("Place on canvas")
        self.place_button.setObjectName("placeButton")
        self.place_button.setProperty("primary", True)
        self.place_button.clicked.connect(self._place_clicked)
        outer.addWidget(self.drag_handle)
        outer.addWidget(self.place_button)
        outer.addLayout(self._nav(self._settings_back))
        return page

    # -------------------------------------------------------------------------------------- entries
    def start_from_topic(self, name: str, type_name: str) -> None:
        """Pathway 1: a topic was picked."""
        self._start_target(Target(name, type_name), service=False)

    def start_from_service(self, name: str, type_name: str) -> None:
        """Pathway 2: a service was picked."""
        self._start_target(Target(name, type_name), service=True)

    def _start_target(self, target: Target, service: bool) -> None:
        self._reset()
        self._picked, self._is_service = target, service
        self.role_title.setText(target.name)
        self.role_type.setText(target.type or "type unknown")
        for role, button in self.role_buttons.items():
            button.setVisible(role.is_service == service)
        self.stack.setCurrentWidget(self.role_page)
        self.show()

    def start_from_widget(self, spec: WidgetSpec) -> None:
        """Pathway 3: a widget was picked in the palette."""
        self._reset()
        roles = sorted(spec.roles, key=lambda r: list(Role).index(r))
        self._open_settings(spec, roles[0], None, pick_target=True)
        self.show()

    def choose_role(self, role: Role) -> None:
        assert self._picked is not None
        self._role = role
        self.widgets_title.setText(f"Widgets that can {role.value} {self._picked.name}")
        self.candidates.clear()
        found = self._rank(self._picked.type, role)
        for cand in found:
            fields = ", ".join(cand.field_paths) if cand.field_paths else "whole message"
            item = QtWidgets.QListWidgetItem(f"{cand.spec.title}  —  {fields}")
            item.setData(QtCore.Qt.ItemDataRole.UserRole, cand)
            item.setToolTip(cand.reason or cand.spec.description)
            self.candidates.addItem(item)
        self.no_candidates.setText(
            "" if found else f"No installed widget can {role.value} {short_type(self._picked.type)}."
        )
        self.no_candidates.setVisible(not found)
        self.stack.setCurrentWidget(self.widgets_page)

    def choose_candidate(self, index: int) -> None:
        item = self.candidates.item(index)
        self._candidate_clicked(item)

    def _candidate_clicked(self, item: QtWidgets.QListWidgetItem) -> None:
        cand: Candidate = item.data(QtCore.Qt.ItemDataRole.UserRole)
        assert self._picked is not None
        target = Target(self._picked.name, self._picked.type, cand.field_paths)
        assert self._role is not None
        self._open_settings(cand.spec, self._role, target, pick_target=False)

    # ------------------------------------------------------------------------------------- settings
    def _open_settings(self, spec: WidgetSpec, role: Role, target: Target | None, pick_target: bool) -> None:
        try:
            settings = spec.make_settings({})
        except SettingsError as exc:
            settings = None
            self.settings_title.setText(f"{spec.title}: {exc}")
        self.draft = Draft(spec=spec, role=role, target=target, settings=settings, title=spec.title)
        self.settings_title.setText(f"{spec.title}")
        self.role_combo.blockSignals(True)
        self.role_combo.clear()
        for r in sorted(spec.roles, key=lambda r: list(Role).index(r)):
            self.role_combo.addItem(r.value, r)
        self.role_combo.setCurrentIndex(max(0, self.role_combo.findData(role)))
        self.role_combo.setEnabled(pick_target and self.role_combo.count() > 1)
        self.role_combo.blockSignals(False)
        self.title_edit.blockSignals(True)
        self.title_edit.setText(spec.title)
        self.title_edit.blockSignals(False)
        self._pick_target = pick_target
        self._fill_targets()
        if self.form is not None:
            self.form.deleteLater()
            self.form = None
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

    def _fill_targets(self) -> None:
        assert self.draft is not None
        self.target_label.setText("Service" if self.draft.role.is_service else "Topic")
        self.target_combo.blockSignals(True)
        self.target_combo.clear()
        if self._pick_target:
            self._targets = self._targets_for(self.draft.spec, self.draft.role)
            self.target_combo.addItem("— choose —", None)
            for t in self._targets:
                self.target_combo.addItem(f"{t.name}  ({short_type(t.type)})", t)
            self.target_combo.setEnabled(True)
            keep = self.draft.target
            index = next((i + 1 for i, t in enumerate(self._targets) if keep and t.name == keep.name), 0)
            self.target_combo.setCurrentIndex(index)
            self.draft.target = self.target_combo.currentData()
        else:
            fixed = self.draft.target
            self.target_combo.addItem(f"{fixed.name}  ({short_type(fixed.type)})" if fixed else "—", fixed)
            self.target_combo.setEnabled(False)
        self.target_combo.blockSignals(False)

    def choose_target(self, name: str) -> None:
        """Select the compatible topic/service ``name`` (pathway 3); ValueError if it is not offered."""
        for i in range(self.target_combo.count()):
            t = self.target_combo.itemData(i)
            if t is not None and t.name == name:
                self.target_combo.setCurrentIndex(i)
                return
        offered = [t.name for t in self._targets]
        raise ValueError(f"{name!r} is not compatible with this widget (offered: {offered})")

    def _role_combo_changed(self, _index: int) -> None:
        if self.draft is None:
            return
        self.draft.role = self.role_combo.currentData()
        self._fill_targets()
        self._rebuild_preview()

    def _target_changed(self, _index: int) -> None:
        if self.draft is None:
            return
        self.draft.target = self.target_combo.currentData()
        self._rebuild_preview()

    def _title_changed(self, text: str) -> None:
        if self.draft is not None:
            self.draft.title = text
            if self.preview_frame is not None:
                self.preview_frame.set_title(text)

    def _settings_changed(self) -> None:
        if self.draft is not None and self.form is not None:
            self.draft.settings = self.form.value()
            self._rebuild_preview()

    # -------------------------------------------------------------------------------------- preview
    def _rebuild_preview(self) -> None:
        self._drop_preview()
        if self.draft is None:
            return
        frame = WidgetFrame("preview", self.draft.title)
        frame.setObjectName("widgetFrame")
        frame.set_editable(False)
        self._build_preview(self.draft, frame)
        w, h = self.draft.spec.default_size
        frame.setMinimumSize(int(min(w, 280)), int(max(min(h, 320), 120)))
        self.preview_frame = frame
        self.preview_slot.addWidget(frame)
        self._refresh_validity()

    def _drop_preview(self) -> None:
        if self.preview_frame is not None:
            self._release_preview()
            self.preview_slot.removeWidget(self.preview_frame)
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

    def _reset(self) -> None:
        self._drop_preview()
        if self.form is not None:
            self.form.deleteLater()
            self.form = None
        self.draft = None
        self._picked = None
        self._role = None
