"""The plugin manager: owned by the app (no module global), a typed facade over pluggy.

::

    pm = PluginManager(disabled=["map"])       # also honours RCON_DISABLE_PLUGINS=name1,name2
    pm.load_entry_points()                     # the `rcon.widgets` group; each one under its own guard
    pm.register(my_module, name="test")        # tests: register plugin objects directly
    pm.widgets()                               # every WidgetSpec, package filled in
    pm.widget("std.slider")                    # one spec, or UnknownWidget
    pm.plugins / pm.failed                     # PluginInfo: name, dist, version, status, error, widgets
    pm.apply_types(type_registry)              # add contributed .msg/.srv definitions
    pm.canvas_templates()                      # example canvases plugins offer (New canvas from template)
    pm.type_registry(ros2=False)               # a standard TypeRegistry plus every contributed type

A plugin is "broken" when importing its entry point raises, or when one of its hooks raises: it is
recorded with status ``"failed"`` and the reason, and every other plugin still loads.
"""

from __future__ import annotations

import enum
import importlib.metadata as md
import logging
import os
import traceback
from collections.abc import Iterable, Mapping
from typing import TYPE_CHECKING, Any, Protocol

import attrs
import pluggy

from . import hookspecs
from .registry import (
    CanvasTemplate,
    TemplateRegistry,
    TypeContributions,
    TypeDefinition,
    TypeKind,
    WidgetRegistry,
)
from .spec import UnknownWidget, WidgetSpec

if TYPE_CHECKING:
    from rcon_core.msgs import TypeRegistry

__all__ = [
    "PluginManager", "PluginInfo", "UnknownWidget", "ENTRY_POINT_GROUP", "DISABLE_ENV", "installed_plugin_types",
    "TypeSink", "PluginStatus",
]

ENTRY_POINT_GROUP = "rcon.widgets"
DISABLE_ENV = "RCON_DISABLE_PLUGINS"

log = logging.getLogger(__name__)


class PluginStatus(enum.StrEnum):
    """Where a plugin stands; a ``str`` too, so ``info.status == "loaded"`` and JSON output keep working."""

    LOADED = "loaded"  #: its hooks ran; its widgets, types and templates are offered
    FAILED = "failed"  #: an import or a hook raised (``PluginInfo.error`` says what); nothing of it is offered
    DISABLED = "disabled"  #: named in ``disabled`` or ``RCON_DISABLE_PLUGINS``; nothing of it is used


@attrs.define
class PluginInfo:
    """What the manager knows about one plugin (one entry point, or one object given to register())."""

    name: str  #: entry-point name (or the name given to register())
    dist: str = ""  #: distribution name, e.g. "rcon-widgets-std"; "" when registered directly
    version: str = ""  #: distribution version
    value: str = ""  #: entry-point value, e.g. "rcon_widgets_std.plugin"
    status: PluginStatus = PluginStatus.LOADED
    error: str | None = None  #: one-line reason when failed
    details: str | None = None  #: traceback text when failed
    widgets: list[WidgetSpec] = attrs.field(factory=list)
    types: list[TypeDefinition] = attrs.field(factory=list)
    templates: list[CanvasTemplate] = attrs.field(factory=list)
    #: what of a loaded plugin is withdrawn while the rest works (a template whose file is missing)
    problems: list[str] = attrs.field(factory=list)
    plugin: Any = attrs.field(default=None, repr=False)

    @property
    def package(self) -> str:
        """The name widgets are recorded under: the distribution name, else the plugin name."""
        return self.dist or self.name

    def to_dict(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "dist": self.dist,
            "version": self.version,
            "value": self.value,
            "status": self.status,
            "error": self.error,
            "widgets": [
                {
                    "kind": s.kind,
                    "title": s.title,
                    "roles": sorted(r.value for r in s.roles),
                    "accepts": s.accepts.describe(),
                }
                for s in self.widgets
            ],
            "types": [d.name for d in self.types],
            "templates": [t.title for t in self.templates],
            "problems": list(self.problems),
        }


def _disabled_from_env(environ: Mapping[str, str]) -> set[str]:
    raw = environ.get(DISABLE_ENV, "")
    return {n.strip() for n in raw.split(",") if n.strip()}


def _one_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {text[0]}" if text else type(exc).__name__


class TypeSink(Protocol):
    """What :meth:`PluginManager.apply_types` and :meth:`~PluginManager.type_problems` need of a type
    registry (``rcon_core.msgs.TypeRegistry`` is one): learn definitions, then look them up."""

    def add_msg_text(self, name: str, text: str) -> list[str]: ...

    def add_typedefs(self, typedefs: Any, root: str | None = None) -> list[str]: ...

    def typedefs(self, name: str) -> list[dict[str, Any]]: ...

    def service_typedefs(self, name: str, part: str) -> list[dict[str, Any]]: ...


