"""Finding text that does not fit on screen, as a person would see it cut: a label or button narrower or
shorter than its text, a widget cut off by the edge of what holds it. Shared by the text size tests."""

from __future__ import annotations

from qtpy import QtCore, QtWidgets

from rcon_core.app.elided_label import ElidedLabel

#: rounding and anti-aliasing slack, px
SLACK = 2


def _shown(label: QtWidgets.QLabel) -> str:
    return label.shown() if isinstance(label, ElidedLabel) else label.text()


def paints_itself(widget: QtWidgets.QWidget) -> bool:
    """A label or button that draws its own text (shrinking its font or eliding to fit, like the std
    widgets' captions): it is responsible for fitting, and QLabel's measure does not apply."""
    for base in (QtWidgets.QLabel, QtWidgets.QPushButton, QtWidgets.QToolButton):
        if isinstance(widget, base) and type(widget).paintEvent is not base.paintEvent:
            return True
    return False


def _inside_scroll(widget: QtWidgets.QWidget, parent: QtWidgets.QWidget) -> bool:
    """Whether ``parent`` scrolls ``widget`` (a scroll area's viewport or its content: cut on purpose)."""
    return isinstance(parent.parentWidget(), QtWidgets.QAbstractScrollArea) or (
        isinstance(parent, QtWidgets.QWidget) and parent.objectName() in ("qt_scrollarea_viewport",))


def cut_by_parent(widget: QtWidgets.QWidget) -> str | None:
    """Why ``widget`` is cut off by an ancestor's edge (not a scrolling one), or None."""
    child, parent = widget, widget.parentWidget()
    while parent is not None and not child.isWindow():
        if _inside_scroll(child, parent) or isinstance(parent, QtWidgets.QAbstractScrollArea):
            return None
        if not parent.rect().contains(child.geometry()):
            return f"cut by {type(parent).__name__}#{parent.objectName()} {parent.rect()} at {child.geometry()}"
        child, parent = parent, parent.parentWidget()
    return None


def text_problem(widget: QtWidgets.QWidget) -> str | None:
    """Why ``widget``'s text does not fit in it (None: it fits, or it has no text to measure)."""
    fm = widget.fontMetrics()
    if paints_itself(widget):
        return None
    if isinstance(widget, QtWidgets.QLabel):
        text = _shown(widget)
        if not text or widget.pixmap() is not None and not widget.pixmap().isNull() or widget.textFormat() == \
                QtCore.Qt.TextFormat.RichText or text.lstrip().startswith("<"):
            return None
        rect = widget.contentsRect().adjusted(widget.margin(), widget.margin(), -widget.margin(), -widget.margin())
        if widget.wordWrap():
            need = widget.heightForWidth(widget.width())
            return f"needs {need} px of height, has {widget.height()}" if need > widget.height() + SLACK else None
        lines = text.split("\n")
        wide = max(fm.horizontalAdvance(line) for line in lines)
        tall = fm.height() * len(lines) if len(lines) > 1 else fm.ascent()  # one line: its letters above the base
        if wide > rect.width() + SLACK:
            return f"text {wide} px wide in {rect.width()}"
        if tall > rect.height() + SLACK:
            return f"text {tall} px tall in {rect.height()}"
        return None
    if isinstance(widget, QtWidgets.QAbstractButton) and widget.text():
        text = widget.text().replace("&&", "&")
        wide = fm.horizontalAdvance(text) + (widget.iconSize().width() if not widget.icon().isNull() else 0)
        if isinstance(widget, QtWidgets.QCheckBox):
            wide += 20
        if wide + 6 > widget.width() + SLACK:
            return f"text {wide} px wide in {widget.width()}"
        if fm.ascent() + 6 > widget.height() + SLACK:
            return f"text {fm.ascent()} px tall in {widget.height()}"
    return None


def problems(root: QtWidgets.QWidget) -> list[str]:
    """Every visible label and button under ``root`` whose text does not fit, or cut off by what holds it."""
    out = []
    for widget in [root, *root.findChildren(QtWidgets.QWidget)]:
        if not widget.isVisible() or widget.width() <= 0 or widget.height() <= 0:
            continue
        name = f"{type(widget).__name__}#{widget.objectName()} {getattr(widget, 'text', lambda: '')()!r}"
        if isinstance(widget, (QtWidgets.QLabel, QtWidgets.QAbstractButton)):
            why = text_problem(widget)
            if why:
                out.append(f"{name}: {why}")
        if isinstance(widget, (QtWidgets.QLabel, QtWidgets.QAbstractButton, QtWidgets.QLineEdit,
                               QtWidgets.QComboBox, QtWidgets.QAbstractSpinBox)) and not isinstance(
                widget.parentWidget(), (QtWidgets.QComboBox, QtWidgets.QAbstractSpinBox)):  # Qt places those
            why = cut_by_parent(widget)
            if why:
                out.append(f"{name}: {why}")
    return out
