"""Touch sizing, the two themes and the text size: the style sheet (``theme.qss``, shipped as package data)
filled in for one of them, and the matching palette.

Two themes: ``sunlight`` (high contrast on light surfaces, black text: reflections hurt dark themes
outdoors; the default) and ``night`` (dark, dim surfaces and light grey text that do not dazzle in the
dark). The text size (``TEXT_SIZES``: 100 to 200 %) scales every font of the style sheet; the touch size
(9 mm, at least 48 px) does not change with it, but nothing is smaller than its text needs.
:func:`apply` sets them on the application at run time (every window and every widget view follows: the
style sheet's font and colours become each widget's font and palette, and a view that paints itself reads
them from its palette); the window saves the choice (``AppConfig.theme``, ``AppConfig.text_size``).
"""

from __future__ import annotations

from importlib import resources

from qtpy import QtGui, QtWidgets

#: the smallest comfortable touch target, in millimetres, and the pixel floor below which we never go
TOUCH_MM = 9.0
TOUCH_FLOOR_PX = 48
#: the text sizes the operator can choose, in percent of the standard one
TEXT_SIZES = (100, 125, 150, 175, 200)
DEFAULT_THEME = "sunlight"

#: each theme's colours, by the names theme.qss uses (@C_NAME@)
THEMES: dict[str, dict[str, str]] = {
    "sunlight": {
        "WINDOW": "#f2f2f2", "BASE": "#ffffff", "TEXT": "#000000", "BORDER": "#000000",
        "ACCENT": "#0040a0", "ACCENT_TEXT": "#ffffff", "FOCUS": "#0040a0",
        "PRESSED": "#000000", "PRESSED_TEXT": "#ffffff",
        "DISABLED": "#707070", "DISABLED_BORDER": "#909090",
        "PRIMARY_OFF": "#d0d0d0", "PRIMARY_OFF_TEXT": "#505050",
        "RULE": "#c0c0c0", "TAB": "#e0e0e0", "CANVAS": "#e8e8e8",
        "THUMB": "#9a9a9a", "THUMB_HOVER": "#6a6a6a", "THUMB_PRESSED": "#404040",
        "MENU_OFF": "#8a8a8a", "PROBLEM": "#b00000", "HINT": "#303030",
        "TITLE": "#000000", "TITLE_TEXT": "#ffffff", "GRID": "#b8b8b8",
    },
    "night": {
        "WINDOW": "#15171a", "BASE": "#1f2226", "TEXT": "#e2e4e7", "BORDER": "#9aa0a6",
        "ACCENT": "#2f63b8", "ACCENT_TEXT": "#ffffff", "FOCUS": "#86b1ff",
        "PRESSED": "#e2e4e7", "PRESSED_TEXT": "#000000",
        "DISABLED": "#80868d", "DISABLED_BORDER": "#555a60",
        "PRIMARY_OFF": "#33373c", "PRIMARY_OFF_TEXT": "#8a9096",
        "RULE": "#3a3e44", "TAB": "#2b2f34", "CANVAS": "#0e1012",
        "THUMB": "#5c6167", "THUMB_HOVER": "#80868d", "THUMB_PRESSED": "#a8adb3",
        "MENU_OFF": "#6a7076", "PROBLEM": "#ff7b72", "HINT": "#b4b9bf",
        "TITLE": "#000000", "TITLE_TEXT": "#e2e4e7", "GRID": "#3a3e44",
    },
}
#: the words the operator reads for each theme
THEME_NAMES = {"sunlight": "Sunlight (high contrast)", "night": "Night (dark)"}


def touch_px(screen: QtGui.QScreen | None = None) -> int:
    """The minimum touch-target size in pixels for ``screen``: 9 mm at its physical DPI, at least 48 px."""
    if screen is None:
        app = QtWidgets.QApplication.instance()
        screen = app.primaryScreen() if isinstance(app, QtGui.QGuiApplication) else None
    dpi = screen.physicalDotsPerInch() if screen is not None else 96.0
    if not dpi or dpi != dpi or dpi <= 0:  # some platforms report 0 or NaN
        dpi = 96.0
    return max(TOUCH_FLOOR_PX, round(TOUCH_MM / 25.4 * dpi))


def check_theme(name: object) -> str:
    """``name`` if it is a theme, else the default (a hand-edited config never keeps the app from starting)."""
    return name if isinstance(name, str) and name in THEMES else DEFAULT_THEME


def check_text_size(percent: object) -> int:
    """``percent`` as one of :data:`TEXT_SIZES` (the nearest), 100 for anything that is not a number."""
    if isinstance(percent, bool) or not isinstance(percent, (int, float)) or percent != percent:
        return 100
    return min(TEXT_SIZES, key=lambda size: abs(size - percent))


