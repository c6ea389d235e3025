"""Entry point of this widget package (group ``rcon.widgets``): the module the plugin manager registers.

It must import without Qt: views are referenced lazily as ``module:attr`` strings. Each widget is
registered exactly as a lab's package would register its own.
"""

from __future__ import annotations

from rcon_core.plugins import Accepts, Role, WidgetSpec, hookimpl

from .common import NUMERIC_TYPES

PKG = "rcon_widgets_std"
#: the widget API this package is written against (rcon_core.plugins.api.API_VERSION when it was written)
API = "1.1"

LOG_TYPES = ("rosgraph_msgs/Log", "rcl_interfaces/msg/Log")


def _refs(module: str, name: str) -> dict[str, str]:
    return {
        "api_version": API,
        "settings": f"{PKG}.{module}:{name}Settings",
        "model": f"{PKG}.{module}:{name}Model",
        "view": f"{PKG}.{module}_view:{name}View",
    }


def specs() -> list[WidgetSpec]:
    """Every standard widget (also used by Compound to build std children without the manager)."""
    return [
        WidgetSpec(
            kind="std.label", title="Label", icon="label", category="Displays",
            description="A field or the whole message of any topic, with decimals, units and its age",
            roles={Role.SUBSCRIBE},
            accepts=Accepts(types=[*NUMERIC_TYPES, "std_msgs/String"],
                            fields=["numeric", "bool", "string", "time"], messages=["any"],
                            prefer=["data", "percentage", "value", "msg", "range", "temperature"]),
            default_size=(256, 112), priority=20, **_refs("label", "Label"),
        ),
        WidgetSpec(
            kind="std.slider", title="Slider", icon="slider", category="Controls",
            description="Sets (or shows) a number: std_msgs numbers or any numeric field",
            roles={Role.PUBLISH, Role.SUBSCRIBE},
            accepts=Accepts(types=NUMERIC_TYPES, fields=["numeric"], prefer=["data", "percentage", "value"]),
            default_size=(220, 80), priority=10, **_refs("slider", "Slider"),
        ),
        WidgetSpec(
            kind="std.switch", title="Switch", icon="switch", category="Controls",
            description="A bool: publishes it, shows it, or calls a SetBool-like service",
            roles={Role.PUBLISH, Role.SUBSCRIBE, Role.CALL},
            accepts=Accepts(types=["std_msgs/Bool", "std_srvs/SetBool"], fields=["bool"],
                            prefer=["data", "enable", "enabled", "on"], service_parts=["request"]),
            default_size=(208, 144), priority=10, **_refs("switch", "Switch"),
        ),
        WidgetSpec(
            kind="std.button", title="Button", icon="button", category="Controls",
            description="Calls a service when pressed (and another when released), or publishes a fixed message",
            roles={Role.CALL, Role.PUBLISH},
            accepts=Accepts(types=["std_srvs/Trigger", "std_srvs/Empty", "std_msgs/Empty"],
                            messages=["empty", "any"], service_parts=["request"]),
            default_size=(224, 144), priority=5, **_refs("button", "Button"),
        ),
        WidgetSpec(
            kind="std.textfield", title="Text Field", icon="textfield", category="Controls",
            description="Shows raw data of any type, or publishes what the operator types (YAML or JSON)",
            roles={Role.SUBSCRIBE, Role.PUBLISH},
            accepts=Accepts(types=["std_msgs/String"], fields=["numeric", "string", "bool", "time"],
                            messages=["any"], prefer=["data", "percentage", "value", "msg", "text", "name"]),
            default_size=(256, 128), priority=16, **_refs("textfield", "TextField"),
        ),
        WidgetSpec(
            kind="std.stepper", title="Stepper", icon="stepper", category="Controls",
            description="Publishes a number with - and + buttons (no feedback)",
            roles={Role.PUBLISH},
            accepts=Accepts(types=NUMERIC_TYPES, fields=["numeric"], prefer=["data", "value"]),
            default_size=(200, 80), priority=5, **_refs("stepper", "Stepper"),
        ),
        WidgetSpec(
            kind="std.textview", title="Text View", icon="textview", category="Displays",
            description="Scrolling history of strings and log lines, coloured by level, with filters; "
                        "as a publisher also an input line (a chat room)",
            roles={Role.SUBSCRIBE, Role.PUBLISH},
            accepts=Accepts(types=["std_msgs/String", *LOG_TYPES]),
            default_size=(420, 260), priority=15, **_refs("textview", "TextView"),
        ),
        WidgetSpec(
            kind="std.compound", title="Compound", icon="compound", category="Controls",
            description="Child widgets composing one message, service request or service response",
            roles={Role.PUBLISH, Role.CALL, Role.SERVE},
            accepts=Accepts(messages=["any"]),
            default_size=(320, 360), priority=0, **_refs("compound", "Compound"),
        ),
        WidgetSpec(
            kind="std.action", title="Action", icon="action", category="Controls",
            description="Sends a goal to a ROS 2 action server (a form from the goal type), shows its live "
                        "feedback and progress, the result and how it ended; Cancel",
            roles={Role.ACTION},
            accepts=Accepts(messages=["any"]),
            default_size=(352, 432), priority=10, **_refs("action", "Action"),
        ),
    ]


@hookimpl
def rcon_register_widgets(registry):  # type: ignore[no-untyped-def]
    for spec in specs():
        registry.add(spec)
