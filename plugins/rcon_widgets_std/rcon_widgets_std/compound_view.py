"""Compound's Qt view: each child's own view under a small title (its field), in a grid; a Publish or
Call button and the result underneath. Child views are built from their specs, like the app builds any
widget view, and refreshed when their model's ``seq`` moves: a child's change wakes the front end through
the compound (its ``seq`` moves too), so the host's ``refresh`` reaches them within the frame; the view
keeps no clock of its own.

A child is never painted below its minimum size: the grid sits in a scroll area, which never makes it
smaller than its minimum (each child's own), so a frame smaller than the children scrolls (the button
stays in view).
``sizeHint()`` is the size that shows every child without scrolling: what the app should give a new
Compound (see :meth:`CompoundSettings.preferred_size` for the same without Qt)."""

from __future__ import annotations

from typing import Any

from qtpy import QtCore, QtWidgets

from rcon_core.plugins import CallPhase, Role, WidgetView

from .view_common import BAD, MUTED, OK, Caption, vbox


class CompoundView(QtWidgets.QWidget):
    def __init__(self, model: Any, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.model = model
        layout = vbox(self)
        self.content = QtWidgets.QWidget()
        self.content.setObjectName("compoundChildren")
        self.grid = QtWidgets.QGridLayout(self.content)
        self.grid.setContentsMargins(0, 0, 0, 0)
        self.grid.setSpacing(6)
        self.scroll_area = QtWidgets.QScrollArea()
        self.scroll_area.setWidgetResizable(True)
        self.scroll_area.setFrameShape(QtWidgets.QFrame.Shape.NoFrame)
        self.scroll_area.setHorizontalScrollBarPolicy(QtCore.Qt.ScrollBarPolicy.ScrollBarAsNeeded)
        self.scroll_area.setWidget(self.content)
        layout.addWidget(self.scroll_area, 1)
        role = model.binding.role
        self.button = None
        if role is not Role.SERVE:
            default = "Publish" if role is Role.PUBLISH else "Call"
            self.button = QtWidgets.QPushButton(model.settings.send_text or default)
            self.button.setProperty("primary", True)
            self.button.clicked.connect(model.send)
            layout.addWidget(self.button)
        self.status = Caption("")
        self.status.setAlignment(QtCore.Qt.AlignmentFlag.AlignCenter)
        layout.addWidget(self.status)
        self.child_views: list[tuple[Any, QtWidgets.QWidget]] = []
        self.child_boxes: list[QtWidgets.QGroupBox] = []
        self._version = -1
        self._painted: dict[int, int] = {}
        self._build()

    def _build(self) -> None:
        if self._version == self.model.children_version:
            return
        self._version = self.model.children_version
        for box in self.child_boxes:
            self.grid.removeWidget(box)
            box.deleteLater()
        self.child_views = []
        self.child_boxes = []
        self._painted = {}
        cols = max(1, int(self.model.settings.columns))
        for c in range(cols):
            self.grid.setColumnStretch(c, 1)
        for i, child in enumerate(self.model.children):
            box = QtWidgets.QGroupBox(child.title)
            inner = vbox(box, margins=2, spacing=0)
            try:
                view = child.spec.load_view()(child.model)
            except Exception as exc:  # a child package's broken view must not break the compound
                view = QtWidgets.QLabel(f"{child.cfg.kind}: {exc}")
            inner.addWidget(view)
            self.grid.addWidget(box, i // cols, i % cols)
            self.child_boxes.append(box)
            self.child_views.append((child, view))

        rows = -(-len(self.model.children) // cols)
        for r in range(max(self.grid.rowCount(), rows + 1)):
            self.grid.setRowStretch(r, 1 if r == rows else 0)  # spare height below the children, not in them
        self.content.adjustSize()
        self.updateGeometry()

    def _chrome(self) -> QtCore.QSize:
        """What the view needs besides the children: margins, the button and the status line."""
        layout = self.layout()
        assert layout is not None  # vbox(self) in __init__
        m = layout.contentsMargins()
        h = m.top() + m.bottom()
        for w in (self.button, self.status):
            if w is not None:
                h += w.sizeHint().height() + layout.spacing()
        return QtCore.QSize(m.left() + m.right(), h)

    def sizeHint(self) -> QtCore.QSize:  # noqa: N802 - Qt override
        """Every child at its preferred size, the button and the status line: nothing scrolls."""
        chrome, content = self._chrome(), self.content.sizeHint()
        bar = self.scroll_area.verticalScrollBar().sizeHint().width()
        return QtCore.QSize(max(content.width() + bar, 160) + chrome.width(), content.height() + chrome.height())

    def minimumSizeHint(self) -> QtCore.QSize:  # noqa: N802 - Qt override
        """The smallest child and the button: anything more scrolls."""
        chrome = self._chrome()
        low = [b.minimumSizeHint() for b in self.child_boxes] or [QtCore.QSize(120, 40)]
        w = max(q.width() for q in low) + self.scroll_area.verticalScrollBar().sizeHint().width()
        return QtCore.QSize(w + chrome.width(), min(q.height() for q in low) + chrome.height())

    def _refresh_children(self) -> None:
        for child, view in self.child_views:
            st = child.model.state
            if self._painted.get(child.index) == st.seq:
                continue
            self._painted[child.index] = st.seq
            if isinstance(view, WidgetView):
                view.refresh(st)
            else:
                view.update()

    def refresh(self, state: Any) -> None:
        self._build()
        self._refresh_children()
        v = state.value
        st = getattr(v, "status", None)
        if state.error:  # one line, elided (nothing under the finger moves); the child shows its own problem
            self.status.show_text(state.error, BAD)
        elif st is None:
            problems = self.model.problems()
            self.status.show_text("; ".join(problems) if problems else "", BAD if problems else MUTED)
        elif st.busy:
            self.status.show_text(f"calling {st.target}…", MUTED)
        elif st.phase is CallPhase.FAILED:
            self.status.show_text(f"✗ {st.text}", BAD)
        else:
            self.status.show_text(f"✓ {st.text}", OK)
