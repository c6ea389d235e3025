"""The registry objects handed to hooks: typed facades, one per plugin call."""

from __future__ import annotations

import enum
import os
from pathlib import Path
from typing import Any

import attrs

from .spec import SpecError, WidgetSpec, check_api_version

__all__ = ["WidgetRegistry", "TypeContributions", "TypeDefinition", "TypeKind", "DuplicateWidget", "TemplateRegistry",
           "CanvasTemplate"]


class DuplicateWidget(SpecError):
    """Two packages (or one package twice) registered the same widget kind."""


class WidgetRegistry:
    """Given to ``rcon_register_widgets``: collects :class:`WidgetSpec` objects for one plugin.

    The manager fills each spec's ``package`` with the plugin's distribution name.
    """

    def __init__(self, package: str, taken: dict[str, WidgetSpec]) -> None:
        self._package = package
        self._taken = taken
        self.specs: list[WidgetSpec] = []

    @property
    def package(self) -> str:
        """The distribution (or plugin) name the widgets are recorded under."""
        return self._package

    def add(self, spec: WidgetSpec) -> WidgetSpec:
        """Register one widget; returns the spec with ``package`` filled in. A spec built for another major
        version of the widget API raises ``ApiVersionError`` (the plugin is refused with that sentence)."""
        if not isinstance(spec, WidgetSpec):
            raise SpecError(f"registry.add() takes a WidgetSpec, got {type(spec).__name__}")
        check_api_version(spec.api_version, spec.kind, self._package)
        if spec.kind in self._taken or any(s.kind == spec.kind for s in self.specs):
            owner = self._taken[spec.kind].package if spec.kind in self._taken else self._package
            raise DuplicateWidget(f"widget kind {spec.kind!r} is already registered by {owner!r}")
        spec = attrs.evolve(spec, package=self._package)
        self.specs.append(spec)
        return spec


class TypeKind(enum.StrEnum):
    """How a contributed definition is given (a ``str``: ``d.kind == "msg"`` still holds)."""

    MSG = "msg"  #: ``.msg`` text
    SRV = "srv"  #: ``.srv`` text
    TYPEDEFS = "typedefs"  #: rosapi ``message_details`` typedefs


@attrs.frozen
class TypeDefinition:
    """One contributed definition: ``kind`` says how it is given (:class:`TypeKind`)."""

    kind: TypeKind = attrs.field(converter=TypeKind)
    name: str
    text: str = ""
    typedefs: tuple[dict[str, Any], ...] = ()
    package: str = ""


class TypeContributions:
    """Given to ``rcon_register_types``: collects message/service definitions for one plugin."""

    def __init__(self, package: str) -> None:
        self._package = package
        self.definitions: list[TypeDefinition] = []

    @property
    def package(self) -> str:
        return self._package

    def add_msg(self, name: str, text: str) -> None:
        """A message type from ``.msg`` text, e.g. ``add_msg("lab_msgs/Gripper", "float64 opening\\n")``."""
        self._check(name, "msg", text)
        self.definitions.append(TypeDefinition(TypeKind.MSG, name, text=text, package=self._package))

    def add_srv(self, name: str, text: str) -> None:
        """A service type from ``.srv`` text (request fields, a ``---`` line, response fields)."""
        self._check(name, "srv", text)
        if not any(line.strip() == "---" for line in text.splitlines()):
            raise SpecError(f"service definition {name!r} has no '---' line between request and response")
        self.definitions.append(TypeDefinition(TypeKind.SRV, name, text=text, package=self._package))

    def add_typedefs(self, typedefs: list[dict[str, Any]]) -> None:
        """Types in rosapi ``message_details`` layout (list of {"type", "fieldnames", "fieldtypes", ...})."""
        if not isinstance(typedefs, list) or not all(isinstance(t, dict) and "type" in t for t in typedefs):
            raise SpecError("add_typedefs() takes a list of rosapi typedef dicts, each with a 'type' key")
        name = typedefs[0]["type"] if typedefs else ""
        self.definitions.append(
            TypeDefinition(TypeKind.TYPEDEFS, name, typedefs=tuple(typedefs), package=self._package)
        )

    @staticmethod
    def _check(name: str, kind: str, text: str) -> None:
        parts = name.split("/")
        if len(parts) not in (2, 3) or not all(parts) or (len(parts) == 3 and parts[1] != kind):
            raise SpecError(f"type name {name!r} must look like 'pkg/Type' or 'pkg/{kind}/Type'")
        if not isinstance(text, str):
            raise SpecError(f"definition of {name!r} must be text")


@attrs.frozen
class CanvasTemplate:
    """An example canvas a plugin offers: a canvas file (``rcon-canvas`` format) shown under "New canvas
    from template"."""

    title: str
    path: Path
    description: str = ""
    package: str = ""


class TemplateRegistry:
    """Given to ``rcon_canvas_templates``: collects the example canvases of one plugin."""

    def __init__(self, package: str) -> None:
        self._package = package
        self.templates: list[CanvasTemplate] = []
        #: sentences about templates that are not offered (a file missing from the installed package)
        self.problems: list[str] = []

    @property
    def package(self) -> str:
        return self._package

    def add(self, title: str, path: str | os.PathLike[str] | Any, description: str = "") -> CanvasTemplate | None:
        """Offer the canvas file at ``path`` (e.g. ``importlib.resources.files(__package__) / "x.json"``)
        as ``title``; it is read when the operator picks the template. A file that is not there (package
        data left out of the wheel) withdraws that template alone: it is recorded in :attr:`problems`
        (``rcon plugins --check`` fails on it) and None is returned; the plugin's widgets still load."""
        if not isinstance(title, str) or not title.strip():
            raise SpecError("a canvas template needs a non-empty title")
        file = Path(str(path))
        if not file.is_file():
            self.problems.append(f"template {title.strip()!r} is not offered: no file at {file} (is it listed "
                                 "as package data in pyproject.toml?)")
            return None
        template = CanvasTemplate(title.strip(), file, description, self._package)
        self.templates.append(template)
        return template
