"""Text View's Qt view: level (log topics only: a String has no levels) and text filters on top, the
coloured history, and (publish role) an input line underneath.

Decision: a pass costs the same whatever arrives
    One ``QPlainTextEdit.appendHtml`` per message froze the window for minutes on a 5 MB String and for
    seconds at 10,000 messages a second. Now each refresh inserts the new lines in one edit block, through a
    text cursor (no HTML to parse), at most ``PASS_LINES`` of them and for at most ``PASS_BUDGET`` seconds;
    lines still waiting are painted by the
    next passes, a frame apart (``_more``), and lines that could no longer be on screen (beyond the
    document's cap) are skipped. Each line is already short (the model keeps a display text of at most
    ``DISPLAY_CHARS`` characters and ``DISPLAY_ROWS`` rows); a shortened line ends with a note, and its
    whole text is one right-click away ("Show the whole message…", "Copy the whole message"). The document
    keeps at most ``min(max_lines, DOC_LINES)`` blocks, one per line. After a filter change the newest lines
    are painted first and the older ones are put above them in the following passes.
"""

from __future__ import annotations

import datetime
import time
from typing import Any

from qtpy import QtCore, QtGui, QtWidgets

from rcon_core.plugins import Role

from .textview import LEVELS, Line
from .view_common import BAD, LEVEL_COLOURS, Caption, vbox

