"""Text View's Qt view: level (log topics only: a String has no levels) and text filters on top, the
coloured history, and (publish role) an input line underneath. Lines are appended incrementally; the
widget keeps at most ``max_lines`` blocks."""

from __future__ import annotations

import datetime
import html
from typing import Any

from qtpy import QtGui, QtWidgets

from rcon_core.plugins import Role

from .textview import LEVELS
from .view_common import BAD, LEVEL_COLOURS, Caption, vbox


class TextViewView(QtWidgets.QWidget):
    def __init__(self, model: Any, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.model = model
        s = model.settings
        layout = vbox(self)
        bar = QtWidgets.QHBoxLayout()
        self.level = QtWidgets.QComboBox()
        self.level.addItems(list(LEVELS))
        self.level.setCurrentText(s.min_level)
        self.level.setToolTip("lowest level shown")
        self.filter = QtWidgets.QLineEdit(s.filter_text)
        self.filter.setPlaceholderText("filter")
        self.filter.setClearButtonEnabled(True)
        bar.addWidget(self.level)
        bar.addWidget(self.filter, 1)
        self.level.setVisible(model.is_log)  # a String topic has no levels to pick from
        layout.addLayout(bar)
        self.history = QtWidgets.QPlainTextEdit()
        self.history.setReadOnly(True)
        self.history.setMaximumBlockCount(max(10, int(s.max_lines)))
        self.history.setLineWrapMode(QtWidgets.QPlainTextEdit.LineWrapMode.WidgetWidth)
        mono = QtGui.QFontDatabase.systemFont(QtGui.QFontDatabase.SystemFont.FixedFont)
        self.history.setFont(mono)
        self.history.setStyleSheet("font-size: 13px;")
        layout.addWidget(self.history, 1)
        self.input = None
        if model.binding.role is Role.PUBLISH:
            self.input = QtWidgets.QLineEdit()
            self.input.setPlaceholderText("type a message, Enter sends")
            self.input.returnPressed.connect(self._send)
            layout.addWidget(self.input)
        self.error = Caption("")
        self.error.hide()
        layout.addWidget(self.error)
        self._painted_n = 0
        self._version = None
        self.level.currentTextChanged.connect(lambda lv: model.set_filter(min_level=lv))
        self.filter.textChanged.connect(lambda t: model.set_filter(text=t))

    def _send(self) -> None:
        if self.input is not None and self.model.send(self.input.text()):
            self.input.clear()

    def _html(self, line: Any) -> str:
        s = self.model.settings
        parts = []
        if s.show_time and line.stamp:
            parts.append(datetime.datetime.fromtimestamp(line.stamp).strftime("%H:%M:%S"))
        if self.model.is_log:
            parts.append(f"[{line.level.upper():5}]")
        if s.show_node and line.node:
            parts.append(f"[{line.node}]")
        parts.append(line.text)
        colour = LEVEL_COLOURS.get(line.level, "#000000")
        weight = "font-weight:bold;" if line.level in ("error", "fatal") else ""
        if getattr(line, "replayed", False):
            # logged before this console subscribed (a node's latched last line): marked, in italics
            parts.insert(0, "↺")
            weight += "font-style:italic;"
        text = html.escape(" ".join(parts)).replace("  ", " &nbsp;")
        return f'<span style="color:{colour};{weight}">{text}</span>'

    def refresh(self, state: Any) -> None:
        if state.error:
            self.error.show_text(state.error, BAD)
            self.error.show()
        else:
            self.error.hide()
        h = state.value
        if h is None:
            return
        bar = self.history.verticalScrollBar()
        at_bottom = bar.value() >= bar.maximum() - 4
        if h.filter_version != self._version:
            self._version = h.filter_version
            self.history.clear()
            new = h.lines
        else:
            new = []
            for x in reversed(h.lines):  # only the lines not painted yet, without walking them all
                if x.n <= self._painted_n:
                    break
                new.append(x)
            new.reverse()
        for line in new:
            self.history.appendHtml(self._html(line))
        if h.lines:
            self._painted_n = h.lines[-1].n
        if at_bottom:
            bar.setValue(bar.maximum())
