"""Canvas ▾ → Robots…: the workspace's robots, one row each (name, URL, CA file, rosauth, view only).

One tap on a cell edits it (the hint under the table says so). OK replaces the robots in one undo step
(``Document.set_robots``); the running widgets are rebuilt only where that changes what they do (see
``FleetUi``): OK with nothing changed keeps every form, trail and value as it was. The first robot's URL may stay empty:
it then follows the connection bar's URL field; the first robot cannot be removed (it is the connection
bar's, and the robot of every binding that names none). A robot whose URL or connection settings changed
connects again. A robot removed here leaves its widgets in place; they
say that their robot is not in the workspace until it is added back (or ↶). A URL the app cannot use is
refused with its reason before anything changes.

*Recording file…* adds a robot whose source is a recording (``Robot.recording``: an .mcap, a .bag or a
rosbag2 folder's file), named after the file; its URL cell shows the file and cannot be edited, and it
is view-only (commands go nowhere). A file that is not a recording is refused with the reason. It is saved
with the workspace like any robot: the window plays it again when the workspace opens
(``robot_recordings.py``).
"""

from __future__ import annotations

import copy
from typing import Any

import attrs
from qtpy import QtCore, QtWidgets

from rcon_core.app.connection_bar import normalize_url
from rcon_core.app.link import BadUrl, check_url
from rcon_core.canvas import new_id
from rcon_core.canvas.robots import Robot

__all__ = ["RobotsDialog"]

COLUMNS = ("Name", "URL", "CA file", "rosauth", "View only")


