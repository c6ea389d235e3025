"""The *Configure* dialog of a placed widget: its field, title and settings in one form, kept out of
``main_window.py``.

OK is one undo step for all three (:meth:`Document.reconfigure_widget`); a new field rebinds the running
widget (the runtime rebuilds its model). Settings with problems (a slider's maximum of 999999999999) are
refused with the reason under the form; settings that could command more than the robot's safety envelope
allows are saved only after a question (``envelope_dialog.beyond_envelope``). The settings are the generated :class:`SettingsForm`, its children
editor (a Compound's children) given a :class:`~rcon_core.plugins.children.ChildContext` for the widget's
binding.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import attrs
from qtpy import QtCore, QtWidgets

from rcon_core.app.choosers import FieldChooser
from rcon_core.app.dialog_fit import room_for
from rcon_core.app.envelope_dialog import ask_beyond, beyond_envelope
from rcon_core.app.settings_form import SettingsForm, form_label, tune_form
from rcon_core.canvas import Document
from rcon_core.matcher import match
from rcon_core.plugins import Binding, PluginManager, WidgetSpec, settings_binding_problems
from rcon_core.plugins.children import ChildContext

__all__ = ["WidgetConfigurer", "field_choices"]


def field_choices(spec: WidgetSpec, binding: Binding, types: Any, plugins: PluginManager) -> list[str]:
    """The fields a widget of ``spec`` can bind on ``binding``'s type in its role, best first (the
    matcher's ``field_paths``); empty when it takes the whole message or the type is not known."""
    if not binding.type or not binding.field_paths:
        return []
    try:
        found = match(binding.type, binding.role, types, plugins)
    except ValueError:  # a malformed type name in the layout: nothing to choose from
        return []
    return next((list(m.field_paths) for m in found if m.spec.kind == spec.kind), [])


