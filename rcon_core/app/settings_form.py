"""A form generated from a widget's attrs settings class.

Supported field types: ``str``, ``int``, ``float``, ``bool``, ``enum.Enum`` subclasses, ``typing.Literal``
and any field with ``metadata={"choices": [...]}``.  Optional metadata: ``label``, ``help``, ``min``,
``max``, ``step``, ``decimals``.  A *children field* (a ``list`` of an attrs class with ``kind``,
``field_path`` and ``settings``, see :mod:`rcon_core.plugins.children`) gets the children editor;
its metadata may add ``exclude_kinds`` (kinds that cannot be children).  Fields of other types keep
their value and are not shown.

Text fields are at least :data:`TEXT_MIN_WIDTH` wide, so in a narrow panel their label goes above them and
they take the row's full width. A text field declared with metadata ``multiline: True`` (a message typed
as YAML or JSON) gets a multi-line editor.

Spin boxes, combo boxes and sliders of a form ignore the mouse wheel unless they have the keyboard focus
(tap them first): a wheel over them scrolls the form instead of changing the value under the pointer
(:func:`guard_wheel`, also used by the add panel's own choosers).
"""

from __future__ import annotations

import enum
import typing
from typing import Any

import attrs
from qtpy import QtCore, QtGui, QtWidgets

from rcon_core.app.children_editor import ChildrenEditor
from rcon_core.plugins.children import ChildContext, children_item_class, settings_problems

#: a context, or a function giving the current one
ContextArg = ChildContext | typing.Callable[[], ChildContext | None] | None

INT_RANGE = 2_000_000_000


class _WheelGuard(QtCore.QObject):
    """Event filter: a wheel over an unfocused value editor scrolls the enclosing scroll area instead."""

    def eventFilter(self, obj: QtCore.QObject, event: QtCore.QEvent) -> bool:
        if event.type() != QtCore.QEvent.Type.Wheel or not isinstance(obj, QtWidgets.QWidget) or obj.hasFocus():
            return False
        wheel = typing.cast(QtGui.QWheelEvent, event)
        scroll = obj.parentWidget()
        while scroll is not None and not isinstance(scroll, QtWidgets.QAbstractScrollArea):
            scroll = scroll.parentWidget()
        if scroll is None:  # nothing to scroll: let the event travel on to the parents, unused here
            event.ignore()
            return True
        viewport = scroll.viewport()
        pos = viewport.mapFromGlobal(wheel.globalPosition())
        forwarded = QtGui.QWheelEvent(
            pos, wheel.globalPosition(), wheel.pixelDelta(), wheel.angleDelta(), wheel.buttons(),
            wheel.modifiers(), wheel.phase(), wheel.inverted(), wheel.source(),
        )
        QtWidgets.QApplication.sendEvent(viewport, forwarded)
        event.accept()
        return True


def guard_wheel(widget: QtWidgets.QWidget) -> QtWidgets.QWidget:
    """Make ``widget`` (a spin box, combo box, slider...) take the wheel only once it has the focus;
    it no longer takes the focus from a wheel either. Returns ``widget``."""
    widget.setFocusPolicy(QtCore.Qt.FocusPolicy.StrongFocus)
    if widget.findChild(_WheelGuard, "wheelGuard", QtCore.Qt.FindChildOption.FindDirectChildrenOnly) is None:
        guard = _WheelGuard(widget)  # lives and dies with the editor
        guard.setObjectName("wheelGuard")
        widget.installEventFilter(guard)
    return widget


#: editors whose value a wheel changes
WHEEL_EDITORS = (QtWidgets.QAbstractSpinBox, QtWidgets.QComboBox, QtWidgets.QAbstractSlider)
#: where an editor's text starts, from its outer left edge: the theme's 3 px border and 8 px padding
TEXT_INSET = 11
#: the narrowest a number editor gets before its row wraps (its label above it); Qt would otherwise size it
#: for the longest number of its range (13 digits) and wrap every number row in the narrow add panel
SPIN_MIN_WIDTH = 120
#: the narrowest a text field gets before its row wraps (label above, the field the full row's width)
TEXT_MIN_WIDTH = 240
#: lines a multi-line text field shows (it scrolls past that)
TEXT_LINES = 3


