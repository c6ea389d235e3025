"""RCON core: rosbridge client, message types, canvas model, plugin system, simulated robot, Qt front end.

Importing this package (or any of its non-``app`` subpackages) never imports Qt.
"""

__version__ = "0.1.0"
