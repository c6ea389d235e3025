"""The robot link, protocol-neutral: the :class:`RobotLink` interface (``iface.py``), the reconnecting
connection both implementations are built on (``connection.py``: :class:`ConnectionShell` and
:class:`ConnectionState`) and choosing the implementation for a URL (``detect.py``: rosbridge or Foxglove, by
subprotocol).  No Qt.

Import order: ``rcon_core.bridge`` first.  ``bridge/client.py`` builds on ``connection.py``, which uses the
bridge's own parts (``reasons.py``, ``freshness.py``, the transport); with the bridge package imported first,
``connection.py`` is imported whole while the bridge imports its client, whichever module a program imports
first (``tests/test_link_connection.py`` imports each alone in a fresh interpreter)."""

import rcon_core.bridge  # noqa: F401  (first: see the docstring)

from .connection import ConnectionShell, ConnectionState
from .detect import check_protocol, detect, make_client, open_client
from .iface import PROTOCOLS, Catalog, Parameters, RobotLink

__all__ = ["PROTOCOLS", "Catalog", "ConnectionShell", "ConnectionState", "Parameters", "RobotLink",
           "check_protocol", "detect", "make_client", "open_client"]
