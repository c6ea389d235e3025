"""Which protocol a robot's URL speaks, found on the bridge thread and handed to the GUI thread.

The app connects to a URL without asking the operator which protocol.  ``RobotConnection.connect_to`` starts a
rosbridge client at once (the connection bar shows its attempts and failures as always) while
:class:`ProtocolFinder` makes the one handshake of ``rcon_core.link.detect`` on the bridge thread (retrying
quietly with backoff while the robot is not up), keeps the answer per URL, and wakes the GUI thread (a posted event, :class:`~rcon_core.app.frame_clock.Waker`),
which then switches to a Foxglove client when the robot picked a Foxglove subprotocol (the rosbridge client
never connected: such a server refuses a handshake without it); a user of ``RobotConnection`` without a running Qt
loop gets it at its next look at ``link.client`` (:meth:`ProtocolFinder.take`, on the thread that called
``connect_to`` only).  The GUI never waits on the network.
``--protocol`` (``RobotConnection.protocol``) skips the question; so does a URL whose answer is known.
"""

from __future__ import annotations

import asyncio
import logging
import random
import threading
import weakref
from collections.abc import Callable
from typing import Any

from rcon_core.bridge.reasons import describe

log = logging.getLogger(__name__)

#: backoff between handshakes while the robot does not answer (s)
BACKOFF = (0.25, 5.0)


#: the finders the GUI wake delivers to (weak: a finder goes with its RobotConnection)
_FINDERS: weakref.WeakSet[ProtocolFinder] = weakref.WeakSet()
_WAKER: Any = None


def _deliver_all(_keys: set[str]) -> None:
    for finder in list(_FINDERS):
        finder._deliver()


def _gui_waker() -> Any:
    """The one wake of the process, made on the GUI thread and owned by the application (parented to it:
    never deleted by Python's collector from another thread while an event is posted to it); None without a
    Qt application (a headless user of ``RobotConnection``)."""
    global _WAKER
    if _WAKER is None:
        from qtpy import QtCore

        app = QtCore.QCoreApplication.instance()
        if app is None:
            return None
        from rcon_core.app.frame_clock import Waker

        _WAKER = Waker(_deliver_all, app, min_gap=0.0)
    return _WAKER


class ProtocolFinder:
    """Finds each URL's protocol once (see the module docstring)."""

    def __init__(self, thread: Any) -> None:
        self.thread = thread
        #: url -> "rosbridge" or "foxglove" (a restarted robot may change: forgotten on a fatal failure)
        self.known: dict[str, str] = {}
        self._lock = threading.Lock()
        self._ready: list[tuple[int, str, Any]] = []
        self._waker: Any = None
        self._adopt: Callable[[int, str, Any], None] | None = None
        self._owner = 0  # the thread that asked (the GUI thread): clients start there

    def find(self, url: str, options: dict[str, Any], gen: int, current: Callable[[], int],
             adopt: Callable[[int, str, Any], None], settings: Any) -> None:
        """Start finding ``url``'s protocol; ``adopt(gen, protocol, settings)`` runs on the GUI thread once
        known, unless ``current()`` moved past ``gen`` (another URL, a disconnect) meanwhile."""
        self._adopt = adopt
        self._owner = threading.get_ident()
        if self._waker is None:
            self._waker = _gui_waker()
            if self._waker is not None:
                _FINDERS.add(self)
        self.thread.run(self._find(url, options, gen, current, settings))

    async def _find(self, url: str, options: dict[str, Any], gen: int, current: Callable[[], int],
                    settings: Any) -> None:
        from rcon_core.link import detect

        delay = BACKOFF[0]
        while current() == gen:
            try:
                protocol = await detect(url, ca_file=options.get("ca_file"), client_cert=options.get("client_cert"),
                                        client_key=options.get("client_key"))
            except asyncio.CancelledError:
                raise
            except Exception as exc:  # the rosbridge client started meanwhile says why, in words
                if current() != gen or describe(exc).fatal:
                    return
                wait = random.uniform(BACKOFF[0] / 2, delay)
                await asyncio.sleep(wait)
                delay = min(delay * 2, BACKOFF[1])
                continue
            self.known[url] = protocol
            if protocol == "rosbridge":
                with self._lock:
                    self._ready.append((gen, protocol, settings))  # taken on the next look: nothing to switch
                return
            with self._lock:
                self._ready.append((gen, protocol, settings))
            if self._waker is not None:
                self._waker.poke()
            return

    def take(self) -> None:
        """Without a Qt application (no wake can be posted): start the client of a protocol found meanwhile,
        on the thread that called ``find`` only.  With one, only the wake does (never in the middle of
        whatever code happened to look at ``link.client``)."""
        if self._waker is None and threading.get_ident() == self._owner and self._ready:
            self._deliver()

    def _deliver(self) -> None:
        if threading.get_ident() != self._owner:
            return
        with self._lock:
            ready, self._ready = self._ready, []
        for gen, protocol, settings in ready:
            if self._adopt is not None:
                try:
                    self._adopt(gen, protocol, settings)
                except Exception:
                    log.exception("starting the %s link failed", protocol)
