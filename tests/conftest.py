"""Fixtures shared by the core's test modules (the sim fixtures come from ``rcon_core.testing``, loaded by
the root conftest). Nothing here imports Qt."""

import pytest

from rcon_core.plugins import PluginManager


@pytest.fixture(scope="module")
def plugins() -> PluginManager:
    """Every widget plugin installed through the entry points (what the app tests' windows use); a module
    that needs other plugins defines its own ``plugins``."""
    pm = PluginManager(environ={})
    pm.load_entry_points()
    return pm