class PluginManager:
    """Discovers, loads and queries widget plugins. One per app (or per test)."""

    def __init__(
        self,
        *,
        disabled: Iterable[str] = (),
        environ: Mapping[str, str] | None = None,
        group: str = ENTRY_POINT_GROUP,
    ) -> None:
        env = os.environ if environ is None else environ
        #: names (entry-point or distribution names) that are not loaded
        self.disabled: set[str] = set(disabled) | _disabled_from_env(env)
        self.group = group
        self.pluggy = pluggy.PluginManager(hookspecs.PROJECT)
        self.pluggy.add_hookspecs(hookspecs)
        self._infos: dict[str, PluginInfo] = {}
        self._collected = False
        self._specs: dict[str, WidgetSpec] = {}
        self._discovered = False

    # -- loading -------------------------------------------------------------------------------------
    def load_entry_points(self) -> list[PluginInfo]:
        """Load every entry point of the group once; returns the infos of what was found."""
        if self._discovered:
            return self.plugins
        self._discovered = True
        found: list[PluginInfo] = []
        for ep in sorted(md.entry_points(group=self.group), key=lambda e: e.name):
            dist = getattr(ep, "dist", None)
            info = PluginInfo(
                name=ep.name,
                dist=dist.metadata["Name"] if dist is not None else "",
                version=dist.version if dist is not None else "",
                value=ep.value,
            )
            if info.name in self._infos:
                info.status, info.error = PluginStatus.FAILED, f"another plugin is already named {info.name!r}"
                self._infos[f"{info.name}@{info.dist}"] = info
                found.append(info)
                continue
            self._infos[info.name] = info
            found.append(info)
            if self._is_disabled(info):
                info.status = PluginStatus.DISABLED
                continue
            try:
                obj = ep.load()
                self._register_obj(obj, info)
            except Exception as exc:  # a broken plugin must not take the others down
                self._fail(info, exc)
        self._collected = False
        return found

    def register(
        self, plugin: Any, name: str | None = None, *, dist: str = "", version: str = ""
    ) -> PluginInfo:
        """Register a plugin object (module, class instance...) directly; used by tests and embedders.

        Raises ValueError if the name is taken. A plugin whose name is disabled is recorded as disabled.
        """
        name = name or getattr(plugin, "__name__", None) or type(plugin).__name__
        if name in self._infos:
            raise ValueError(f"a plugin named {name!r} is already registered")
        info = PluginInfo(name=name, dist=dist, version=version, value=repr(plugin))
        self._infos[name] = info
        if self._is_disabled(info):
            info.status = PluginStatus.DISABLED
        else:
            self._register_obj(plugin, info)
        self._collected = False
        return info

    def _is_disabled(self, info: PluginInfo) -> bool:
        return info.name in self.disabled or (bool(info.dist) and info.dist in self.disabled)

    def _register_obj(self, obj: Any, info: PluginInfo) -> None:
        self.pluggy.register(obj, name=info.name)
        info.plugin = obj
        self.pluggy.check_pending()  # hooks with an rcon_ prefix that match no spec raise here

    def _fail(self, info: PluginInfo, exc: BaseException) -> None:
        info.status = PluginStatus.FAILED
        info.error = _one_line(exc)
        info.details = "".join(traceback.format_exception(exc))
        info.widgets.clear()
        info.types.clear()
        info.templates.clear()
        info.problems.clear()
        if info.plugin is not None and self.pluggy.is_registered(info.plugin):
            self.pluggy.unregister(info.plugin)

    # -- hooks ---------------------------------------------------------------------------------------
    def _collect(self) -> None:
        if self._collected:
            return
        self._collected = True
        self._specs = {}
        for info in self._infos.values():
            info.widgets.clear()
            info.types.clear()
            info.templates.clear()
            info.problems.clear()
        for impl in self.pluggy.hook.rcon_register_widgets.get_hookimpls():  # registration order
            info = self._infos[impl.plugin_name]
            reg = WidgetRegistry(info.package, self._specs)
            try:
                impl.function(registry=reg)
            except Exception as exc:
                self._fail(info, exc)
                continue
            for spec in reg.specs:
                self._specs[spec.kind] = spec
            info.widgets.extend(reg.specs)
        for impl in self.pluggy.hook.rcon_register_types.get_hookimpls():
            info = self._infos[impl.plugin_name]
            if info.status is PluginStatus.FAILED:
                continue
            contrib = TypeContributions(info.package)
            try:
                impl.function(registry=contrib)
            except Exception as exc:
                for spec in info.widgets:
                    self._specs.pop(spec.kind, None)
                self._fail(info, exc)
                continue
            info.types.extend(contrib.definitions)
        for impl in self.pluggy.hook.rcon_canvas_templates.get_hookimpls():
            info = self._infos[impl.plugin_name]
            if info.status is PluginStatus.FAILED:
                continue
            templates = TemplateRegistry(info.package)
            try:
                impl.function(registry=templates)
            except Exception as exc:
                for spec in info.widgets:
                    self._specs.pop(spec.kind, None)
                self._fail(info, exc)
                continue
            info.templates.extend(templates.templates)
            info.problems.extend(templates.problems)
            for problem in templates.problems:
                log.warning("plugin %s: %s", info.name, problem)

    @property
    def plugins(self) -> list[PluginInfo]:
        """Every plugin seen, loaded or not, in discovery/registration order."""
        self._collect()
        return list(self._infos.values())

    @property
    def failed(self) -> list[PluginInfo]:
        return [p for p in self.plugins if p.status is PluginStatus.FAILED]

    def widgets(self) -> list[WidgetSpec]:
        """Every widget of every loaded plugin, in registration order."""
        self._collect()
        return list(self._specs.values())

    def widget(self, kind: str) -> WidgetSpec:
        """The spec of one kind; :class:`UnknownWidget` (a KeyError) names what is installed otherwise."""
        self._collect()
        try:
            return self._specs[kind]
        except KeyError:
            raise UnknownWidget(
                f"no installed widget plugin offers {kind!r} (installed kinds: "
                f"{', '.join(sorted(self._specs)) or 'none'})"
            ) from None

    def has_widget(self, kind: str) -> bool:
        self._collect()
        return kind in self._specs

    def canvas_templates(self) -> list[CanvasTemplate]:
        """Every example canvas the loaded plugins offer (``rcon_canvas_templates``), in plugin order."""
        return [t for p in self.plugins if p.status is PluginStatus.LOADED for t in p.templates]

    def type_definitions(self) -> list[TypeDefinition]:
        """Every definition contributed through ``rcon_register_types`` by loaded plugins."""
        return [d for p in self.plugins if p.status is PluginStatus.LOADED for d in p.types]

    def apply_types(self, types: TypeSink) -> list[str]:
        """Add contributed definitions to an ``rcon_core.msgs.TypeRegistry``.

        ``.msg``/``.srv`` text goes through ``types.add_msg_text``, typedefs through
        ``types.add_typedefs``. Returns the canonical names added. A definition that does not parse
        fails its plugin (recorded with the reason; its widgets are withdrawn) without stopping others.
        """
        added: list[str] = []
        for info in self.plugins:
            if info.status is not PluginStatus.LOADED:
                continue
            mine: list[str] = []
            try:
                for d in info.types:
                    if d.kind is TypeKind.TYPEDEFS:
                        mine += types.add_typedefs(list(d.typedefs))
                    else:
                        mine += types.add_msg_text(_interface_name(d.name, d.kind), d.text)
            except Exception as exc:
                for spec in info.widgets:
                    self._specs.pop(spec.kind, None)
                self._fail(info, exc)
                continue
            added += mine
        return added

    def type_problems(self, types: TypeSink) -> dict[str, list[str]]:
        """After :meth:`apply_types`: per plugin name, each contributed type that does not resolve in
        ``types`` (it uses a type nobody defines, often a misspelt builtin such as ``flaot64``)."""
        out: dict[str, list[str]] = {}
        for info in self.plugins:
            if info.status is not PluginStatus.LOADED:
                continue
            for d in info.types:
                try:
                    if d.kind is TypeKind.SRV:
                        for part in ("request", "response"):
                            types.service_typedefs(_interface_name(d.name, d.kind), part)
                    elif d.kind is TypeKind.MSG:
                        types.typedefs(d.name)
                except Exception as exc:
                    out.setdefault(info.name, []).append(f"type {d.name}: {exc}")
        return out

    def type_registry(self, ros2: bool = False) -> TypeRegistry:
        """A standard ``rcon_core.msgs.TypeRegistry`` for the flavour plus every type the loaded plugins
        contribute: the one registry every type look-up (app, CLI, matcher, sim) starts from."""
        from rcon_core.msgs import TypeRegistry

        types = TypeRegistry.standard(ros2=ros2)
        self.apply_types(types)
        return types


def installed_plugin_types(types: TypeSink) -> list[str]:
    """Add the types of every installed (enabled) plugin to ``types``; returns the names added.

    A plugin that fails is skipped (and logged), like everywhere else.
    """
    pm = PluginManager()
    pm.load_entry_points()
    added = pm.apply_types(types)
    for info in pm.failed:
        log.warning("plugin %s failed, its types are not loaded: %s", info.name, info.error)
    return added


def _interface_name(name: str, kind: str) -> str:
    """``lab_msgs/Grip`` given as a service -> ``lab_msgs/srv/Grip`` (the ROS 1 spelling is ambiguous)."""
    parts = name.split("/")
    return f"{parts[0]}/{kind}/{parts[1]}" if len(parts) == 2 else name