def form_label(text: str, buddy: QtWidgets.QWidget | None = None) -> QtWidgets.QLabel:
    """A form row's label, vertically centred on its (taller, touch-sized) field: QFormLayout gives a
    label the whole row's height only when it may grow vertically; its text is centred in that."""
    label = QtWidgets.QLabel(text)
    label.setSizePolicy(QtWidgets.QSizePolicy.Policy.Preferred, QtWidgets.QSizePolicy.Policy.Expanding)
    label.setAlignment(QtCore.Qt.AlignmentFlag.AlignLeft | QtCore.Qt.AlignmentFlag.AlignVCenter)
    if buddy is not None:
        label.setBuddy(buddy)
    return label


def tune_form(layout: QtWidgets.QFormLayout) -> QtWidgets.QFormLayout:
    """The form look of RCON's settings: labels left of their fields and centred on them, fields taking the
    rest of the width; a row whose label and field do not fit side by side (a very narrow panel) puts the
    label above. Use :func:`form_label` for the labels. Returns ``layout``."""
    layout.setFieldGrowthPolicy(QtWidgets.QFormLayout.FieldGrowthPolicy.AllNonFixedFieldsGrow)
    layout.setRowWrapPolicy(QtWidgets.QFormLayout.RowWrapPolicy.WrapLongRows)
    layout.setLabelAlignment(QtCore.Qt.AlignmentFlag.AlignLeft | QtCore.Qt.AlignmentFlag.AlignVCenter)
    layout.setFormAlignment(QtCore.Qt.AlignmentFlag.AlignLeft | QtCore.Qt.AlignmentFlag.AlignTop)
    return layout


class _SpinTextInset(QtCore.QObject):
    """Event filter on a spin box's inner line edit: keeps its text :data:`TEXT_INSET` px from the spin
    box's outer edge, like a line edit's (the style sheet style places the inner edit at the very left,
    over the border, ignoring the theme's padding)."""

    def eventFilter(self, obj: QtCore.QObject, event: QtCore.QEvent) -> bool:
        if event.type() in (QtCore.QEvent.Type.Move, QtCore.QEvent.Type.Show) and isinstance(obj, QtWidgets.QLineEdit):
            inset = max(0, TEXT_INSET - obj.x())
            margins = obj.textMargins()
            if margins.left() != inset:
                obj.setTextMargins(inset, margins.top(), margins.right(), margins.bottom())
        return False


def pad_spin_box(spin: QtWidgets.QAbstractSpinBox) -> QtWidgets.QAbstractSpinBox:
    """Give ``spin``'s text the same inner padding as a line edit's, and a modest minimum width.
    Returns ``spin``."""
    spin.setMinimumWidth(SPIN_MIN_WIDTH)
    edit = spin.findChild(QtWidgets.QLineEdit)
    if edit is not None and edit.findChild(_SpinTextInset, "spinTextInset") is None:
        inset = _SpinTextInset(edit)
        inset.setObjectName("spinTextInset")
        edit.installEventFilter(inset)
        edit.setTextMargins(max(0, TEXT_INSET - edit.x()), 0, 0, 0)
    return spin


def _resolved_fields(cls: type) -> tuple[attrs.Attribute, ...]:
    try:
        attrs.resolve_types(cls)
    except Exception:  # unresolvable forward refs: fall back to whatever .type holds
        pass
    return attrs.fields(cls)


def _unwrap_optional(tp: Any) -> Any:
    if typing.get_origin(tp) in (typing.Union, getattr(__import__("types"), "UnionType", None)):
        args = [a for a in typing.get_args(tp) if a is not type(None)]
        if len(args) == 1:
            return args[0]
    return tp