class RobotsDialog(QtWidgets.QDialog):
    def __init__(self, robots: list[Robot], parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.setObjectName("robotsDialog")
        self.setWindowTitle("Robots")
        self._robots = copy.deepcopy(list(robots))
        self.table = QtWidgets.QTableWidget(0, len(COLUMNS))
        self.table.setObjectName("robotsTable")
        self.table.setHorizontalHeaderLabels(list(COLUMNS))
        self.table.setAccessibleName("Robots")
        # one tap on a cell types in it (a double tap is no gesture a gloved finger finds, and nothing said
        # so); a cell is never opened for typing by itself (on opening, by focus), only by a tap or a key
        self.table.clicked.connect(self._tapped)
        header = self.table.horizontalHeader()
        header.setSectionResizeMode(1, QtWidgets.QHeaderView.ResizeMode.Stretch)
        # rows as tall as the theme's touch-sized check boxes, with room around them
        self.table.verticalHeader().setDefaultSectionSize(QtWidgets.QCheckBox().sizeHint().height() + 16)
        for robot in self._robots:
            self._add_row(robot)
        add = QtWidgets.QPushButton("Add robot")
        add.setObjectName("addRobot")
        add.clicked.connect(lambda: self._add_row(Robot(new_id("r"), f"Robot {self.table.rowCount() + 1}")))
        recording = QtWidgets.QPushButton("Recording file…")
        recording.setObjectName("addRecording")
        recording.setToolTip("A recording (.mcap, .bag, rosbag2) played as one more robot; commands go nowhere")
        recording.clicked.connect(self._pick_recording)
        remove = QtWidgets.QPushButton("Remove")
        remove.setObjectName("removeRobot")
        remove.clicked.connect(self._remove_row)
        self.hint = QtWidgets.QLabel("Tap a cell to type in it; tick rosauth or View only in a robot's row.")
        self.hint.setObjectName("robotsHint")
        self.hint.setProperty("role", "hint")
        self.hint.setWordWrap(True)
        self.problem = QtWidgets.QLabel()
        self.problem.setObjectName("robotsProblem")
        self.problem.setProperty("role", "problem")
        self.problem.setWordWrap(True)
        buttons = QtWidgets.QDialogButtonBox(
            QtWidgets.QDialogButtonBox.StandardButton.Ok | QtWidgets.QDialogButtonBox.StandardButton.Cancel)
        buttons.accepted.connect(self._ok)
        buttons.rejected.connect(self.reject)
        row = QtWidgets.QHBoxLayout()
        row.addWidget(add)
        row.addWidget(recording)
        row.addWidget(remove)
        row.addStretch(1)
        col = QtWidgets.QVBoxLayout(self)
        col.addWidget(self.table, 1)
        col.addWidget(self.hint)
        col.addLayout(row)
        col.addWidget(self.problem)
        col.addWidget(buttons)
        self.resize(820, 360)

    def _add_row(self, robot: Robot) -> None:
        if robot not in self._robots:
            self._robots.append(robot)
        r = self.table.rowCount()
        self.table.insertRow(r)
        for c, text in enumerate((robot.name, robot.recording or robot.url, robot.ca_file)):
            item = QtWidgets.QTableWidgetItem(text)
            if c == 1 and r == 0:
                item.setToolTip("empty: the URL of the connection bar")
            if c == 1 and robot.recording:  # where it comes from: a file, not a URL to edit
                item.setFlags(item.flags() & ~QtCore.Qt.ItemFlag.ItemIsEditable)
                item.setToolTip("a recording played as this robot: commands go nowhere")
            self.table.setItem(r, c, item)
        for c, flag in ((3, robot.auth), (4, robot.view_only or bool(robot.recording))):
            box = QtWidgets.QCheckBox()
            box.setObjectName(("robotAuth", "robotViewOnly")[c - 3])
            box.setChecked(flag)
            box.setEnabled(not robot.recording)
            box.setAccessibleName(f"{COLUMNS[c]} for {robot.name or robot.id}")
            cell = QtWidgets.QWidget()
            row = QtWidgets.QHBoxLayout(cell)
            row.setContentsMargins(0, 0, 0, 0)
            row.addWidget(box, 0, QtCore.Qt.AlignmentFlag.AlignCenter)
            self.table.setCellWidget(r, c, cell)

    def _tapped(self, index: QtCore.QModelIndex) -> None:
        if self.table.item(index.row(), index.column()) is not None:  # a text cell (not a tick box's)
            self.table.edit(index)

    def _pick_recording(self) -> None:
        path, _filter = QtWidgets.QFileDialog.getOpenFileName(
            self, "Recording file", "", "Recordings (*.mcap *.bag *.db3 metadata.yaml);;All files (*)")
        if path:
            self.add_recording(path)

    def add_recording(self, path: str) -> Robot | None:
        """Add a robot that plays the recording at ``path`` (a rosbag2 folder's ``metadata.yaml`` or
        ``.db3``: the folder); a file that is not a recording is refused in :attr:`problem`."""
        from pathlib import Path

        from rcon_core.record.files import RecordingError, open_recording

        p = Path(path).expanduser().absolute()  # kept with the workspace: not relative to where the app started
        if p.name == "metadata.yaml" or p.suffix == ".db3":
            p = p.parent
        try:
            open_recording(str(p)).close()
        except (RecordingError, OSError, ValueError) as exc:
            self.problem.setText(f"cannot replay {p.name}: {exc}")
            return None
        self.problem.clear()
        robot = Robot(new_id("r"), p.name.split(".")[0] or p.name, recording=str(p), view_only=True)
        self._add_row(robot)
        return robot

    def _remove_row(self) -> None:
        r = self.table.currentRow()
        if r <= 0:  # none picked, or the first: the connection bar's robot, the default of every binding
            self.problem.setText("pick a robot to remove; the first robot (the connection bar's) stays")
            return
        self.table.removeRow(r)
        del self._robots[r]

    def _text(self, r: int, c: int) -> str:
        item = self.table.item(r, c)
        return item.text().strip() if item is not None else ""

    def _box(self, r: int, c: int) -> QtWidgets.QCheckBox | None:
        cell = self.table.cellWidget(r, c)
        return cell.findChild(QtWidgets.QCheckBox) if cell is not None else None

    def _checked(self, r: int, c: int) -> bool:
        box = self._box(r, c)
        return box is not None and box.isChecked()

    def robots(self) -> list[Robot]:
        """The robots as edited (raises BadUrl for a URL the app cannot use)."""
        out = []
        for r, robot in enumerate(self._robots):
            url = "" if robot.recording else self._text(r, 1)  # a recording's cell shows its file
            if url:
                url = check_url(normalize_url(url))
            out.append(attrs.evolve(robot, name=self._text(r, 0) or robot.id, url=url, ca_file=self._text(r, 2),
                                    auth=self._checked(r, 3), view_only=self._checked(r, 4)))
        return out

    def _ok(self) -> None:
        # a cell still being typed in counts: leaving it commits the editor's text to the table
        self.table.setCurrentIndex(QtCore.QModelIndex())
        try:
            self.robots()
        except BadUrl as exc:
            self.problem.setText(str(exc))
            return
        self.accept()

    def set_row(self, r: int, **values: Any) -> None:
        """Fill a row's cells (name, url, ca_file: text; auth, view_only: bool), as typing would."""
        for c, key in enumerate(("name", "url", "ca_file")):
            if key in values:
                self.table.setItem(r, c, QtWidgets.QTableWidgetItem(values[key]))
        for c, key in ((3, "auth"), (4, "view_only")):
            if key in values:
                box = self._box(r, c)
                if box is not None:
                    box.setChecked(bool(values[key]))
