"""The window's parts are composed, not patched (issue 24.9): each is built with the few objects it needs,
typed, the operator lock's guard among them, and none takes the whole window."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest
from qtpy import QtWidgets

from rcon_core.app.canvas_bar import CanvasBar
from rcon_core.app.config import AppConfig
from rcon_core.app.connection_bar import ConnectionBar
from rcon_core.app.link import RobotConnection

pytestmark = pytest.mark.usefixtures("qapp")
APP = Path(__file__).resolve().parent.parent / "rcon_core" / "app"


class Refusing:
    """A guard that never lets anything through (a locked app whose operator cancels the PIN)."""

    def __init__(self) -> None:
        self.asked: list[str] = []

    def __call__(self, what, then):
        self.asked.append(what)


def test_the_canvas_bar_asks_its_guard_for_the_gated_actions_only() -> None:
    ran: list[str] = []
    guard = Refusing()
    bar = CanvasBar({name: (name, lambda name=name: ran.append(name)) for name in ("new", "delete", "export")},
                    lambda: ran.append("undo"), lambda: ran.append("redo"), guard=guard,
                    gated={"new": "add a canvas", "delete": "delete the canvas"})
    for name in ("new", "delete", "export"):
        bar.canvas_actions[name].trigger()
    bar.canvas_buttons["undo"].click()
    assert guard.asked == ["add a canvas", "delete the canvas"]
    assert ran == ["export", "undo"]  # the gated ones waited for the guard, which said no


def test_a_canvas_bar_without_a_guard_runs_every_action() -> None:
    ran: list[str] = []
    bar = CanvasBar({"new": ("New", lambda: ran.append("new"))}, lambda: None, lambda: None,
                    gated={"new": "add a canvas"})
    bar.canvas_actions["new"].trigger()
    assert ran == ["new"]


def test_the_connection_bar_asks_its_guard_before_changing_the_robot(tmp_path: Path) -> None:
    guard = Refusing()
    link = RobotConnection()
    try:
        bar = ConnectionBar(link, AppConfig(tmp_path / "cfg"), guard=guard)
        bar.url.setCurrentText("ws://127.0.0.1:9")
        bar.connect_button.click()
        assert bar.open_settings() is None
        assert guard.asked == ["change the robot", "change the robot's connection settings"]
        assert link.client is None and bar.dialog is None  # nothing connected, no dialog opened
    finally:
        link.shutdown()


def test_without_the_lock_the_security_dialog_opens(tmp_path: Path) -> None:
    link = RobotConnection()
    try:
        bar = ConnectionBar(link, AppConfig(tmp_path / "cfg"))
        bar.url.setCurrentText("ws://127.0.0.1:9")
        dialog = bar.open_settings()
        assert isinstance(dialog, QtWidgets.QDialog) and dialog is bar.dialog
        dialog.close()
    finally:
        link.shutdown()


def _whole_window_parameters(root: Path = APP) -> list[str]:
    """Parameters in ``root`` named like the window (window, win, main) and typed ``Any`` or not typed."""
    found = []
    for path in sorted(root.glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                for arg in [*node.args.posonlyargs, *node.args.args, *node.args.kwonlyargs]:
                    note = ast.unparse(arg.annotation) if arg.annotation is not None else None
                    if arg.arg in ("window", "win", "main") and note in (None, "Any"):
                        found.append(f"{path.name}:{node.lineno} {node.name}({arg.arg}: {note})")
    return found


def test_no_part_takes_the_whole_window_untyped() -> None:
    assert _whole_window_parameters() == []


def test_the_check_sees_a_whole_window_parameter(tmp_path: Path) -> None:
    (tmp_path / "part.py").write_text("from typing import Any\n\n\ndef install(window: Any) -> None:\n    pass\n\n\n"
                                      "def show(window) -> None:\n    pass\n")
    assert _whole_window_parameters(tmp_path) == ["part.py:4 install(window: Any)", "part.py:8 show(window: None)"]
