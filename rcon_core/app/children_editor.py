"""Editing a widget's child widgets (a Compound's children) in the generated settings form.

A settings field is a *children field* when it is a ``list`` of an attrs class with the fields
``kind: str``, ``field_path: str`` and ``settings: dict`` (and optionally ``title: str``); see
``docs/writing-a-widget-plugin.md``. :class:`~rcon_core.app.settings_form.SettingsForm` shows such a field
with a :class:`ChildrenEditor`:

* the list of children (kind, field, problems), each with ▲ ▼ Edit Remove;
* *Add child*: the fields of the bound type (from the type registry, learned from the robot's rosapi
  typedefs when the registry does not know the type), then only the widget kinds that fit that field
  (:func:`rcon_core.matcher.match` on the field's message type and the child's role), then the child's
  own settings in the same generated form.

A child's role follows from where it sits: children fill what the parent sends and show what it
receives. That logic, with the catalog of fields and kinds and the child checks, is Qt-free and lives in
the plugin contract, :mod:`rcon_core.plugins.children`; this module is only the editor. It needs a
:class:`~rcon_core.plugins.children.ChildContext` (the type registry, the plugin manager, the parent's
current binding); the form takes one as ``context=`` (the main window makes it,
:meth:`MainWindow.child_context`). Without one, a children field shows its children but cannot add any.
The child's own settings page uses the form factory the settings form passes in (``form=``), so the
editor does not import the form that contains it.
"""

from __future__ import annotations

import concurrent.futures
import functools
from collections.abc import Callable
from typing import Any

import attrs
from qtpy import QtCore, QtWidgets

from rcon_core.app.focus import focus_into, has_focus_inside
from rcon_core.plugins import Role, SettingsError, WidgetSpec
from rcon_core.plugins.children import (
    ChildCatalog,
    ChildContext,
    FieldChoice,
    Learn,
    fetch_typedefs,
    paths_overlap,
)

#: form(settings, context=...) -> a settings form with ``changed`` and ``value()``: the settings form passes
#: its own class, so the editor does not import the form that contains it
FormFactory = Callable[..., Any]

__all__ = ["ChildrenEditor", "FieldButton", "ChoiceRow", "FormFactory", "link_learner"]

# ------------------------------------------------------------------------------------------ learning
def link_learner(link: Any) -> Learn | None:
    """Fetches a type's typedefs from the robot the app's link is connected to (None: no link)."""
    if link is None:
        return None

    def learn(type_name: str, service: bool) -> concurrent.futures.Future[Any]:
        client = link.client
        if client is None:
            fut: concurrent.futures.Future[Any] = concurrent.futures.Future()
            fut.set_exception(RuntimeError("not connected to a robot"))
            return fut
        return link.thread.run(fetch_typedefs(client.rosapi, type_name, service))

    return learn


# ------------------------------------------------------------------------------------------ the editor
def _button(text: str, name: str, slot: Callable[[], None], primary: bool = False) -> QtWidgets.QPushButton:
    b = QtWidgets.QPushButton(text)
    b.setObjectName(name)
    if primary:
        b.setProperty("primary", True)
    b.clicked.connect(lambda _=False: slot())
    return b


def _icon_button(glyph: str, name: str, tip: str, slot: Callable[[], None]) -> QtWidgets.QPushButton:
    """A square touch-sized button with one symbol (its meaning in the tooltip and accessible name). Sized
    by the theme (``square``: the touch size plus its border), never fixed below it: a fixed touch-size
    box clipped the border the theme draws around it."""
    b = _button(glyph, name, slot)
    b.setToolTip(tip)
    b.setAccessibleName(tip)
    b.setProperty("square", True)
    b.setSizePolicy(QtWidgets.QSizePolicy.Policy.Fixed, QtWidgets.QSizePolicy.Policy.Fixed)
    return b