def _is_multiline(field: attrs.Attribute) -> bool:
    """A text field declared ``metadata={"multiline": True}`` (a message typed as YAML or JSON)."""
    return bool(field.metadata.get("multiline", False))


class TextBlock(QtWidgets.QPlainTextEdit):
    """A multi-line plain-text field (a message as YAML or JSON): :data:`TEXT_LINES` lines high, wrapping
    at its width, as wide as the row; Tab moves on to the next field instead of typing a tab."""

    def __init__(self, text: str = "") -> None:
        super().__init__(text)
        self.setTabChangesFocus(True)
        self.setLineWrapMode(QtWidgets.QPlainTextEdit.LineWrapMode.WidgetWidth)
        self.setMinimumWidth(TEXT_MIN_WIDTH)
        self.setSizePolicy(QtWidgets.QSizePolicy.Policy.Expanding, QtWidgets.QSizePolicy.Policy.Fixed)
        self._fit_height()

    def _fit_height(self) -> None:
        margins = self.contentsMargins()
        doc = int(self.document().documentMargin() * 2)
        self.setFixedHeight(self.fontMetrics().lineSpacing() * TEXT_LINES + doc + margins.top()
                            + margins.bottom() + 8)

    def changeEvent(self, event: QtCore.QEvent) -> None:
        super().changeEvent(event)
        if event.type() in (QtCore.QEvent.Type.FontChange, QtCore.QEvent.Type.StyleChange):
            self._fit_height()


def _label(field: attrs.Attribute) -> str:
    return str(field.metadata.get("label") or field.name.replace("_", " ").capitalize())


