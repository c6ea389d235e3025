"""The view of the accelerometer, gyroscope and magnetometer widgets: three signed bars and the magnitude.

With the ``device`` source it attaches the Qt Sensors backend (lazily imported); on a device without the
sensor it shows that clearly instead of values.
"""

from __future__ import annotations

from typing import Any

from qtpy import QtCore, QtGui, QtWidgets

from .motion_sensors import SensorValue

#: full-scale of the bars, per sensor (SI units)
FULL_SCALE = {"accelerometer": 20.0, "gyroscope": 3.0, "magnetometer": 100e-6}
COLOURS = [QtGui.QColor(230, 80, 70), QtGui.QColor(80, 190, 100), QtGui.QColor(70, 140, 235)]


def fmt(v: float, sensor: str) -> str:
    if sensor == "magnetometer":
        return f"{v * 1e6:+.1f} µT"
    return f"{v:+.2f}"


class MotionSensorView(QtWidgets.QWidget):
    def __init__(self, model: Any, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.model = model
        self._value: SensorValue | None = model.state.value if isinstance(model.state.value, SensorValue) else None
        self._state: Any = None
        self.backend = None
        if getattr(model.settings, "source", "") == "device" and model.binding.role.value == "publish":
            from .qt_sensors import attach

            self.backend = attach(model, self)
        self.setMinimumSize(160, 110)

    def refresh(self, state: Any) -> None:
        self._state = state
        if isinstance(state.value, SensorValue):
            self._value = state.value
        self.update()

    def paintEvent(self, _e: QtGui.QPaintEvent) -> None:  # noqa: N802
        p = QtGui.QPainter(self)
        p.setRenderHint(QtGui.QPainter.RenderHint.Antialiasing, True)
        pal = self.palette()
        p.fillRect(self.rect(), pal.color(QtGui.QPalette.ColorRole.Window))
        text = pal.color(QtGui.QPalette.ColorRole.WindowText)
        v = self._value
        sensor = getattr(self.model, "sensor", "sensor")
        unit = getattr(self.model, "unit", "")
        w, h = self.width(), self.height()
        p.setPen(text)
        head = p.font()
        head.setBold(True)
        p.setFont(head)
        p.drawText(QtCore.QRectF(8, 4, w - 16, 18), QtCore.Qt.AlignmentFlag.AlignLeft,
                   f"{sensor.capitalize()}" + (f"  ({'µT' if sensor == 'magnetometer' else unit})"))
        body = p.font()
        body.setBold(False)
        p.setFont(body)
        if v is None or v.vector is None:
            msg = v.status if v is not None and v.status else "no reading yet"
            p.setPen(QtGui.QColor(200, 120, 40) if v is not None and not v.available else text)
            p.drawText(QtCore.QRectF(8, 26, w - 16, h - 30),
                       QtCore.Qt.AlignmentFlag.AlignCenter | QtCore.Qt.TextFlag.TextWordWrap, msg)
            p.end()
            return
        full = FULL_SCALE.get(sensor, 1.0)
        top, row = 28.0, max(16.0, (h - 28 - 24) / 3)
        label_w, value_w = 16.0, 78.0
        bar_x, bar_w = 8 + label_w, max(20.0, w - 16 - label_w - value_w)
        mid = bar_x + bar_w / 2
        for i, (axis, val) in enumerate(zip("xyz", v.vector, strict=True)):
            y = top + i * row
            p.setPen(text)
            p.drawText(QtCore.QRectF(8, y, label_w, row - 4), QtCore.Qt.AlignmentFlag.AlignVCenter, axis)
            p.fillRect(QtCore.QRectF(bar_x, y + 3, bar_w, row - 10), QtGui.QColor(128, 128, 128, 40))
            frac = max(-1.0, min(1.0, val / full)) if val == val else 0.0
            p.fillRect(QtCore.QRectF(min(mid, mid + frac * bar_w / 2), y + 3, abs(frac) * bar_w / 2, row - 10),
                       COLOURS[i])
            p.setPen(QtGui.QPen(text, 1))
            p.drawLine(QtCore.QPointF(mid, y + 1), QtCore.QPointF(mid, y + row - 5))
            p.drawText(QtCore.QRectF(bar_x + bar_w + 4, y, value_w - 4, row - 4),
                       QtCore.Qt.AlignmentFlag.AlignRight | QtCore.Qt.AlignmentFlag.AlignVCenter, fmt(val, sensor))
        mag = v.magnitude or 0.0
        status = f"|v| {fmt(mag, sensor).lstrip('+')}  ·  {v.status}"
        if v.sent:
            status += f"  ·  {v.sent} sent"
        p.setPen(text)
        p.drawText(QtCore.QRectF(8, h - 20, w - 16, 18), QtCore.Qt.AlignmentFlag.AlignLeft, status)
        p.end()
