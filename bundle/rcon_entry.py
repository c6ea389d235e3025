"""The frozen app's entry point: the same ``rcon`` command a pip install gives (the app, and every
subcommand). PyInstaller freezes this file; ``bundle/rcon.spec`` says what goes with it."""

import sys

from rcon_core.cli.main import main

if __name__ == "__main__":
    sys.exit(main())
