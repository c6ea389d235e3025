"""The robot link, protocol-neutral: the :class:`RobotLink` interface (``iface.py``) and choosing its
implementation for a URL (``detect.py``: rosbridge or Foxglove, by subprotocol).  No Qt."""

from .detect import check_protocol, detect, make_client, open_client
from .iface import PROTOCOLS, Catalog, Parameters, RobotLink

__all__ = ["PROTOCOLS", "Catalog", "Parameters", "RobotLink", "check_protocol", "detect", "make_client",
           "open_client"]