class SettingsForm(QtWidgets.QWidget):
    """Edits one attrs settings instance; emits ``changed`` after every edit.

    ``context`` (a :class:`ChildContext` or a function returning one) is what a children field needs:
    the type registry, the plugins and the widget's binding. The main window passes one
    (:meth:`MainWindow.child_context`).
    """

    changed = QtCore.Signal()

    def __init__(self, settings: Any, parent: QtWidgets.QWidget | None = None, *,
                 context: ContextArg = None) -> None:
        super().__init__(parent)
        if not attrs.has(type(settings)):
            raise TypeError(f"settings must be an attrs instance, not {type(settings).__name__}")
        self._cls = type(settings)
        self._value = settings
        self._initial = settings
        self._context = context
        self._editors: dict[str, tuple[QtWidgets.QWidget, typing.Callable[[], Any]]] = {}
        self.children_editors: dict[str, ChildrenEditor] = {}
        layout = tune_form(QtWidgets.QFormLayout(self))
        layout.setContentsMargins(0, 0, 0, 0)  # lined up with the rows above it (add panel, Configure)
        layout.setVerticalSpacing(10)
        for field in _resolved_fields(self._cls):
            if field.name.startswith("_"):
                continue
            built = self._editor_for(field, getattr(settings, field.name))
            if built is None:
                continue
            editor, getter = built
            editor.setObjectName(f"setting_{field.name}")
            if isinstance(editor, WHEEL_EDITORS):
                guard_wheel(editor)
            if isinstance(editor, QtWidgets.QAbstractSpinBox):
                pad_spin_box(editor)
            if field.metadata.get("help"):
                editor.setToolTip(str(field.metadata["help"]))
            self._editors[field.name] = (editor, getter)
            if isinstance(editor, TextBlock):  # a message: the row's full width, its label above it
                label = QtWidgets.QLabel(_label(field))
                label.setBuddy(editor)
                layout.addRow(label)
                layout.addRow(editor)
            elif isinstance(editor, ChildrenEditor):  # full width under its heading
                heading = QtWidgets.QLabel(_label(field))
                heading.setProperty("role", "heading")
                layout.addRow(heading)
                layout.addRow(editor)
            else:
                layout.addRow(form_label(_label(field), editor), editor)
        if not self._editors:
            note = QtWidgets.QLabel("This widget has no settings.")
            note.setProperty("role", "hint")
            layout.addRow(note)

    # ----------------------------------------------------------------------------------------- building
    def _editor_for(self, field: attrs.Attribute, value: Any):
        tp = _unwrap_optional(field.type)
        meta = field.metadata
        item_cls = children_item_class(tp)
        if item_cls is not None:
            children = ChildrenEditor(item_cls, list(value or []), self.child_context,
                                      exclude=tuple(meta.get("exclude_kinds", ())), form=SettingsForm)
            self.children_editors[field.name] = children
            children.changed.connect(self._edited)
            return children, children.value
        choices = meta.get("choices")
        if choices is None and typing.get_origin(tp) is typing.Literal:
            choices = list(typing.get_args(tp))
        if choices is None and isinstance(tp, type) and issubclass(tp, enum.Enum):
            choices = list(tp)
        if choices is not None:
            box = QtWidgets.QComboBox()
            box.setSizeAdjustPolicy(QtWidgets.QComboBox.SizeAdjustPolicy.AdjustToMinimumContentsLengthWithIcon)
            for choice in choices:
                text = choice.name if isinstance(choice, enum.Enum) else str(choice)
                box.addItem(text, choice)
            index = next((i for i, c in enumerate(choices) if c == value), -1)
            box.setCurrentIndex(max(0, index) if choices else -1)
            box.currentIndexChanged.connect(self._edited)
            return box, box.currentData
        if tp is bool:
            check = QtWidgets.QCheckBox()
            check.setChecked(bool(value))
            check.toggled.connect(self._edited)
            return check, check.isChecked
        if tp is int:
            spin = QtWidgets.QSpinBox()
            spin.setRange(int(meta.get("min", -INT_RANGE)), int(meta.get("max", INT_RANGE)))
            spin.setSingleStep(int(meta.get("step", 1)))
            if meta.get("special"):  # words for the minimum: "as received", not "-1"
                spin.setSpecialValueText(str(meta["special"]))
            spin.setValue(int(value or 0))
            spin.valueChanged.connect(self._edited)
            return spin, spin.value
        if tp is float:
            dspin = QtWidgets.QDoubleSpinBox()
            dspin.setDecimals(int(meta.get("decimals", 3)))
            dspin.setRange(float(meta.get("min", -1e12)), float(meta.get("max", 1e12)))
            dspin.setSingleStep(float(meta.get("step", 0.1)))
            dspin.setValue(float(value or 0.0))
            dspin.valueChanged.connect(self._edited)
            return dspin, dspin.value
        if tp is str:
            text = "" if value is None else str(value)
            if _is_multiline(field):
                block = TextBlock(text)
                block.textChanged.connect(self._edited)
                return block, block.toPlainText
            line = QtWidgets.QLineEdit(text)
            line.setMinimumWidth(TEXT_MIN_WIDTH)
            line.textChanged.connect(self._edited)
            return line, line.text
        return None

    # ------------------------------------------------------------------------------------------- values
    def _edited(self, *_: Any) -> None:
        self._value = self._read()
        self.changed.emit()

    def _read(self) -> Any:
        values = {name: getter() for name, (_, getter) in self._editors.items()}
        try:
            return attrs.evolve(self._value, **values)
        except (TypeError, ValueError):
            return self._value  # a validator refused the edit: keep the last good value

    def value(self) -> Any:
        """The settings instance as currently edited."""
        return self._value

    def editor(self, name: str) -> QtWidgets.QWidget:
        """The editor of field ``name`` (for tests and accessibility tooling)."""
        return self._editors[name][0]

    def child_context(self) -> ChildContext | None:
        """The context children fields use: the one given, else found from the window."""
        ctx = self._context
        if callable(ctx) and not isinstance(ctx, ChildContext):
            return ctx()
        return ctx

    def problems(self) -> list[str]:
        """What is still missing or wrong, empty once valid: the settings' own ``problems()``, then what
        children editors find against the binding (a child on a field the type lacks...)."""
        context = self.child_context()
        out = settings_problems(self._value, context.plugins if context is not None else None)
        for children in self.children_editors.values():
            out += [p for p in children.problems() if p not in out]
        return out