#: lines inserted into the document per pass at most, and the time that may take (the rest in the next
#: passes, a frame apart)
PASS_LINES = 200
PASS_BUDGET = 0.008
#: blocks the document keeps at most (the model may keep more lines: the filter looks at all of them)
DOC_LINES = 10_000
#: characters of a whole message the "Show the whole message" dialog shows (Copy takes all of it)
SHOW_CHARS = 200_000
#: the gap between the passes that paint lines still waiting (ms): about one frame
MORE_AFTER_MS = 16
_LINE_SEPARATOR = "\u2028"  # a line break inside one block: one block per message


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
        self.doc_lines = min(max(10, int(s.max_lines)), DOC_LINES)
        self.history.setMaximumBlockCount(self.doc_lines)
        self.history.setLineWrapMode(QtWidgets.QPlainTextEdit.LineWrapMode.WidgetWidth)
        self.history.setUndoRedoEnabled(False)
        mono = QtGui.QFontDatabase.systemFont(QtGui.QFontDatabase.SystemFont.FixedFont)
        self.history.setFont(mono)
        self.history.setStyleSheet("font-size: 13px;")
        self.history.setContextMenuPolicy(QtCore.Qt.ContextMenuPolicy.CustomContextMenu)
        self.history.customContextMenuRequested.connect(self._context_menu)
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
        self._history: Any = None  # the latest History seen
        self._version: Any = None
        self._next = 0  # the next visible line (ring index) to append
        self._top = 0  # the oldest ring index painted; older ones down to _floor are put above later
        self._floor = 0
        self._formats: dict[tuple[str, bool], QtGui.QTextCharFormat] = {}
        self._more = QtCore.QTimer(self)
        self._more.setSingleShot(True)
        self._more.setInterval(MORE_AFTER_MS)
        self._more.timeout.connect(self._paint_pending)
        #: lines inserted into the document so far (for tests and benchmarks)
        self.painted = 0
        self.level.currentTextChanged.connect(lambda lv: model.set_filter(min_level=lv))
        self.filter.textChanged.connect(lambda t: model.set_filter(text=t))

    def _send(self) -> None:
        if self.input is not None and self.model.send(self.input.text()):
            self.input.clear()

    # -- one line --------------------------------------------------------------------------------------
    def line_text(self, line: Line) -> str:
        """The text of one line on screen (one block; its rows separated by U+2028)."""
        s = self.model.settings
        parts = []
        if getattr(line, "replayed", False):
            parts.append("↺")  # logged before this console subscribed (a node's latched last line)
        if s.show_time and line.stamp:
            try:
                parts.append(datetime.datetime.fromtimestamp(line.stamp).strftime("%H:%M:%S"))
            except (OverflowError, OSError, ValueError):
                parts.append("--:--:--")
        if self.model.is_log:
            parts.append(f"[{line.level.upper():5}]")
        if s.show_node and line.node:
            parts.append(f"[{line.node}]")
        parts.append(line.text)
        text = " ".join(parts)
        if line.length is not None:
            text += f" … [{line.length:,} characters: right-click to see them all]"
        return text.replace("\n", _LINE_SEPARATOR)

    def _format(self, line: Line) -> QtGui.QTextCharFormat:
        key = (line.level, bool(getattr(line, "replayed", False)))
        fmt = self._formats.get(key)
        if fmt is None:
            fmt = QtGui.QTextCharFormat()
            fmt.setForeground(QtGui.QColor(LEVEL_COLOURS.get(line.level, "#000000")))
            if line.level in ("error", "fatal"):
                fmt.setFontWeight(QtGui.QFont.Weight.Bold)
            fmt.setFontItalic(key[1])
            self._formats[key] = fmt
        return fmt

    # -- painting --------------------------------------------------------------------------------------
    def refresh(self, state: Any) -> None:
        if state.error:
            self.error.show_text(state.error, BAD)
            self.error.show()
        else:
            self.error.hide()
        h = state.value
        if h is None:
            return
        self._history = h
        if h.filter_version != self._version:  # another filter, or lines moved: paint it all again
            self._version = h.filter_version
            self.history.clear()
            self._floor = max(h.start, h.end - h.ring.capacity, h.end - self.doc_lines)
            self._next = self._top = max(self._floor, h.end - PASS_LINES)
        self._paint_pending()

    def _paint_pending(self) -> None:
        """Append the newest lines not painted yet, then put older ones above (after a filter change),
        ``PASS_LINES`` in all per pass; what is left waits for the next pass."""
        h = self._history
        if h is None:
            return
        if h.end - self._next > self.doc_lines:  # more arrived than the document can hold: the newest
            self._next = h.end - self.doc_lines
            self._floor = self._top = self._next
        bar = self.history.verticalScrollBar()
        at_bottom = bar.value() >= bar.maximum() - 4
        budget = PASS_LINES
        deadline = time.perf_counter() + PASS_BUDGET
        first = max(self._next, h.end - h.ring.capacity)
        last = min(h.end, first + budget)
        if last > first:
            done = self._append(h, first, last, deadline)
            budget -= done - first
            last = done
        self._next = max(self._next, last)
        oldest = max(self._floor, h.end - h.ring.capacity)
        if budget > 0 and self._top > oldest:
            lo = max(oldest, self._top - budget)
            self._prepend([x for x in map(h.ring.get, range(lo, self._top)) if x is not None])
            self._top = lo
        if at_bottom:
            bar.setValue(bar.maximum())
        if (self._next < h.end or self._top > oldest) and not self._more.isActive():
            self._more.start()

    def _append(self, h: Any, first: int, last: int, deadline: float) -> int:
        """Append the visible lines ``first .. last - 1`` of ``h`` (those still there), until ``deadline``;
        returns the index after the last one appended."""
        doc = self.history.document()
        cursor = QtGui.QTextCursor(doc)
        cursor.beginEditBlock()
        cursor.movePosition(QtGui.QTextCursor.MoveOperation.End)
        empty = doc.isEmpty()
        k = first
        while k < last:
            line = h.ring.get(k)
            k += 1
            if line is None:  # fell off the history meanwhile
                continue
            if not empty:
                cursor.insertBlock()
            empty = False
            cursor.insertText(self.line_text(line), self._format(line))
            cursor.block().setUserState(line.n & 0x7FFFFFFF)
            self.painted += 1
            if k % 16 == 0 and time.perf_counter() > deadline:
                break
        cursor.endEditBlock()
        return k

    def _prepend(self, lines: list[Line]) -> None:
        if not lines:
            return
        doc = self.history.document()
        room = self.doc_lines - (0 if doc.isEmpty() else doc.blockCount())
        lines = lines[-room:] if room > 0 else []
        if not lines:
            self._floor = self._top
            return
        cursor = QtGui.QTextCursor(doc)
        cursor.beginEditBlock()
        cursor.movePosition(QtGui.QTextCursor.MoveOperation.Start)
        empty = doc.isEmpty()
        top = doc.firstBlock().userState()  # the first line's number: a split leaves it on the first half
        for i, line in enumerate(lines):
            cursor.insertText(self.line_text(line), self._format(line))
            cursor.block().setUserState(line.n & 0x7FFFFFFF)
            if i < len(lines) - 1 or not empty:
                cursor.insertBlock()
        if not empty:
            cursor.block().setUserState(top)  # the line that was first, now after the new ones
        cursor.endEditBlock()
        self.painted += len(lines)

    # -- the whole text on demand ---------------------------------------------------------------------
    def line_at(self, pos: QtCore.QPoint) -> Line | None:
        """The line shown at ``pos`` (viewport coordinates), if it is still in the history."""
        block = self.history.cursorForPosition(pos).block()
        n = block.userState()
        h = self._history
        if n < 0 or h is None:
            return None
        for x in reversed(h.since(self._floor)):
            if x.n & 0x7FFFFFFF == n:
                return x
        return None

    def _context_menu(self, pos: QtCore.QPoint) -> None:
        menu = self.history.createStandardContextMenu()
        line = self.line_at(pos)
        if line is not None and line.shortened:
            menu.addSeparator()
            menu.addAction("Show the whole message…", lambda: self.show_whole(line))
            menu.addAction("Copy the whole message", lambda: self.copy_whole(line))
        menu.exec(self.history.viewport().mapToGlobal(pos))
        menu.deleteLater()

    def copy_whole(self, line: Line) -> bool:
        whole = self.model.full_text(line)
        if whole is None:
            return False
        QtWidgets.QApplication.clipboard().setText(whole)
        return True

    def show_whole(self, line: Line) -> QtWidgets.QDialog:
        """A dialog with the whole text of ``line`` (its first ``SHOW_CHARS`` characters; Copy takes all)."""
        whole = self.model.full_text(line)
        dialog = QtWidgets.QDialog(self)
        dialog.setWindowTitle("The whole message")
        dialog.setAttribute(QtCore.Qt.WidgetAttribute.WA_DeleteOnClose)
        lay = QtWidgets.QVBoxLayout(dialog)
        if whole is None:
            note = QtWidgets.QLabel("The whole text of this message is no longer kept (only the newest long "
                                    "messages are).")
            note.setWordWrap(True)
            lay.addWidget(note)
        else:
            shown = whole[:SHOW_CHARS]
            if len(whole) > SHOW_CHARS:
                lay.addWidget(QtWidgets.QLabel(f"The first {SHOW_CHARS:,} of {len(whole):,} characters; "
                                               "Copy takes all of them."))
            text = QtWidgets.QPlainTextEdit()
            text.setReadOnly(True)
            text.setUndoRedoEnabled(False)
            text.setLineWrapMode(QtWidgets.QPlainTextEdit.LineWrapMode.NoWrap)
            text.setFont(self.history.font())
            # pieces of at most DISPLAY_CHARS characters per row: Qt never lays out a megabyte-long line
            text.setPlainText("\n".join(_pieces(shown, 1000)))
            lay.addWidget(text, 1)
            copy = QtWidgets.QPushButton("Copy")
            copy.clicked.connect(lambda: QtWidgets.QApplication.clipboard().setText(whole))
            lay.addWidget(copy)
        close = QtWidgets.QPushButton("Close")
        close.clicked.connect(dialog.close)
        lay.addWidget(close)
        dialog.resize(640, 420)
        dialog.show()
        return dialog


def _pieces(text: str, width: int) -> list[str]:
    """``text``'s rows, each cut into pieces of at most ``width`` characters."""
    out: list[str] = []
    for row in text.splitlines() or [""]:
        out.extend(row[i:i + width] for i in range(0, max(len(row), 1), width))
    return out