class FieldButton(QtWidgets.QPushButton):
    """A field to pick: ``name · type`` on one line when it fits the button, else the type on a second line
    (never cut off at the right)."""

    def __init__(self, name: str, type_label: str, object_name: str, slot: Callable[[], None]) -> None:
        super().__init__()
        self.setObjectName(object_name)
        self.name, self.type_label = name, type_label
        self.setStyleSheet("text-align: left; padding: 4px 12px;")
        self.setSizePolicy(QtWidgets.QSizePolicy.Policy.Ignored, QtWidgets.QSizePolicy.Policy.Preferred)
        self.clicked.connect(lambda _=False: slot())
        self._fit()

    def one_line(self) -> str:
        return f"{self.name}   ·   {self.type_label}" if self.type_label else self.name

    def _fit(self) -> None:
        text = self.one_line()
        room = self.width() - 24 - 6  # the padding and the border
        if self.width() > 0 and self.fontMetrics().horizontalAdvance(text) > room and self.type_label:
            text = f"{self.name}\n{self.type_label}"
        if text != self.text():
            self.setText(text)
            self.updateGeometry()

    def resizeEvent(self, event: Any) -> None:
        super().resizeEvent(event)
        self._fit()


class ChoiceRow(QtWidgets.QFrame):
    """A tappable row with a bold first line and wrapped text under it (a button that wraps)."""

    clicked = QtCore.Signal()

    def __init__(self, title: str, text: str = "", problem: bool = False,
                 parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        from rcon_core.app.theme import current_touch_px

        self.setProperty("role", "choice")
        self.setCursor(QtCore.Qt.CursorShape.PointingHandCursor)
        self.setFocusPolicy(QtCore.Qt.FocusPolicy.StrongFocus)
        self.setMinimumHeight(current_touch_px())
        # the theme's colours (the application palette: see theme.py)
        self.setStyleSheet("ChoiceRow { border: 3px solid palette(dark); border-radius: 6px; background: palette(base); }"
                           "ChoiceRow:focus { border-color: palette(link); }")
        col = QtWidgets.QVBoxLayout(self)
        col.setContentsMargins(12, 6, 12, 6)
        col.setSpacing(2)
        self.title = _label(title)
        self.title.setStyleSheet("font-weight: bold;")
        col.addWidget(self.title)
        self.text = _label(text, "problem" if problem else "hint")
        self.text.setVisible(bool(text))
        col.addWidget(self.text)
        for label in (self.title, self.text):
            label.setAttribute(QtCore.Qt.WidgetAttribute.WA_TransparentForMouseEvents)

    def click(self) -> None:
        self.clicked.emit()

    def mouseReleaseEvent(self, event: Any) -> None:
        if self.rect().contains(event.position().toPoint()):
            self.clicked.emit()

    def keyPressEvent(self, event: Any) -> None:
        if event.key() in (QtCore.Qt.Key.Key_Return, QtCore.Qt.Key.Key_Enter, QtCore.Qt.Key.Key_Space):
            self.clicked.emit()
        else:
            super().keyPressEvent(event)


def _label(text: str, role: str = "", wrap: bool = True) -> QtWidgets.QLabel:
    label = QtWidgets.QLabel(text)
    label.setWordWrap(wrap)
    if role:
        label.setProperty("role", role)
    return label


def _clear(layout: QtWidgets.QLayout) -> None:
    page = layout.parentWidget()
    if page is not None:  # shown again by ChildrenEditor._show, with its new content
        page.hide()
    while layout.count():
        item = layout.takeAt(0)
        if item is None:
            break
        widget, inner = item.widget(), item.layout()
        if widget is not None:
            widget.hide()
            widget.deleteLater()
        elif inner is not None:
            _clear(inner)


class ChildrenEditor(QtWidgets.QWidget):
    """Edits a list of children in place: one page at a time (list, field, widget, child settings),
    sized to its content so the surrounding form scrolls as one."""

    changed = QtCore.Signal()

    def __init__(self, item_cls: type, children: list[Any], context: Callable[[], ChildContext | None],
                 exclude: tuple[str, ...] = (), parent: QtWidgets.QWidget | None = None, *,
                 form: FormFactory | None = None) -> None:
        super().__init__(parent)
        self.setObjectName("childrenEditor")
        self._form = form  #: builds a child's settings form (the settings form passes its own class)
        self.item_cls = item_cls
        self.children_list: list[Any] = [attrs.evolve(c) for c in children]
        self._context = context
        self.exclude = tuple(exclude)
        self.editing: int | None = None  #: the child whose settings page is open
        self.child_form: Any = None
        self._learning: concurrent.futures.Future[Any] | None = None
        self._after_learning: Callable[[], None] | None = None
        self._last_binding: Any = None
        col = QtWidgets.QVBoxLayout(self)
        col.setContentsMargins(0, 0, 0, 0)
        self.pages: dict[str, QtWidgets.QWidget] = {}
        self.page_layouts: dict[str, QtWidgets.QVBoxLayout] = {}
        for name in ("list", "fields", "kinds", "child"):
            page = QtWidgets.QFrame()
            page.setObjectName(f"children_{name}_page")
            lay = QtWidgets.QVBoxLayout(page)
            lay.setContentsMargins(0, 0, 0, 0)
            lay.setSpacing(8)
            self.pages[name], self.page_layouts[name] = page, lay
            col.addWidget(page)
        self.status = _label("", "hint")
        self.status.setObjectName("childrenStatus")
        self.status.hide()
        col.addWidget(self.status)
        self._poll = QtCore.QTimer(self)  # the robot's typedefs arriving; the binding changing
        self._poll.setInterval(100)
        self._poll.timeout.connect(self._tick)
        self._poll.start()
        self._follow = False  # the form just opened: its scroll position is the panel's to set
        self._refocus = False
        self.show_list()
        self._follow = True

    # -- context -----------------------------------------------------------------------------------
    def catalog(self) -> ChildCatalog | None:
        ctx = self._context()
        if ctx is None:
            return None
        return ChildCatalog(ctx.types, ctx.plugins, ctx.binding(), self.exclude)

    def value(self) -> list[Any]:
        return [attrs.evolve(c) for c in self.children_list]

    def problems(self) -> list[str]:
        """Each child's problems that depend on the binding (the settings' own ``problems()`` cannot
        see the type), named: ``child 2 (Slider) on linear.q: … has no field 'linear.q'``."""
        cat = self.catalog()
        if cat is None:
            return []
        return [f"{cat.child_name(i, c)}: {p}" for i, c in enumerate(self.children_list)
                for p in cat.placement_problems(c)]

    def child_problems(self, index: int) -> list[str]:
        """Everything wrong with one child (placement and its own settings)."""
        cat = self.catalog()
        if cat is None:
            return []
        item = self.children_list[index]
        return cat.placement_problems(item) + cat.settings_problems(item)

    def _clear_page(self, lay: QtWidgets.QVBoxLayout) -> None:
        """Empty a page before it is rebuilt; remembers whether the keyboard was in the editor (on the
        button just tapped, which goes away), so :meth:`_show` hands it to the new page."""
        self._refocus = self._refocus or has_focus_inside(self)
        _clear(lay)

    def _show(self, name: str) -> None:
        for key, page in self.pages.items():
            page.setVisible(key == name)
        self.current_page = name
        if self._refocus and self.isVisible():
            focus_into(self.pages[name])  # not whatever Qt picks next (the robot URL, its text selected)
        self._refocus = False
        if self._follow:  # a page the operator opened: bring it into sight
            QtCore.QTimer.singleShot(0, self, lambda: self._scroll_to(self.pages[name]))

    def _scroll_to(self, page: QtWidgets.QWidget) -> None:
        """Bring the top of the page just opened into sight in the form's scroll area."""
        w = self.parentWidget()
        while w is not None and not isinstance(w, QtWidgets.QScrollArea):
            w = w.parentWidget()
        content = w.widget() if w is not None else None
        if w is None or content is None or not page.isVisible():
            return
        if self.current_page == "list":  # back on the list: the least scrolling that shows it
            w.ensureWidgetVisible(page, 0, 0)
            return
        top = page.mapTo(content, QtCore.QPoint(0, 0)).y()
        w.verticalScrollBar().setValue(max(0, top - 8))

    # -- page: the list ----------------------------------------------------------------------------
    def show_list(self) -> None:
        self.editing = None
        self.child_form = None
        lay = self.page_layouts["list"]
        self._clear_page(lay)
        lay.setSpacing(16)  # children apart: each row's buttons belong to the title above them
        cat = self.catalog()
        self.rows: list[QtWidgets.QFrame] = []
        if not self.children_list:
            lay.addWidget(_label("No children yet. Add one for each field this widget should set or show.",
                                 "hint"))
        n = len(self.children_list)
        for i, item in enumerate(self.children_list):
            row = QtWidgets.QFrame()
            row.setObjectName(f"child_{i}")
            rc = QtWidgets.QVBoxLayout(row)
            rc.setContentsMargins(0, 0, 0, 0)
            rc.setSpacing(4)
            problems = self.child_problems(i)
            head = ChoiceRow(f"{i + 1}. {self._describe(cat, item)}",
                             "\n".join(f"⚠ {p}" for p in problems), problem=bool(problems))
            head.setObjectName(f"childTitle_{i}")
            head.setToolTip("Tap to edit this child")
            head.clicked.connect(lambda i=i: self.edit_child(i))
            rc.addWidget(head)
            buttons = QtWidgets.QHBoxLayout()
            buttons.setSpacing(6)
            for glyph, name, tip, slot, enabled in (
                ("▲", "childUp", "Move up", lambda i=i: self.move_child(i, -1), i > 0),
                ("▼", "childDown", "Move down", lambda i=i: self.move_child(i, +1), i < n - 1),
                ("", "", "", None, False),
                ("✎", "childEdit", "Edit this child", lambda i=i: self.edit_child(i), True),
                ("✕", "childRemove", "Remove this child", lambda i=i: self.remove_child(i), True),
            ):
                if slot is None:
                    buttons.addStretch(1)
                    continue
                b = _icon_button(glyph, f"{name}_{i}", tip, slot)
                b.setEnabled(enabled)
                buttons.addWidget(b)
            rc.addLayout(buttons)
            lay.addWidget(row)
            self.rows.append(row)
        self.add_button = _button("+ Add child", "addChildButton", self.start_add)
        lay.addWidget(self.add_button)
        self._show("list")

    @staticmethod
    def _describe(cat: ChildCatalog | None, item: Any) -> str:
        spec = cat.spec_of(item.kind) if cat is not None else None
        what = spec.title if spec is not None else (item.kind or "?")
        title = getattr(item, "title", "")
        where = item.field_path or "the whole message"
        return f"{title}: {what} on {where}" if title else f"{what} on {where}"

    def move_child(self, index: int, step: int) -> None:
        other = index + step
        if not (0 <= index < len(self.children_list) and 0 <= other < len(self.children_list)):
            return
        items = self.children_list
        items[index], items[other] = items[other], items[index]
        self._changed()
        self.show_list()

    def remove_child(self, index: int) -> None:
        if 0 <= index < len(self.children_list):
            del self.children_list[index]
            self._changed()
        self.show_list()

    # -- page: which field -------------------------------------------------------------------------
    def start_add(self) -> None:
        """Add a child: first the field (learning the bound type from the robot if needed)."""
        cat = self.catalog()
        if cat is None:
            self._say("The children editor needs the app's type registry and widgets.")
            return
        if cat.binding is None or not cat.type_name:
            what = "service" if cat.binding is not None and cat.binding.role.is_service else "topic"
            self._say(f"Choose the {what} first: the children are fields of its type.")
            return
        if not cat.known():
            self._learn(cat, self.start_add)
            return
        self.show_fields(cat)

    def show_fields(self, cat: ChildCatalog) -> None:
        lay = self.page_layouts["fields"]
        self._clear_page(lay)
        verb = {Role.PUBLISH: "set"}.get(cat.parts()[0][2], "show") if not cat.is_service else "set or show"
        lay.addWidget(_label(f"Which field should the new child {verb}?", "heading"))
        lay.addWidget(_label(f"Fields of {cat.type_name}", "hint"))
        self.field_buttons: dict[str, QtWidgets.QPushButton] = {}
        part_now = None
        taken = [item.field_path for item in self.children_list]
        for choice in cat.fields():
            if any(paths_overlap(choice.path, used) for used in taken):
                continue  # another child already sets (or shows) this field, or a part of it
            if cat.is_service and choice.part != part_now:
                part_now = choice.part
                side = "filled by the children" if choice.role is Role.PUBLISH else "shown by the children"
                lay.addWidget(_label(f"{choice.part.capitalize()} ({side})", "hint"))
            b = FieldButton(choice.label, choice.type_label, f"field_{choice.path or 'whole'}",
                            functools.partial(self.show_kinds, choice))
            b.setToolTip(f"{choice.path or '(whole message)'}: {choice.type}")
            lay.addWidget(b)
            self.field_buttons[choice.path] = b
        if not self.field_buttons:
            lay.addWidget(_label(f"No installed widget fits a field of {cat.type_name}.", "problem"))
        lay.addWidget(_button("‹ Back", "childrenBack", self.show_list))
        self._show("fields")

    def choose_field(self, path: str) -> None:
        """Tap the field ``path`` (ValueError if it is not offered)."""
        if path not in getattr(self, "field_buttons", {}):
            raise ValueError(f"field {path!r} is not offered (offered: {sorted(getattr(self, 'field_buttons', {}))})")
        self.field_buttons[path].click()

    # -- page: which widget ------------------------------------------------------------------------
    def show_kinds(self, choice: FieldChoice) -> None:
        cat = self.catalog()
        assert cat is not None
        lay = self.page_layouts["kinds"]
        self._clear_page(lay)
        self.picked_field = choice
        lay.addWidget(_label(f"Which widget for {choice.label}?", "heading"))
        lay.addWidget(_label(f"{choice.type_label}; the child will {choice.role.value}", "hint"))
        self.kind_buttons: dict[str, ChoiceRow] = {}
        for k in cat.kinds_for(choice):
            b = ChoiceRow(k.spec.title, k.spec.description or k.reason)
            b.setObjectName(f"kind_{k.spec.kind}")
            b.setToolTip(f"{k.spec.kind}: {k.reason}")
            b.clicked.connect(lambda k=k: self.add_child(choice, k.spec))
            lay.addWidget(b)
            self.kind_buttons[k.spec.kind] = b
        lay.addWidget(_button("‹ Back", "childrenBack", lambda: self.show_fields(cat)))
        self._show("kinds")

    def choose_kind(self, kind: str) -> None:
        """Tap the widget ``kind`` (ValueError if it does not fit the field)."""
        if kind not in getattr(self, "kind_buttons", {}):
            raise ValueError(f"{kind!r} does not fit this field (offered: {sorted(getattr(self, 'kind_buttons', {}))})")
        self.kind_buttons[kind].click()

    def add_child(self, choice: FieldChoice, spec: WidgetSpec) -> None:
        try:
            settings = spec.settings_to_dict(spec.make_settings({}))
        except SettingsError:
            settings = {}
        self.children_list.append(self.item_cls(kind=spec.kind, field_path=choice.path, settings=settings))
        self._changed()
        self.edit_child(len(self.children_list) - 1)

    # -- page: one child's settings ----------------------------------------------------------------
    def edit_child(self, index: int) -> None:
        cat = self.catalog()
        item = self.children_list[index]
        spec = cat.spec_of(item.kind) if cat is not None else None
        lay = self.page_layouts["child"]
        self._clear_page(lay)
        self.editing = index
        self.child_form = None
        title = spec.title if spec is not None else item.kind
        lay.addWidget(_label(f"Child {index + 1}: {title} on {item.field_path or 'the whole message'}", "heading"))
        if "title" in attrs.fields_dict(self.item_cls):
            form_row = QtWidgets.QFormLayout()
            form_row.setRowWrapPolicy(QtWidgets.QFormLayout.RowWrapPolicy.WrapLongRows)
            self.child_title = QtWidgets.QLineEdit(item.title)
            self.child_title.setObjectName("childTitleEdit")
            self.child_title.setPlaceholderText(item.field_path or "(whole message)")
            self.child_title.textChanged.connect(self._title_edited)
            form_row.addRow("Child title", self.child_title)
            lay.addLayout(form_row)
        if spec is None:
            lay.addWidget(_label(f"No installed widget package offers {item.kind!r}; its settings are kept.",
                                 "problem"))
        else:
            note = ""
            try:
                settings = spec.make_settings(item.settings)
            except SettingsError as exc:
                note = f"{exc}; the form starts from the defaults"
                settings = spec.make_settings({})
            if note:
                lay.addWidget(_label(note, "problem"))
            make_form = self._form
            if settings is not None and make_form is None:
                lay.addWidget(_label("Its settings are edited in the settings form.", "hint"))
            elif settings is not None and make_form is not None:
                outer, parent_context = self, self._context  # the child's context is drawn from ours

                def child_context() -> ChildContext | None:
                    ctx = parent_context()
                    if ctx is None:
                        return None
                    i = outer.editing if outer.editing is not None else index
                    return ChildContext(ctx.types, ctx.plugins,
                                        lambda: outer.catalog().child_binding(i, outer.children_list[i]),  # type: ignore[union-attr]
                                        ctx.learn)

                form = make_form(settings, context=child_context)
                form.setObjectName("childSettingsForm")
                form.changed.connect(self._child_form_edited)
                lay.addWidget(form)
                self.child_form = form
            else:
                lay.addWidget(_label("This widget has no settings.", "hint"))
        self.child_problems_label = _label("", "problem")
        self.child_problems_label.setObjectName("childProblemsLabel")
        lay.addWidget(self.child_problems_label)
        row = QtWidgets.QHBoxLayout()
        row.addWidget(_button("Remove child", "childRemove", lambda: self.remove_child(index)))
        row.addStretch(1)
        row.addWidget(_button("Done", "childDone", self.show_list, primary=True))
        lay.addLayout(row)
        self._show_child_problems()
        self._show("child")

    def _title_edited(self, text: str) -> None:
        if self.editing is not None:
            self.children_list[self.editing] = attrs.evolve(self.children_list[self.editing], title=text)
            self._changed()

    def _child_form_edited(self) -> None:
        if self.editing is None or self.child_form is None:
            return
        cat = self.catalog()
        item = self.children_list[self.editing]
        spec = cat.spec_of(item.kind) if cat is not None else None
        if spec is not None:
            data = spec.settings_to_dict(self.child_form.value())
            self.children_list[self.editing] = attrs.evolve(item, settings=data)
            self._changed()
        self._show_child_problems()

    def _show_child_problems(self) -> None:
        if self.editing is None:
            return
        problems = self.child_problems(self.editing)
        self.child_problems_label.setText("\n".join(f"⚠ {p}" for p in problems))
        self.child_problems_label.setVisible(bool(problems))

    # -- learning the type -------------------------------------------------------------------------
    def _learn(self, cat: ChildCatalog, then: Callable[[], None]) -> None:
        ctx = self._context()
        if ctx is None or ctx.learn is None:
            self._say(f"{cat.type_name} is not known here and there is no robot to ask.")
            return
        if self._learning is None:
            self._learning = ctx.learn(cat.type_name, cat.is_service)
        self._after_learning = then
        self._say(f"Asking the robot for the definition of {cat.type_name}…")

    def _tick(self) -> None:
        fut = self._learning
        if fut is not None and fut.done():
            self._learning = None
            try:
                learned = fut.result()
                ctx = self._context()
                if ctx is not None:
                    for root, typedefs in learned:
                        if typedefs:
                            ctx.types.add_typedefs(typedefs, root=root)
            except Exception as exc:  # the robot does not know it, or the link is down
                self._say(f"Could not learn the type from the robot: {exc}")
                self._after_learning = None
                return
            then, self._after_learning = self._after_learning, None
            cat = self.catalog()
            if cat is not None and not cat.known():
                self._say(f"The robot does not know {cat.type_name}.")
            elif then is not None:
                self._say("")
                then()
        if self.current_page == "list" and self.isVisible():
            ctx = self._context()
            b = ctx.binding() if ctx is not None else None
            key = (b.name, b.type, b.role) if b is not None else None
            if key != self._last_binding:  # the topic/service changed under the children: recheck them
                self._last_binding = key
                status = self.status.text()
                self._follow = False  # a refresh, not the operator's move: leave the scrolling alone
                try:
                    self.show_list()
                finally:
                    self._follow = True
                self.status.setText(status)

    def _say(self, text: str) -> None:
        self.status.setText(text)
        self.status.setVisible(bool(text))

    def _changed(self) -> None:
        self.changed.emit()
