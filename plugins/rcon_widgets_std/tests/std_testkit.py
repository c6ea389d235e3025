"""Helpers for the standard widgets' tests (a plain module with a unique name, not a conftest)."""

from __future__ import annotations

from rcon_widgets_std import plugin as std_plugin

from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import Binding, WidgetContext
from rcon_core.testing import connected, widget_catalog

#: what the standard widgets' tests see: this package's kinds only (no entry point, no other package)
STD = widget_catalog(std_plugin, names=["std"])


def bridge(sim):
    """``async with bridge(sim) as client:`` a client connected to ``sim``, closed afterwards."""
    return connected(sim.url, reconnect=False)


def build(model_cls, settings, name, type_, role, paths=(), *, client=None, types=None, node="w", clock=None,
          port=None, context=None, **extra):
    """A model bound as given, on its own node of ``client``, on ``port`` (e.g. a ``RecordingPort``) or on
    no port; ``context``: a ``WidgetContext`` (default: one whose catalog is this package's kinds,
    :data:`STD`); ``extra``: the model's own keyword arguments (e.g. a numeric model's ``schedule``)."""
    kwargs = {"types": types if types is not None else TypeRegistry.standard(), **extra}
    if clock is not None:
        kwargs["clock"] = clock
    kwargs["context"] = context if context is not None else WidgetContext(STD)
    port = client.node(node) if client is not None else port
    return model_cls(settings, Binding(name, type_, role, paths), port, **kwargs)
