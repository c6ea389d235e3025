"""Action's Qt view: the goal form (generated from the goal type), Send and Cancel, the goal's status in
words and colour, a progress bar when a feedback field looks like progress, the feedback's numbers, the
last feedback and the result."""

from __future__ import annotations

from typing import Any

from qtpy import QtCore, QtWidgets

from rcon_core.app.settings_form import form_label, tune_form
from rcon_core.plugins import GoalPhase

from .common import format_value
from .view_common import BAD, MUTED, OK, STALE, Caption, vbox

#: phase -> (words, colour)
PHASE_TEXT = {
    "idle": ("Ready", MUTED),
    "active": ("▶ Running", "#00558f"),
    "canceling": ("⊘ Cancelling…", STALE),
    "succeeded": ("✓ Succeeded", OK),
    "canceled": ("⊘ Canceled", STALE),
    "aborted": ("✗ Aborted", BAD),
    "failed": ("✗ Failed", BAD),
    "unknown": ("? Unknown", STALE),
}


class ActionView(QtWidgets.QWidget):
    def __init__(self, model: Any, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.model = model
        layout = vbox(self)
        self.form_box = QtWidgets.QWidget()
        self.form = tune_form(QtWidgets.QFormLayout(self.form_box))
        self.form.setContentsMargins(0, 0, 0, 0)
        scroll = QtWidgets.QScrollArea()
        scroll.setObjectName("goalForm")
        scroll.setWidgetResizable(True)
        scroll.setFrameShape(QtWidgets.QFrame.Shape.NoFrame)
        scroll.setWidget(self.form_box)
        layout.addWidget(scroll, 1)
        self.editors: dict[str, QtWidgets.QWidget] = {}
        self._fields: list[Any] = []
        buttons = QtWidgets.QHBoxLayout()
        self.send_button = QtWidgets.QPushButton("Send goal")
        self.send_button.setObjectName("actionSend")
        self.send_button.setProperty("primary", True)
        self.send_button.clicked.connect(self.send)
        self.cancel_button = QtWidgets.QPushButton("Cancel")
        self.cancel_button.setObjectName("actionCancel")
        self.cancel_button.clicked.connect(model.cancel)
        buttons.addWidget(self.send_button, 1)
        buttons.addWidget(self.cancel_button, 1)
        layout.addLayout(buttons)
        self.status = Caption("")
        self.status.setObjectName("actionStatus")
        font = self.status.font()
        font.setBold(True)
        font.setPointSizeF(font.pointSizeF() / 0.85)
        self.status.setFont(font)
        layout.addWidget(self.status)
        self.progress = QtWidgets.QProgressBar()
        self.progress.setObjectName("actionProgress")
        self.progress.setRange(0, 1000)
        self.progress.setTextVisible(True)
        self.progress.hide()
        layout.addWidget(self.progress)
        self.numbers = Caption("")
        self.numbers.setObjectName("actionNumbers")
        self.feedback = Caption("")
        self.feedback.setObjectName("actionFeedback")
        self.result = Caption("")
        self.result.setObjectName("actionResult")
        for label in (self.numbers, self.feedback, self.result):
            layout.addWidget(label)
        self._build_form()
        self.refresh(model.state)

    # -- the form ---------------------------------------------------------------------------------
    def _build_form(self) -> None:
        fields = self.model.goal_fields()
        if fields == self._fields:
            return
        self._fields = fields
        while self.form.rowCount():
            self.form.removeRow(0)
        self.editors = {}
        firsts = {f.path.split(".", 1)[0] for f in fields}
        common = f"{firsts.pop()}." if len(firsts) == 1 and all("." in f.path for f in fields) else ""
        if common:  # one message holds every field (NavigateToFix's target): named once, above them
            heading = QtWidgets.QLabel(f"{common[:-1]}:")
            heading.setProperty("role", "hint")
            self.form.addRow(heading)
        for f in fields:
            editor: QtWidgets.QWidget
            kind = f"{f.base}{'[]' if f.is_array else ''}"
            if f.is_bool:
                editor = QtWidgets.QCheckBox()
                editor.setChecked(f.text == "true")
                tip = f"{f.path}: {kind}"
            else:  # empty: its placeholder is what an empty entry sends; a required one has none to send
                editor = QtWidgets.QLineEdit(f.text)
                editor.setPlaceholderText("required" if f.required else f.default or f"{kind} (robot's default)")
                editor.textChanged.connect(self._update_send)
                tip = (f"{f.path}: {kind}, required" if f.required else
                       f"{f.path}: {kind}; empty sends {f.default}" if f.default else
                       f"{f.path}: {kind}; empty: the robot's default")
            editor.setObjectName(f"goal_{f.path}")
            editor.setToolTip(tip)
            editor.setAccessibleName(f"{f.path}{' (required)' if f.required else ''}")
            editor.setMinimumWidth(120)  # a narrow widget puts the label above its field instead
            self.editors[f.path] = editor
            label = form_label(f.path[len(common):] + (" *" if f.required else ""), editor)
            if f.required:
                label.setToolTip("required: type a value before Send")
                label.setProperty("required", True)
            self.form.addRow(label, editor)
        if not fields:
            note = QtWidgets.QLabel("The goal's fields appear once the action type is known.")
            note.setProperty("role", "hint")
            note.setWordWrap(True)
            self.form.addRow(note)
        elif any(f.required for f in fields):
            note = QtWidgets.QLabel("* required")
            note.setObjectName("goalRequiredNote")
            note.setProperty("role", "hint")
            self.form.addRow(note)
        self._update_send()

    def missing(self) -> list[str]:
        """The required entries still empty (Send waits for them)."""
        return [f.path for f in self._fields if f.required and isinstance(editor := self.editors.get(f.path),
                                                                          QtWidgets.QLineEdit)
                and not editor.text().strip()]

    def _update_send(self, *_: Any) -> None:
        """Send only once every required entry is filled; the button says what it waits for."""
        missing = self.missing()
        self.send_button.setEnabled(not missing)
        self.send_button.setToolTip(
            "fill in " + ", ".join(m.rsplit(".", 1)[-1] for m in missing) + " first" if missing else "")

    def texts(self) -> dict[str, str]:
        """What the form holds, ``{path: text}``."""
        out = {}
        for path, editor in self.editors.items():
            if isinstance(editor, QtWidgets.QCheckBox):
                out[path] = "true" if editor.isChecked() else "false"
            elif isinstance(editor, QtWidgets.QLineEdit):
                out[path] = editor.text()
        return out

    def set_text(self, path: str, text: str) -> None:
        editor = self.editors[path]
        if isinstance(editor, QtWidgets.QCheckBox):
            editor.setChecked(text.strip().lower() == "true")
        elif isinstance(editor, QtWidgets.QLineEdit):
            editor.setText(text)

    def send(self) -> None:
        self.model.send(self.texts())

    # -- painting ---------------------------------------------------------------------------------
    def refresh(self, state: Any) -> None:
        if not self._fields:
            self._build_form()
        st = state.value
        phase = getattr(st, "phase", GoalPhase.IDLE)
        words, colour = PHASE_TEXT.get(phase, (phase, MUTED))
        detail = getattr(st, "text", "") or ""
        problem = state.error or getattr(st, "problem", "")  # e.g. "not sent: target.latitude: ..."
        if problem and (st is None or not st.running):
            words, colour, detail = "✗ Problem", BAD, problem
        elif state.link_down and st is not None and st.running:
            words, colour, detail = "? Link down", STALE, "the goal's fate is unknown until the link is back"
        self.status.show_text(f"{words}: {detail}" if detail else words, colour, tooltip=detail or words)
        running = st is not None and st.running
        self.cancel_button.setEnabled(running and phase is not GoalPhase.CANCELING)
        self.send_button.setText("Send new goal" if running else "Send goal")
        self._show_feedback(st)
        if problem and running:  # a new goal refused while one runs: said under it, the run stays in sight
            self.result.show_text(f"✗ {problem}", BAD, tooltip=problem)

    def _show_feedback(self, st: Any) -> None:
        if st is None:
            self.progress.hide()
            for label in (self.numbers, self.feedback, self.result):
                label.show_text("")
            return
        if st.progress is not None:
            self.progress.setValue(round(st.progress * 1000))
            self.progress.setFormat(f"{st.progress * 100:.0f} %  ({st.progress_label})")
            self.progress.show()
        else:
            self.progress.hide()
        self.numbers.show_text("   ".join(f"{p} {format_value(n, 2)}" for p, n in st.numbers), MUTED)
        if st.feedback is not None:
            one_line = " ".join(format_value(st.feedback).split())
            self.feedback.show_text(f"feedback #{st.feedback_count}: {one_line}", MUTED, tooltip=format_value(st.feedback))
        else:
            self.feedback.show_text("")
        if st.result is not None:
            colour = OK if st.phase is GoalPhase.SUCCEEDED else BAD if st.phase is GoalPhase.ABORTED else STALE
            took = f" after {st.seconds:.1f} s" if st.seconds else ""
            one_line = " ".join(format_value(st.result).split())
            self.result.show_text(f"result{took}: {one_line}", colour, tooltip=format_value(st.result))
        else:
            self.result.show_text("")

    def sizeHint(self) -> QtCore.QSize:  # noqa: N802 - Qt override
        return QtCore.QSize(320, 400)
