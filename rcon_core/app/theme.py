"""Touch sizing and the high-contrast stylesheet (``theme.qss``, shipped as package data)."""

from __future__ import annotations

from importlib import resources

from qtpy import QtGui, QtWidgets

#: the smallest comfortable touch target, in millimetres, and the pixel floor below which we never go
TOUCH_MM = 9.0
TOUCH_FLOOR_PX = 48


def touch_px(screen: QtGui.QScreen | None = None) -> int:
    """The minimum touch-target size in pixels for ``screen``: 9 mm at its physical DPI, at least 48 px."""
    if screen is None:
        app = QtWidgets.QApplication.instance()
        screen = app.primaryScreen() if isinstance(app, QtGui.QGuiApplication) else None
    dpi = screen.physicalDotsPerInch() if screen is not None else 96.0
    if not dpi or dpi != dpi or dpi <= 0:  # some platforms report 0 or NaN
        dpi = 96.0
    return max(TOUCH_FLOOR_PX, round(TOUCH_MM / 25.4 * dpi))


def stylesheet(touch: int | None = None) -> str:
    """The theme's QSS with the touch size and font sizes filled in."""
    touch = touch or touch_px()
    font = max(16, touch // 3)
    here = resources.files("rcon_core.app")
    text = here.joinpath("theme.qss").read_text(encoding="utf-8")
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
        .replace("@BIG@", str(font + 4))
    )


def apply(app: QtWidgets.QApplication) -> int:
    """Apply the theme to ``app``; returns the touch size used."""
    touch = touch_px(app.primaryScreen())
    app.setStyle("Fusion")
    app.setStyleSheet(stylesheet(touch))
    app.setProperty("rcon_touch_px", touch)
    return touch


def current_touch_px() -> int:
    app = QtWidgets.QApplication.instance()
    value = app.property("rcon_touch_px") if app is not None else None
    return int(value) if value else touch_px()


def repolish(widget: QtWidgets.QWidget) -> None:
    """Re-evaluate a widget's style after one of its dynamic properties changed."""
    style = widget.style()
    style.unpolish(widget)
    style.polish(widget)
    widget.update()
