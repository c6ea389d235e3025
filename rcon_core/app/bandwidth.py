"""The connection bar's bandwidth readout: bytes per second in, per robot and by topic.

A fixed-width button on the bar shows the total of every robot's link (``↓ 64 kB/s``); a tap opens the
details: each robot's total and its topics, biggest first, with messages per second (refreshed while open;
the same text is the tooltip). The counts come from each client's :class:`~rcon_core.bridge.traffic.Traffic`
(the read loop counts the frames as they come off the socket); the rates are taken here, on the GUI thread,
at most every :data:`REFRESH_S`.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

from qtpy import QtCore, QtGui, QtWidgets

from rcon_core.bridge.traffic import TrafficRates, rate_text

__all__ = ["BandwidthButton", "REFRESH_S", "details_text"]

#: seconds between two readings of the counters
REFRESH_S = 0.5
#: topics listed per robot in the details
TOP_TOPICS = 12


def details_text(rows: list[tuple[str, TrafficRates]]) -> str:
    """The details: per robot (``name``: "" for a one-robot window) its total, then its topics."""
    lines = ["Bytes per second in, by topic:"]
    for name, rates in rows:
        lines.append(f"{name or 'robot'}: {rate_text(rates.total)} in all" if name or len(rows) > 1
                     else f"in all: {rate_text(rates.total)}")
        if not rates.topics:
            lines.append("  nothing received")
        for topic, nbytes, msgs in rates.topics[:TOP_TOPICS]:
            lines.append(f"  {rate_text(nbytes):>10}  {msgs:5.1f}/s  {topic}")
        if len(rates.topics) > TOP_TOPICS:
            rest = sum(r[1] for r in rates.topics[TOP_TOPICS:])
            lines.append(f"  {rate_text(rest):>10}  in {len(rates.topics) - TOP_TOPICS} more topics")
    return "\n".join(lines)


class BandwidthButton(QtWidgets.QToolButton):
    """``↓ total``; tap: the details. ``sources()`` gives ``[(robot name, link)]`` (a link has ``.client``)."""

    def __init__(self, link: Any, parent: QtWidgets.QWidget | None = None,
                 clock: Callable[[], float] = time.monotonic) -> None:
        super().__init__(parent)
        self.setObjectName("bandwidth")
        self.setAccessibleName("Bandwidth")
        self.setAutoRaise(True)
        #: the robots' links, named: the window's fleet sets it; alone, the bar's own link
        self.sources: Callable[[], list[tuple[str, Any]]] = lambda: [("", link)]
        self._clock = clock
        self._rates: dict[str, TrafficRates] = {}
        self._next = 0.0
        self.total = 0.0
        self.details = ""
        self.popup: QtWidgets.QLabel | None = None
        self.reading = "↓ —"
        self.setText(self.reading)
        # the row's height, never more, and no width the bar must keep: the readout never makes the bar (and
        # so the window or the canvas) bigger; where the bar has no room for it, it shrinks to the arrow (or
        # nothing), its reading still in the tooltip and the details a tap away
        self.setSizePolicy(QtWidgets.QSizePolicy.Policy.Preferred, QtWidgets.QSizePolicy.Policy.Ignored)
        self._full_width = 0
        #: the most its bar gives it (ConnectionBar._share_room: the URL field and the latency come first)
        self._room = 16_777_215
        self.clicked.connect(self.show_details)

    def full_width(self) -> int:
        """Its width showing its widest reading (0 before it is measured, once shown)."""
        return self._full_width

    def set_room(self, px: int) -> None:
        """The widest its bar lets it be (it shrinks to the arrow, or nothing, below its reading's width)."""
        if px != self._room:
            self._room = px
            if self._full_width:
                self.setMaximumWidth(min(self._full_width, px))

    def showEvent(self, event: QtGui.QShowEvent) -> None:  # noqa: N802 - Qt's name
        super().showEvent(event)
        self.ensurePolished()
        self._measure()

    def _measure(self) -> None:
        """Wide enough for the widest reading, measured as styled (the theme's font and padding), so no
        reading ever changes what the bar needs; measured again when the text size or the theme changes."""
        self._full_width = 0
        self.setMaximumWidth(16_777_215)
        shown = self.text()
        widths = []
        for sample in ("↓ 888 kB/s", "↓ 88.8 MB/s"):
            self.setText(sample)
            widths.append(super().sizeHint().width())
        self.setText(shown)
        self._full_width = max(widths)
        self.setMaximumWidth(min(self._full_width, self._room))
        self.updateGeometry()
        self._show_reading()

    def event(self, e: QtCore.QEvent) -> bool:
        handled = super().event(e)
        kind = e.type()
        if kind in (QtCore.QEvent.Type.Polish, QtCore.QEvent.Type.StyleChange) and self.minimumWidth():
            self.setMinimumWidth(0)  # a theme's touch-size min-width would widen the bar: squeezed instead
        if kind in (QtCore.QEvent.Type.StyleChange, QtCore.QEvent.Type.FontChange) and self._full_width:
            self._measure()  # another text size or theme: the readings' widths changed
        return handled

    def sizeHint(self) -> QtCore.QSize:  # noqa: N802 - Qt's name
        hint = super().sizeHint()
        return QtCore.QSize(self._full_width or hint.width(), hint.height())

    def minimumSizeHint(self) -> QtCore.QSize:  # noqa: N802 - Qt's name
        return QtCore.QSize(0, super().minimumSizeHint().height())

    def resizeEvent(self, event: QtGui.QResizeEvent) -> None:  # noqa: N802 - Qt's name
        super().resizeEvent(event)
        self._show_reading()

    def _show_reading(self) -> None:
        """The reading when the button has its width, the arrow alone when squeezed, nothing when tiny."""
        full = self._full_width
        if not full or self.width() >= full:
            text = self.reading
        elif self.width() >= 28:
            text = "↓"
        else:
            text = ""
        if text != self.text():
            self.setText(text)

    def poll(self, _now: float = 0.0) -> None:
        """Called every frame by the connection bar; reads the counters every :data:`REFRESH_S`."""
        now = self._clock()
        if now < self._next:
            return
        self._next = now + REFRESH_S
        rows = []
        seen = set()
        for name, link in self.sources():
            rates = self._rates.get(name)
            if rates is None:
                rates = self._rates[name] = TrafficRates(clock=self._clock)
            client = getattr(link, "client", None)
            rates.update(getattr(client, "traffic", None))
            rows.append((name, rates))
            seen.add(name)
        for gone in set(self._rates) - seen:
            del self._rates[gone]
        self.total = sum(r.total for _n, r in rows)
        connected = any(getattr(link, "client", None) is not None for _n, link in self.sources())
        self.reading = f"↓ {rate_text(self.total)}" if connected else "↓ —"
        self._show_reading()
        self.details = details_text(rows)
        self.setToolTip(self.details)
        if self.popup is not None and self.popup.isVisible():
            self.popup.setText(self.details)
            self.popup.resize(self.popup.sizeHint())  # adjustSize would cap it at 2/3 of the screen

    def show_details(self) -> None:
        """The details under the button (a popup: a tap anywhere else closes it)."""
        if self.popup is None:
            self.popup = QtWidgets.QLabel(self, QtCore.Qt.WindowType.Popup)
            self.popup.setObjectName("bandwidthDetails")
            self.popup.setTextFormat(QtCore.Qt.TextFormat.PlainText)
            self.popup.setMargin(10)
            font = QtGui.QFontDatabase.systemFont(QtGui.QFontDatabase.SystemFont.FixedFont)
            self.popup.setFont(font)
        self._next = 0.0
        self.poll()
        self.popup.setText(self.details)
        self.popup.ensurePolished()
        self.popup.resize(self.popup.sizeHint())  # adjustSize would cap it at 2/3 of the screen
        # under the button, kept on the window's screen: its right edge at the window's right at most
        at = self.mapToGlobal(QtCore.QPoint(0, self.height()))
        right = self.window().mapToGlobal(QtCore.QPoint(self.window().width(), 0)).x()
        self.popup.move(min(at.x(), right - self.popup.width()), at.y())
        self.popup.show()
        self.popup.resize(self.popup.sizeHint())  # adjustSize would cap it at 2/3 of the screen
