"""Helpers for the standard widgets' tests (a plain module with a unique name, not a conftest)."""

from __future__ import annotations

from contextlib import asynccontextmanager

from rcon_core.bridge import BridgeClient
from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import Binding


@asynccontextmanager
async def bridge(sim):
    client = BridgeClient(sim.url, reconnect=False)
    await client.connect()
    try:
        yield client
    finally:
        await client.close()


def build(model_cls, settings, name, type_, role, paths=(), *, client=None, types=None, node="w", clock=None,
          port=None):
    """A model bound as given, on its own node of ``client``, on ``port`` (e.g. a ``RecordingPort``) or on
    no port."""
    kwargs = {"types": types if types is not None else TypeRegistry.standard()}
    if clock is not None:
        kwargs["clock"] = clock
    port = client.node(node) if client is not None else port
    return model_cls(settings, Binding(name, type_, role, paths), port, **kwargs)
