"""RCON's Qt front end (qtpy over PySide6): the only core package that imports Qt.

Entry point: :func:`rcon_core.app.main.run_app`, called by the ``rcon`` command.
"""
