"""The hooks a widget package may implement (all prefixed ``rcon_``, always called with keywords).

Every hook here is documented in ``docs/hooks.md`` (a test checks it). Implement a hook with
``from rcon_core.plugins import hookimpl``::

    @hookimpl
    def rcon_register_widgets(registry):
        registry.add(WidgetSpec(...))

The plugin manager calls each plugin's implementation separately, so one plugin raising does not stop
the others: the failure is recorded against that plugin (``rcon plugins`` shows it).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import pluggy

if TYPE_CHECKING:
    from .registry import TemplateRegistry, TypeContributions, WidgetRegistry

#: pluggy project name; also the prefix of every hook
PROJECT = "rcon"

hookspec = pluggy.HookspecMarker(PROJECT)
hookimpl = pluggy.HookimplMarker(PROJECT)


@hookspec
def rcon_register_widgets(registry: WidgetRegistry) -> None:
    """Register the widget kinds this package offers.

    Call ``registry.add(WidgetSpec(...))`` once per widget. Must not import Qt: refer to views as
    ``"module:attr"`` strings. Called once, when the app (or ``rcon plugins``) first lists widgets.
    A kind already registered by another package is refused (``registry.add`` raises
    :class:`~rcon_core.plugins.registry.DuplicateWidget`), which fails this plugin only.
    """


@hookspec
def rcon_register_types(registry: TypeContributions) -> None:
    """Contribute message or service definitions the robot may use but RCON does not ship.

    ``registry.add_msg("lab_msgs/msg/Gripper", text)`` with ``.msg`` text,
    ``registry.add_srv("lab_msgs/srv/Grip", text)`` with ``.srv`` text (request ``---`` response), or
    ``registry.add_typedefs(typedefs)`` with rosapi ``message_details`` typedefs. Either type-name
    spelling is accepted. The definitions are added to the app's type registry before widgets are
    matched, so the matcher and ``rcon type`` know them even when offline.
    """


@hookspec
def rcon_canvas_templates(registry: TemplateRegistry) -> None:
    """Offer example canvases (ready layouts for the package's widgets) under "New canvas from template".

    ``registry.add(title, path, description="")`` with a canvas file in the ``rcon-canvas`` format (what
    "Export canvas…" writes; see ``docs/layout-format.md``), usually shipped as package data:
    ``registry.add("Gripper station", importlib.resources.files(__package__) / "gripper.json")``.
    A missing file fails this plugin only. Check a file with ``rcon layout validate FILE``.
    """
