"""Root conftest: shared fixtures for the core's tests and the bundled plugins' tests."""

pytest_plugins = ["rcon_core.testing"]
