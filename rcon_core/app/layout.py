"""The app's view of a workspace: canvases of widget instances, the lock, and their JSON file.

This is the data the window edits and saves.  It is deliberately plain (attrs + dicts): instances carry
their kind, binding, settings dict and rectangle, so a layout whose widget package is missing still
loads, shows placeholders, and saves back unchanged.
"""

from __future__ import annotations

import json
import uuid
from pathlib import Path
from typing import Any

import attrs

from rcon_core.plugins import Binding, Role

FORMAT = "rcon-workspace"
VERSION = 1


class LayoutError(ValueError):
    """A layout file that cannot be read; the message names the file and the problem."""


def new_id(kind: str) -> str:
    return f"{kind.rsplit('.', 1)[-1]}-{uuid.uuid4().hex[:8]}"


@attrs.define
class Instance:
    """One widget on a canvas."""

    kind: str
    binding: Binding = attrs.field(factory=Binding)
    settings: dict[str, Any] = attrs.field(factory=dict)
    rect: tuple[int, int, int, int] = (16, 16, 192, 128)
    title: str = ""
    id: str = ""

    def __attrs_post_init__(self) -> None:
        if not self.id:
            self.id = new_id(self.kind)

    def to_dict(self) -> dict[str, Any]:
        b = self.binding
        return {
            "id": self.id,
            "kind": self.kind,
            "title": self.title,
            "binding": {"name": b.name, "type": b.type, "role": b.role.value, "field_paths": list(b.field_paths)},
            "settings": self.settings,
            "rect": list(self.rect),
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> Instance:
        b = d.get("binding") or {}
        rect = d.get("rect") or (16, 16, 192, 128)
        if len(rect) != 4:
            raise LayoutError(f"widget {d.get('id')!r}: rect must have 4 numbers, got {rect!r}")
        return cls(
            kind=str(d["kind"]),
            binding=Binding(
                str(b.get("name", "")), str(b.get("type", "")), Role.parse(b.get("role", "subscribe")),
                tuple(b.get("field_paths") or ()),
            ),
            settings=dict(d.get("settings") or {}),
            rect=tuple(int(v) for v in rect),  # type: ignore[arg-type]
            title=str(d.get("title", "")),
            id=str(d.get("id", "")),
        )


@attrs.define
class CanvasDoc:
    """A named page of widgets; ``locked`` is the operator mode, saved with the layout."""

    name: str
    instances: list[Instance] = attrs.field(factory=list)
    locked: bool = False

    def find(self, instance_id: str) -> Instance | None:
        return next((i for i in self.instances if i.id == instance_id), None)

    def to_dict(self) -> dict[str, Any]:
        return {"name": self.name, "locked": self.locked, "widgets": [i.to_dict() for i in self.instances]}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> CanvasDoc:
        return cls(
            name=str(d.get("name") or "Canvas"),
            instances=[Instance.from_dict(w) for w in d.get("widgets") or []],
            locked=bool(d.get("locked", False)),
        )


@attrs.define
class WorkspaceDoc:
    """Every canvas, and which one is shown."""

    canvases: list[CanvasDoc] = attrs.field(factory=list)
    current: int = 0

    def __attrs_post_init__(self) -> None:
        if not self.canvases:
            self.canvases.append(CanvasDoc("Main"))

    @property
    def canvas(self) -> CanvasDoc:
        self.current = max(0, min(self.current, len(self.canvases) - 1))
        return self.canvases[self.current]

    def unique_name(self, base: str) -> str:
        taken = {c.name for c in self.canvases}
        if base not in taken:
            return base
        n = 2
        while f"{base} {n}" in taken:
            n += 1
        return f"{base} {n}"

    def to_dict(self) -> dict[str, Any]:
        return {
            "format": FORMAT,
            "version": VERSION,
            "current": self.current,
            "canvases": [c.to_dict() for c in self.canvases],
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> WorkspaceDoc:
        if d.get("format") != FORMAT:
            raise LayoutError(f"not an RCON workspace (format is {d.get('format')!r}, expected {FORMAT!r})")
        return cls(canvases=[CanvasDoc.from_dict(c) for c in d.get("canvases") or []], current=int(d.get("current", 0)))

    def save(self, path: Path) -> None:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(path.suffix + ".tmp")
        tmp.write_text(json.dumps(self.to_dict(), indent=2), encoding="utf-8")
        tmp.replace(path)

    @classmethod
    def load(cls, path: Path) -> WorkspaceDoc:
        try:
            data = json.loads(Path(path).read_text(encoding="utf-8"))
        except OSError as exc:
            raise LayoutError(f"{path}: cannot read the layout: {exc.strerror or exc}") from exc
        except ValueError as exc:
            raise LayoutError(f"{path}: not valid JSON: {exc}") from exc
        if not isinstance(data, dict):
            raise LayoutError(f"{path}: a layout must be a JSON object")
        try:
            return cls.from_dict(data)
        except (KeyError, TypeError, ValueError) as exc:
            if isinstance(exc, LayoutError):
                raise LayoutError(f"{path}: {exc}") from exc
            raise LayoutError(f"{path}: damaged layout: {exc}") from exc
