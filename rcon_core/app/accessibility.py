"""What assistive technology (a screen reader, switch access) learns about the app's controls: each one's
accessible name and role.

Qt gives its own controls a role (a button is a button, a field is editable text) and takes a name from
their text, or from a label that is their buddy; a control with neither, an icon button, or a widget that
paints itself (the teleop pad, the map) needs ``setAccessibleName``. A widget that paints itself has no
role of its own (Qt calls it a "client" area): it sets the dynamic property ``accessibleRole`` to the name
of a ``QAccessible.Role`` ("Canvas" for a pad or a map, "Graphic" for a picture), and the factory installed
here (:func:`install`, by the main window) gives it that role. :func:`nameless_controls` lists the controls
that still lack one or the other: the app's tests walk the demo window and every bundled widget with it.
Widget packages follow the same rules (docs/writing-a-widget-plugin.md).
"""

from __future__ import annotations

from typing import Any

from qtpy import QtCore, QtGui, QtWidgets

__all__ = ["install", "nameless_controls", "role_of", "name_of"]

#: the dynamic property naming a self-painted widget's role (a QAccessible.Role member's name)
ROLE_PROPERTY = "accessibleRole"
#: Qt's own controls: always interactive
CONTROLS = (QtWidgets.QAbstractButton, QtWidgets.QComboBox, QtWidgets.QLineEdit, QtWidgets.QAbstractSpinBox,
            QtWidgets.QAbstractSlider, QtWidgets.QTextEdit, QtWidgets.QPlainTextEdit, QtWidgets.QAbstractItemView,
            QtWidgets.QTabBar)
#: roles that say nothing of what a control is
NO_ROLES = (QtGui.QAccessible.Role.NoRole, QtGui.QAccessible.Role.Client)
_installed = False


def _factory(_key: str, obj: Any) -> Any:
    if isinstance(obj, QtWidgets.QWidget):
        role = obj.property(ROLE_PROPERTY)
        if isinstance(role, str) and role:
            member = getattr(QtGui.QAccessible.Role, role, None)
            if member is not None:
                return QtWidgets.QAccessibleWidget(obj, member, "")
    return None


def install() -> None:
    """Install the role factory (once per process)."""
    global _installed
    if not _installed:
        QtGui.QAccessible.installFactory(_factory)
        _installed = True


def _interface(widget: QtWidgets.QWidget) -> Any:
    return QtGui.QAccessible.queryAccessibleInterface(widget)


def name_of(widget: QtWidgets.QWidget) -> str:
    iface = _interface(widget)
    return (iface.text(QtGui.QAccessible.Text.Name) or "").strip() if iface is not None else ""


def role_of(widget: QtWidgets.QWidget) -> Any:
    iface = _interface(widget)
    return iface.role() if iface is not None else QtGui.QAccessible.Role.NoRole


def is_control(widget: QtWidgets.QWidget) -> bool:
    """Whether a person operates ``widget``: one of Qt's controls, or a widget that takes touches or the
    keyboard itself (a pad, a map), not a box that only holds others."""
    if isinstance(widget, CONTROLS):
        return True
    if isinstance(widget, (QtWidgets.QAbstractScrollArea, QtWidgets.QDialog, QtWidgets.QMainWindow,
                           QtWidgets.QMenu, QtWidgets.QSplitterHandle)):
        return False
    if widget.property(ROLE_PROPERTY):
        return True
    takes = widget.focusPolicy() != QtCore.Qt.FocusPolicy.NoFocus
    touch = widget.testAttribute(QtCore.Qt.WidgetAttribute.WA_AcceptTouchEvents)
    return (takes or touch) and type(widget).__module__.split(".")[0] not in ("PySide6", "PyQt6", "PyQt5")


def _qt_part(widget: QtWidgets.QWidget) -> bool:
    """A part Qt builds inside one of its controls (a combo box's line edit, a spin box's, a list's header,
    a scroll area's bars): the control names it, Qt gives the part its role."""
    parent = widget.parentWidget()
    if isinstance(parent, (QtWidgets.QComboBox, QtWidgets.QAbstractSpinBox)) or isinstance(
            widget, QtWidgets.QHeaderView) or widget.objectName() == "qt_tableview_cornerbutton":
        return True
    holder = parent.parentWidget() if parent is not None else None
    return isinstance(widget, QtWidgets.QScrollBar) and isinstance(holder, QtWidgets.QAbstractScrollArea)


def name_parts(view: QtWidgets.QWidget, title: str) -> None:
    """Name what a widget's view leaves nameless, from what it shows: the view itself after the widget's
    title; a field by its placeholder ("Log: filter"); a read-only text area, or the view's only slider,
    as the widget; a button without words by its tooltip. Whatever has nothing to go by stays nameless
    (the accessibility test finds it)."""
    # plain property reads only (no accessibility interface is made here: views are built often)
    if not view.accessibleName() and title:
        view.setAccessibleName(title)
    sliders = [s for s in view.findChildren(QtWidgets.QAbstractSlider) if not _qt_part(s)]
    for widget in view.findChildren(QtWidgets.QWidget):
        if widget.accessibleName() or not is_control(widget) or _qt_part(widget):
            continue
        name = ""
        if isinstance(widget, QtWidgets.QLineEdit) and widget.placeholderText():
            name = f"{title}: {widget.placeholderText().rstrip('…')}"
        elif isinstance(widget, (QtWidgets.QPlainTextEdit, QtWidgets.QTextEdit)) and widget.isReadOnly():
            name = title
        elif isinstance(widget, QtWidgets.QAbstractSlider) and sliders == [widget]:
            name = title
        elif isinstance(widget, QtWidgets.QAbstractButton) and not widget.text() and widget.toolTip():
            name = widget.toolTip()
        if name:
            widget.setAccessibleName(name)


def name_side_panel(tabs: QtWidgets.QTabWidget) -> None:
    """The side panel's search fields and lists, after their tab: "Search topics", "Topics list"."""
    for k in range(tabs.count()):
        page, what = tabs.widget(k), tabs.tabText(k)
        if page is None:
            continue
        for field in page.findChildren(QtWidgets.QLineEdit):
            if not field.accessibleName() and not _qt_part(field):
                field.setAccessibleName(f"Search {what.lower()}")
        for view in page.findChildren(QtWidgets.QAbstractItemView):
            if not view.accessibleName() and not _qt_part(view):
                view.setAccessibleName(f"{what} list")


def nameless_controls(root: QtWidgets.QWidget, visible_only: bool = True) -> list[str]:
    """Every control under ``root`` (and ``root`` itself) that has no accessible name, or no role that says
    what it is: "<class>#<objectName> in <parent chain>: no name" lines, empty when all are named."""
    out = []
    for widget in [root, *root.findChildren(QtWidgets.QWidget)]:
        if visible_only and not widget.isVisible():
            continue
        if not is_control(widget) or _qt_part(widget):
            continue
        problems = []
        if not name_of(widget):
            problems.append("no name")
        if role_of(widget) in NO_ROLES:
            problems.append("no role")
        if problems:
            chain: list[str] = []
            parent = widget.parentWidget()
            while parent is not None and len(chain) < 4:
                chain.append(f"{type(parent).__name__}#{parent.objectName()}")
                parent = parent.parentWidget()
            out.append(f"{type(widget).__name__}#{widget.objectName()} in {' < '.join(chain)}: "
                       f"{', '.join(problems)}")
    return out
