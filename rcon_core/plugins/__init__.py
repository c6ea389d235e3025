"""The widget contract and the plugin system (no Qt).

::

    from rcon_core.plugins import PluginManager, WidgetSpec, Role, Accepts, hookimpl, WidgetModel, Binding

The contract itself is stated in :mod:`rcon_core.plugins.api`. See ``docs/hooks.md`` (the hooks) and
``docs/writing-a-widget-plugin.md`` (a guide).
"""

from .api import (
    API_VERSION,
    ActionGoal,
    ApiVersionError,
    CallPhase,
    CatalogSettings,
    CommandBounds,
    GoalPhase,
    HostedModel,
    ModelHooks,
    NotAValue,
    Port,
    RobotPort,
    SizedSettings,
    StaleAfterSettings,
    WidgetSettings,
    WidgetView,
    as_port,
    settings_commands,
    settings_problems,
    settings_size,
)
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
from .staleness import NO_DATA_AFTER, Staleness

__all__ = [
    "API_VERSION",
    "ApiVersionError",
    "ActionGoal",
    "CallPhase",
    "GoalPhase",
    "CatalogSettings",
    "CommandBounds",
    "HostedModel",
    "ModelHooks",
    "NotAValue",
    "Port",
    "RobotPort",
    "SizedSettings",
    "StaleAfterSettings",
    "WidgetSettings",
    "WidgetView",
    "as_port",
    "settings_commands",
    "settings_problems",
    "settings_size",
    "NO_DATA_AFTER",
    "Staleness",
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
