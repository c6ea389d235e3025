"""Root conftest: shared fixtures for the core's tests and the bundled plugins' tests."""

import os

# `pytest` run directly (without tox) is headless too, instead of aborting where there is no display.
os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")

pytest_plugins = ["rcon_core.testing"]
