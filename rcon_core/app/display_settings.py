"""Canvas ▾ → Display…: the theme (Sunlight, high contrast, or Night, dark) and the text size (100 to 200 %).

Each tap applies at once to the whole app (every window, panel, dialog and widget view follows; see
``theme.py``) and is saved in the app config, so the next start looks the same. Changing how the app looks
changes nothing on a robot: it needs no PIN, also while the operator lock is on (the operator in the sun
switches to Sunlight without calling a supervisor).
"""

from __future__ import annotations

from qtpy import QtGui, QtWidgets

from rcon_core.app import theme
from rcon_core.app.canvas_bar import CanvasBar
from rcon_core.app.config import AppConfig
from rcon_core.app.notice_bar import NoticeBar

__all__ = ["DisplayDialog", "DisplayMenu", "set_display"]


def set_display(config: AppConfig, notice: NoticeBar | None, theme_name: str | None = None,
                text_size: int | None = None) -> None:
    """Apply ``theme_name`` and/or ``text_size`` to the app now and save them in ``config`` (a failure to
    save is said on ``notice``)."""
    app = QtWidgets.QApplication.instance()
    if not isinstance(app, QtWidgets.QApplication):
        return
    chosen_theme = theme.check_theme(theme_name if theme_name is not None else config.theme)
    chosen_size = theme.check_text_size(text_size if text_size is not None else config.text_size)
    theme.apply(app, chosen_theme, chosen_size)
    from rcon_core.app.widget_frame import WidgetFrame

    for widget in app.allWidgets():  # every widget's text as large as its box allows (widget_frame.py)
        if isinstance(widget, WidgetFrame):
            widget.fit_text()
    try:
        config.set_display(chosen_theme, chosen_size)
    except OSError as exc:  # applied all the same; the next start may look different
        if notice is not None:
            notice.show_notice(f"⚠ The display settings could not be saved: {exc}")


class DisplayDialog(QtWidgets.QDialog):
    """Two theme buttons and a row of text sizes: large, checkable, one tap each."""

    def __init__(self, config: AppConfig, notice: NoticeBar | None, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.setObjectName("displayDialog")
        self.setWindowTitle("Display")
        self.config, self.notice = config, notice
        col = QtWidgets.QVBoxLayout(self)
        heading = QtWidgets.QLabel("Theme")
        heading.setProperty("role", "heading")
        col.addWidget(heading)
        self.theme_buttons: dict[str, QtWidgets.QPushButton] = {}
        themes = QtWidgets.QVBoxLayout()  # one above the other: whole names at any text size
        group = QtWidgets.QButtonGroup(self)
        for name in theme.THEMES:
            button = QtWidgets.QPushButton(theme.THEME_NAMES[name])
            button.setObjectName(f"theme-{name}")
            button.setCheckable(True)
            button.setAccessibleName(f"Theme: {theme.THEME_NAMES[name]}")
            button.clicked.connect(lambda _c=False, n=name: self._pick(theme_name=n))
            group.addButton(button)
            themes.addWidget(button)
            self.theme_buttons[name] = button
        col.addLayout(themes)
        size_heading = QtWidgets.QLabel("Text size")
        size_heading.setProperty("role", "heading")
        col.addWidget(size_heading)
        self.size_buttons: dict[int, QtWidgets.QPushButton] = {}
        sizes = QtWidgets.QGridLayout()
        size_group = QtWidgets.QButtonGroup(self)
        for k, size in enumerate(theme.TEXT_SIZES):
            button = QtWidgets.QPushButton(f"{size} %")
            button.setObjectName(f"text-{size}")
            button.setCheckable(True)
            button.setAccessibleName(f"Text size {size} percent")
            button.clicked.connect(lambda _c=False, s=size: self._pick(text_size=s))
            size_group.addButton(button)
            sizes.addWidget(button, k // 3, k % 3)
            self.size_buttons[size] = button
        col.addLayout(sizes)
        hint = QtWidgets.QLabel("Applies at once, kept for the next start.")
        hint.setProperty("role", "hint")
        hint.setWordWrap(True)
        col.addWidget(hint)
        close = QtWidgets.QDialogButtonBox(QtWidgets.QDialogButtonBox.StandardButton.Close)
        close.rejected.connect(self.reject)
        col.addWidget(close)
        self._show_current()

    def _pick(self, theme_name: str | None = None, text_size: int | None = None) -> None:
        set_display(self.config, self.notice, theme_name, text_size)
        self._show_current()
        self.adjustSize()

    def _show_current(self) -> None:
        self.theme_buttons[theme.current_theme()].setChecked(True)
        self.size_buttons[theme.current_text_size()].setChecked(True)


class DisplayMenu:
    """*Display…* in the canvas bar's menu (after the canvas actions, never PIN-gated); ``dialog``: the
    last one opened."""

    def __init__(self, config: AppConfig, notice: NoticeBar, bar: CanvasBar, parent: QtWidgets.QWidget) -> None:
        self.config, self.notice, self.parent = config, notice, parent
        self.dialog: DisplayDialog | None = None
        menu = bar.menu
        self.action = action = QtGui.QAction("Display…", menu)
        action.setObjectName("canvas_display")
        before = bar.canvas_actions.get("lock")
        if before is not None:
            menu.insertAction(before, action)
        else:
            menu.addAction(action)
        bar.canvas_actions["display"] = action
        action.triggered.connect(self.open_dialog)

    def open_dialog(self) -> DisplayDialog:
        dialog = DisplayDialog(self.config, self.notice, self.parent)
        dialog.finished.connect(lambda _r: dialog.deleteLater())
        self.dialog = dialog
        dialog.open()
        return dialog
