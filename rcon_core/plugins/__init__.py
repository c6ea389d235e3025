"""The widget contract and the plugin system (no Qt).

::

    from rcon_core.plugins import PluginManager, WidgetSpec, Role, Accepts, hookimpl, WidgetModel, Binding

See ``docs/hooks.md`` (the hooks) and ``docs/writing-a-widget-plugin.md`` (a guide).
"""

from .context import SharedResources, SpecLookup, WidgetCatalog, WidgetContext
from .hookspecs import hookimpl, hookspec
from .manager import DISABLE_ENV, ENTRY_POINT_GROUP, PluginInfo, PluginManager, PluginStatus, UnknownWidget
from .model import Binding, BridgePort, WidgetModel, WidgetState
from .model_types import ModelTypes
from .paths import PathError, get_path, set_path
from .registry import (
    CanvasTemplate,
    DuplicateWidget,
    TemplateRegistry,
    TypeContributions,
    TypeDefinition,
    WidgetRegistry,
)
from .spec import (
    FIELD_PREDICATES,
    MESSAGE_PREDICATES,
    Accepts,
    Role,
    SettingsError,
    SpecError,
    WidgetSpec,
    resolve,
)

__all__ = [
    "hookimpl",
    "hookspec",
    "PluginManager",
    "PluginInfo",
    "PluginStatus",
    "UnknownWidget",
    "ENTRY_POINT_GROUP",
    "DISABLE_ENV",
    "WidgetSpec",
    "Role",
    "Accepts",
    "FIELD_PREDICATES",
    "MESSAGE_PREDICATES",
    "SpecError",
    "SettingsError",
    "resolve",
    "WidgetModel",
    "WidgetState",
    "ModelTypes",
    "Binding",
    "BridgePort",
    "WidgetContext",
    "SharedResources",
    "SpecLookup",
    "WidgetCatalog",
    "WidgetRegistry",
    "TypeContributions",
    "TemplateRegistry",
    "CanvasTemplate",
    "TypeDefinition",
    "DuplicateWidget",
    "PathError",
    "get_path",
    "set_path",
]
