"""docs/protocols.md names the test that holds each behaviour; every one it names must exist."""

from __future__ import annotations

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def named_tests(text: str) -> list[tuple[str, str]]:
    """``(module, test)`` of every ``tests/module.py::name`` span, and of ``::name`` spans after one."""
    out: list[tuple[str, str]] = []
    module = ""
    for span in re.findall(r"`([^`]+)`", text):
        if re.fullmatch(r"[\w/]+\.py::\w+", span):
            module, name = span.split("::")
            module = module.removeprefix("tests/")
            out.append((module, name))
        elif re.fullmatch(r"::\w+", span):
            out.append((module, span[2:]))
    return out


def test_every_test_the_protocols_page_names_exists() -> None:
    named = named_tests((ROOT / "docs" / "protocols.md").read_text(encoding="utf-8"))
    assert len(named) >= 30
    missing = []
    for module, name in named:
        tree = ast.parse((ROOT / "tests" / module).read_text(encoding="utf-8"))
        funcs = {n.name for n in ast.walk(tree) if isinstance(n, ast.FunctionDef | ast.AsyncFunctionDef)}
        if name not in funcs:
            missing.append(f"{module}::{name}")
    assert missing == []
