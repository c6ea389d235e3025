"""The embedded simulated robot: a rosbridge v2 server (``websockets``) around a Kingfisher-like vessel.

``SimServer`` is the entry point; see docs/architecture.md for the contract. No Qt here.
"""

from .server import SimServer
from .vessel import Vessel

__all__ = ["SimServer", "Vessel"]
