"""Root conftest: shared fixtures for the core's tests and the bundled plugins' tests."""

import os

# `pytest` run directly (without tox) is headless too, instead of aborting where there is no display.
os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")

pytest_plugins = ["rcon_core.testing", "rcon_core.foxglove.testing"]

# a lab package with its own tests and pytest settings; tests/test_plugins_example.py runs them installed
collect_ignore = ["tests/example_plugin"]