def font_px(touch: int, text_size: int = 100) -> int:
    """The base font size in pixels: a third of the touch size (at least 16 px), times the text size."""
    return round(max(16, touch // 3) * check_text_size(text_size) / 100)


def stylesheet(touch: int | None = None, theme: str = DEFAULT_THEME, text_size: int = 100) -> str:
    """The QSS with the touch size, the font sizes and ``theme``'s colours filled in."""
    touch = touch or touch_px()
    font = font_px(touch, text_size)
    here = resources.files("rcon_core.app")
    text = here.joinpath("theme.qss").read_text(encoding="utf-8")
    for name, colour in THEMES[check_theme(theme)].items():
        text = text.replace(f"@C_{name}@", colour)
    bar = max(24, touch * 2 // 3)  # the scroll bar's strip: a finger finds it, it hides little
    thumb = max(6, bar // 3)  # the thumb at rest: slim and light
    wide = max(12, bar * 2 // 3)  # under the mouse or the finger
    return (
        text.replace("@BAR@", str(bar))
        .replace("@THUMB_GAP_WIDE@", str((bar - wide) // 2))
        .replace("@THUMB_GAP@", str((bar - thumb) // 2))
        .replace("@THUMB_R@", str(thumb // 2))
        .replace("@ICONS@", str(here).replace("\\", "/"))  # the theme's SVG icons, next to this file
        .replace("@SCROLLER@", str(2 * touch + 4))  # both tab scroll buttons: touch-sized
        .replace("@ARROW@", str(max(16, touch // 2)))
        .replace("@TOUCH@", str(touch))
        .replace("@HALF@", str(max(28, touch * 2 // 3)))
        .replace("@FONT@", str(font))
        .replace("@BIG@", str(font + round(4 * check_text_size(text_size) / 100)))
    )


def palette(theme: str = DEFAULT_THEME) -> QtGui.QPalette:
    """The application palette for ``theme``: what a view that paints itself reads (its background is
    ``Window``, its text ``WindowText``; ``Base``/``Text`` for fields, ``Highlight`` for the accent)."""
    c = THEMES[check_theme(theme)]
    pal = QtGui.QPalette()
    role, group = QtGui.QPalette.ColorRole, QtGui.QPalette.ColorGroup
    for r, name in ((role.Window, "BASE"), (role.WindowText, "TEXT"), (role.Base, "BASE"), (role.Text, "TEXT"),
                    (role.AlternateBase, "WINDOW"), (role.Button, "BASE"), (role.ButtonText, "TEXT"),
                    (role.Highlight, "ACCENT"), (role.HighlightedText, "ACCENT_TEXT"),
                    (role.ToolTipBase, "BASE"), (role.ToolTipText, "TEXT"), (role.PlaceholderText, "DISABLED"),
                    (role.BrightText, "ACCENT_TEXT"), (role.Link, "FOCUS"), (role.Mid, "RULE"),
                    (role.Dark, "BORDER"), (role.Light, "TAB"), (role.Midlight, "TAB"), (role.Shadow, "BORDER")):
        pal.setColor(r, QtGui.QColor(c[name]))
    for r in (role.WindowText, role.Text, role.ButtonText):
        pal.setColor(group.Disabled, r, QtGui.QColor(c["DISABLED"]))
    return pal


def colour(name: str) -> QtGui.QColor:
    """One of the current theme's colours (``"GRID"``, ``"TEXT"``...), for what the app paints itself."""
    return QtGui.QColor(THEMES[current_theme()][name])


def apply(app: QtWidgets.QApplication, theme: str | None = None, text_size: int | None = None) -> int:
    """Apply the theme to ``app`` (``theme`` and ``text_size``: None keeps what is applied, else the
    defaults); returns the touch size used. Re-applying the same choice does nothing."""
    touch = touch_px(app.primaryScreen())
    theme = check_theme(theme if theme is not None else app.property("rcon_theme"))
    text_size = check_text_size(text_size if text_size is not None else (app.property("rcon_text_size") or 100))
    key = (touch, theme, text_size)
    if app.property("rcon_theme_key") == repr(key):
        return touch
    app.setStyle("Fusion")
    app.setPalette(palette(theme))
    app.setStyleSheet(stylesheet(touch, theme, text_size))
    app.setProperty("rcon_touch_px", touch)
    app.setProperty("rcon_theme", theme)
    app.setProperty("rcon_text_size", text_size)
    app.setProperty("rcon_theme_key", repr(key))
    return touch


def current_touch_px() -> int:
    app = QtWidgets.QApplication.instance()
    value = app.property("rcon_touch_px") if app is not None else None
    return int(value) if value else touch_px()


def current_theme() -> str:
    app = QtWidgets.QApplication.instance()
    return check_theme(app.property("rcon_theme") if app is not None else None)


def current_text_size() -> int:
    app = QtWidgets.QApplication.instance()
    return check_text_size(app.property("rcon_text_size") if app is not None else 100)


def tinted_icon(path: str, colour: QtGui.QColor, size: int = 44) -> QtGui.QIcon:
    """A one-colour icon file (an SVG drawn in black) drawn in ``colour`` instead: the theme's text."""
    pixmap = QtGui.QIcon(path).pixmap(size, size)
    painter = QtGui.QPainter(pixmap)
    painter.setCompositionMode(QtGui.QPainter.CompositionMode.CompositionMode_SourceIn)
    painter.fillRect(pixmap.rect(), colour)
    painter.end()
    return QtGui.QIcon(pixmap)


def is_dark(widget: QtWidgets.QWidget) -> bool:
    """Whether ``widget`` sits on a dark background (its palette's window colour)."""
    return widget.palette().color(QtGui.QPalette.ColorRole.Window).lightness() < 128


def repolish(widget: QtWidgets.QWidget) -> None:
    """Re-evaluate a widget's style after one of its dynamic properties changed."""
    style = widget.style()
    style.unpolish(widget)
    style.polish(widget)
    widget.update()