class WidgetConfigurer:
    """Opens the Configure dialog over ``parent`` for a widget of ``doc``'s workspace."""

    def __init__(self, parent: QtWidgets.QWidget, doc: Document, plugins: PluginManager, types: Any,
                 child_context: Callable[[Callable[[], Binding | None]], ChildContext],
                 dialog_closed: Callable[[QtWidgets.QDialog], None]) -> None:
        self.parent, self.doc, self.plugins, self.types = parent, doc, plugins, types
        self.child_context = child_context
        self.dialog_closed = dialog_closed
        self.dialog: QtWidgets.QDialog | None = None  #: the dialog opened last
        #: the question asked last before saving settings beyond the robot's safety envelope (tests)
        self.beyond_dialog: QtWidgets.QMessageBox | None = None

    def open(self, instance_id: str) -> None:
        """Edit a placed widget's field, title and settings in a dialog (window-modal, returns at once)."""
        try:
            _canvas, inst = self.doc.workspace.find_widget(instance_id)
        except KeyError:
            return
        if not self.plugins.has_widget(inst.kind):
            return
        spec = self.plugins.widget(inst.kind)
        settings = spec.make_settings(inst.settings)
        binding = inst.binding
        dialog = QtWidgets.QDialog(self.parent)
        dialog.setObjectName("configureDialog")
        dialog.setWindowTitle(f"Configure {inst.title or spec.title}")
        col = QtWidgets.QVBoxLayout(dialog)
        # one white page holding every label and field (no label boxes on the dialog's grey)
        body = QtWidgets.QFrame()
        body.setObjectName("configureBody")
        body.setStyleSheet("QFrame#configureBody { background: palette(base); border: 3px solid palette(dark);"
                           " border-radius: 6px; }")
        body_col = QtWidgets.QVBoxLayout(body)
        body_col.setContentsMargins(16, 12, 16, 12)
        heading = QtWidgets.QLabel(f"{spec.title} on {binding.name}" if binding.name else spec.title)
        heading.setProperty("role", "heading")
        body_col.addWidget(heading)
        top = QtWidgets.QFormLayout()
        tune_form(top)
        field = FieldChooser("configureField")
        field_label = form_label("Field", field)
        top.addRow(field_label, field)
        top.setRowVisible(field, field.set_fields(
            field_choices(spec, binding, self.types, self.plugins), binding.field_path, types=self.types,
            type_name=binding.type, service=binding.role.is_service))
        title = QtWidgets.QLineEdit(inst.title)
        title.setObjectName("configureTitle")
        title.setPlaceholderText(spec.title)
        title_label = form_label("Title", title)
        top.addRow(title_label, title)
        body_col.addLayout(top)
        form = SettingsForm(settings, context=self.child_context(lambda: binding)) if settings is not None else None
        if form is not None:
            body_col.addWidget(form)
            _align_with(top, (field_label, title_label), form)
        body_col.addStretch(1)  # a taller dialog leaves the rows as they are
        # the settings scroll inside a dialog that fits the window: a pad's dozen settings made it 729 px
        # tall, its OK and Cancel below a 600 px tablet's edge
        scroll = QtWidgets.QScrollArea()
        scroll.setObjectName("configureScroll")
        scroll.setWidgetResizable(True)
        scroll.setFrameShape(QtWidgets.QFrame.Shape.NoFrame)
        scroll.setHorizontalScrollBarPolicy(QtCore.Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        scroll.setWidget(body)
        QtWidgets.QScroller.grabGesture(scroll.viewport(), QtWidgets.QScroller.ScrollerGestureType.TouchGesture)
        col.addWidget(scroll, 1)
        buttons = QtWidgets.QDialogButtonBox(
            QtWidgets.QDialogButtonBox.StandardButton.Ok | QtWidgets.QDialogButtonBox.StandardButton.Cancel
        )
        problem = QtWidgets.QLabel()
        problem.setObjectName("configureProblem")
        problem.setProperty("role", "problem")
        problem.setWordWrap(True)
        col.addWidget(problem)
        if form is not None:
            form.changed.connect(lambda: problem.setText(""))
        buttons.rejected.connect(dialog.reject)
        col.addWidget(buttons)
        self.dialog = dialog

        def rebound_binding() -> Binding | None:
            path = field.current_path()
            if top.isRowVisible(field) and path is not None and path != binding.field_path:
                rest = tuple(p for p in binding.field_paths[1:] if p != path)
                return attrs.evolve(binding, field_paths=(path, *rest))
            return None

        def ok() -> None:
            """Settings that are wrong (a maximum of 999999999999) are refused, said under the form; settings
            that could command more than the robot's safety envelope allows are saved only when the operator
            says so (the robot is held to its envelope either way)."""
            problems = form.problems() if form is not None else []
            if form is not None:  # and the settings against the field they are bound to (an int8's range)
                problems += [p for p in settings_binding_problems(form.value(), rebound_binding() or binding,
                                                                  self.types) if p not in problems]
            if problems:
                problem.setText("Not saved: " + "; ".join(problems))
                return
            try:
                envelope = self.doc.workspace.robot_of(inst).envelope
            except KeyError:  # a robot not in the workspace: nothing to compare with
                envelope = None
            beyond = beyond_envelope(envelope, rebound_binding() or binding,
                                     form.value() if form is not None else None, self.plugins)
            if beyond:
                self.beyond_dialog = ask_beyond(dialog, beyond, dialog.accept)
                return
            dialog.accept()

        buttons.accepted.connect(ok)

        def apply() -> None:
            rebound = rebound_binding()
            self.doc.reconfigure_widget(  # one undo step for field, title and settings together
                instance_id,
                settings=spec.settings_to_dict(form.value()) if form is not None else None,
                binding=rebound,
                title=title.text(),
            )

        dialog.accepted.connect(apply)
        dialog.finished.connect(lambda _result: self.dialog_closed(dialog))
        _fit_to_window(dialog, scroll, body, self.parent)
        dialog.open()


def _fit_to_window(dialog: QtWidgets.QDialog, scroll: QtWidgets.QScrollArea, body: QtWidgets.QWidget,
                   parent: QtWidgets.QWidget) -> None:
    """Size ``dialog`` to show all of ``body`` when the window (and the screen) has the room, else as tall as
    the window, the settings scrolling; never wider than the window."""
    room = room_for(parent)
    bar = scroll.verticalScrollBar().sizeHint().width()
    layout = dialog.layout()
    margins = layout.contentsMargins().left() + layout.contentsMargins().right() if layout is not None else 0
    width = min(body.sizeHint().width() + bar + margins, room.width())
    scroll.setMinimumWidth(min(body.sizeHint().width() + bar, width))
    dialog.setMaximumSize(room)
    wanted = dialog.sizeHint().height() - scroll.sizeHint().height() + body.sizeHint().height()
    dialog.resize(width, min(wanted, room.height()))


def _align_with(top: QtWidgets.QFormLayout, labels: tuple[QtWidgets.QLabel, ...], form: QtWidgets.QWidget) -> None:
    """Give the dialog's own rows (field, title) the settings form's margins and label column, so the
    dialog reads as one form."""
    inner = form.layout()
    if not isinstance(inner, QtWidgets.QFormLayout):
        return
    top.setContentsMargins(inner.contentsMargins())
    top.setHorizontalSpacing(inner.horizontalSpacing())
    top.setLabelAlignment(inner.labelAlignment())
    widths = [label.sizeHint().width() for label in labels]
    for row in range(inner.rowCount()):
        item = inner.itemAt(row, QtWidgets.QFormLayout.ItemRole.LabelRole)
        widget = item.widget() if item is not None else None
        if widget is not None:
            widths.append(widget.sizeHint().width())
    for label in labels:
        label.setMinimumWidth(max(widths))
