"""``ConnectionShell``: the reconnecting connection every robot link is built on, whatever its protocol.

``BridgeClient`` (rosbridge, ``rcon_core/bridge/client.py``) and ``FoxgloveClient`` (the Foxglove WebSocket
protocol, ``rcon_core/foxglove/client.py``) are subclasses: this module connects, reconnects, watches the
link, reports its state and its failures and closes; the subclass says what one protocol does on a fresh
link and when it goes (the hooks below).  A third protocol gets reconnect, backoff, the stall watch, state
and failure reporting, TLS and close from here.  All of it runs on one asyncio loop; listeners are called
on that loop's thread.

Reconnect
    One attempt at a time through the chosen transport (``rcon_core/bridge/transport.py``: picows where it
    imports, else websockets; ``transport=`` or ``RCON_TRANSPORT``), offering the protocol's WebSocket
    subprotocols (none for rosbridge).  Failed attempts in a row wait a capped exponential backoff with
    full jitter (:func:`backoff`: the n-th waits between ``backoff_min / 2`` and ``backoff_min * 2**(n-1)``,
    at most ``backoff_max``); a link that was up and is lost is reopened after a random pause shorter than
    ``backoff_min`` (never a tight reconnect loop), and the backoff starts again from ``backoff_min``.  Each
    failed attempt is put in words by ``rcon_core.bridge.reasons.describe`` (a protocol may word its own
    errors: :meth:`ConnectionShell._why`); ``client.failure`` holds the last one and failure listeners get
    it, with the time of the next attempt (``retry_at``).  A fatal failure -- a TLS certificate the client
    does not trust, a URL the library cannot use, what the protocol adds (a refused ``auth`` on rosbridge,
    a server that is not a Foxglove server) -- is not retried: the client gives up and goes CLOSED.  With
    ``reconnect=False`` the first failure is raised by ``connect()`` and a lost link is not reopened.

State
    CONNECTING (the first attempt of a ``connect()``) -> CONNECTED -> RECONNECTING (link lost, retrying)
    -> CONNECTED ...; CLOSED after ``close()`` or a fatal error.  When a fresh link counts as CONNECTED is
    the protocol's (rosbridge: once ``auth`` is written; Foxglove: once ``serverInfo`` arrived): it calls
    :meth:`ConnectionShell._up`.  CONNECTED <-> DEGRADED while the socket is open but the link is stalled:
    DEGRADED is a state of its own so every listener sees it and treats it as "not usable" (the app shows
    it, widgets mark their values link-down, teleop stops, a command is refused at once), while
    ``client.connected`` -- "a socket is open" -- stays True and nothing is restored when the link
    recovers.  Listeners get ``fn(state)`` once per change; one that raises is logged and the others are
    still called.

Latency and stall detection (``rcon_core/bridge/freshness.py``)
    With ``stall_timeout`` (1 s, the default) a WebSocket ping goes out every ``stall_timeout / 4`` while
    none is in flight; a ping unanswered for ``stall_timeout`` (or a write buffer not draining as long) is
    DEGRADED, and when commands written since the last answered ping are unconfirmed the link is cut with
    a TCP reset so they are never delivered late.  ``stall_timeout=None``: a ping every
    ``latency_interval`` (2 s) only.  ``client.latency`` is the ping/pong round trip.  It needs nothing of
    the protocol and works on any server; a pong missing for ``pong_timeout`` seconds drops the link (then
    it reconnects).

The end of a link
    Messages that arrived before the close are still delivered; then the receiver, the writer and the
    pinger stop, the protocol is told (:meth:`ConnectionShell._link_down`) and the link is released: its
    buffers go by reference counting now, not at the collector's next full pass (the app freezes
    long-lived objects: ``rcon_core/gcpolicy.py``).  The error it ended with is kept in ``last_error``
    without its traceback, whose frames would hold the dead connection
    (``tests/test_bridge_reconnect_memory.py``).

TLS
    A ``wss://`` URL is opened with ``rcon_core.bridge.secure.ssl_context(ca_file, client_cert,
    client_key)``; on a ``wss://`` URL without a client certificate, a connection closed during the
    handshake says the robot may ask for one.

Close
    ``close()`` stops reconnecting, closes the link (its close handshake, bounded in time), waits for the
    run loop to end, lets the protocol drop its tasks (:meth:`ConnectionShell._closed`) and says CLOSED.
    It is a coroutine on the link's loop; another thread runs it there (``BridgeThread.run``).  Nodes stay
    usable for a later ``connect()``.

What a protocol supplies
    ``session`` (its protocol state: ``guard``, ``envelope``, ``nodes`` and ``stale_in_queue(pub)``, the
    count of a queued command dropped at its deadline), ``call_service`` (what a node's calls reach),
    :meth:`~ConnectionShell._receiver` (what a link's messages go to), :meth:`~ConnectionShell._link_up`
    and :meth:`~ConnectionShell._link_down` (a link comes and goes), and where it needs them
    :meth:`~ConnectionShell._open` (a check of the fresh link), :meth:`~ConnectionShell._why`,
    :meth:`~ConnectionShell._check_end` (a lost link that must not be reopened) and
    :meth:`~ConnectionShell._closed`.  ``tests/test_link_connection.py`` builds a third protocol this way.
"""

from __future__ import annotations

import asyncio
import enum
import logging
import random
import ssl
import time
from collections.abc import Callable, Generator
from typing import Any, Protocol, Self

from rcon_core.bridge.envelope import Envelope
from rcon_core.bridge.errors import LinkClosedError, NotConnectedError
from rcon_core.bridge.freshness import LinkEvent, LinkWatch, watch_link
from rcon_core.bridge.guard import LinkGuard
from rcon_core.bridge.linkbase import Link
from rcon_core.bridge.nodes import Node
from rcon_core.bridge.reasons import Failure, describe
from rcon_core.bridge.safety import safe_text, without_traceback
from rcon_core.bridge.secure import ssl_context
from rcon_core.bridge.stats import BridgeStats
from rcon_core.bridge.transport import choose, open_link

log = logging.getLogger(__name__)

_monotonic = time.monotonic
__all__ = ["ConnectionShell", "ConnectionState", "LinkSession", "backoff"]


class ConnectionState(enum.Enum):
    CONNECTING = "connecting"
    CONNECTED = "connected"
    DEGRADED = "degraded"
    RECONNECTING = "reconnecting"
    CLOSED = "closed"


class LinkSession(Protocol):
    """What the shell reads of a protocol's state (``bridge.session.Session``, ``foxglove.FoxgloveSession``)."""

    guard: Any  # a LinkGuard
    envelope: Envelope | None
    nodes: dict[str, Node]

    def stale_in_queue(self, pub: Any) -> None: ...


def backoff(least: float, most: float, uniform: Callable[[float, float], float] = random.uniform
            ) -> Generator[float]:
    """The waits after failed attempts in a row: the n-th between ``least / 2`` and ``least * 2**(n-1)``,
    capped at ``most`` (full jitter, drawn by ``uniform``)."""
    ceiling = least
    while True:
        yield uniform(least / 2, ceiling)
        ceiling = min(ceiling * 2, most)


class ConnectionShell:
    """One robot link's connection (see the module docstring); subclassed once per protocol."""

    protocol = ""
    #: the WebSocket subprotocols offered in the handshake (None: none)
    subprotocols: tuple[str, ...] | None = None
    session: LinkSession
    call_timeout: float

    def __init__(self, url: str, *, reconnect: bool = True, ca_file: str | None = None,
                 client_cert: str | None = None, client_key: str | None = None, backoff_min: float = 0.25,
                 backoff_max: float = 10.0, latency_interval: float = 2.0, pong_timeout: float = 10.0,
                 open_timeout: float = 10.0, stall_timeout: float | None = 1.0, max_frame_size: int = 64 << 20,
                 transport: str | None = None, stats: BridgeStats | None = None) -> None:
        if not isinstance(url, str) or not url.startswith(("ws://", "wss://")):
            raise ValueError(f"url must start with ws:// or wss://, got {url!r}")
        self.url = url
        #: the WebSocket library carrying the link: ``picows`` or ``websockets`` (``transport.choose``)
        self.transport = choose(transport)
        self.reconnect = reconnect
        self.ca_file, self.client_cert, self.client_key = ca_file, client_cert, client_key
        self.backoff_min, self.backoff_max = backoff_min, backoff_max
        self.latency_interval, self.pong_timeout = latency_interval, pong_timeout
        self.open_timeout = open_timeout
        self.stall_timeout = stall_timeout
        #: the largest frame (and message) the transport accepts; a larger one closes the link (1009)
        self.max_frame_size = max_frame_size
        #: what the client counts (``rcon_core/bridge/stats.py``)
        self.stats = BridgeStats() if stats is None else stats
        self.latency: float | None = None
        self.last_error: BaseException | None = None
        self.failure: Failure | None = None
        self._failure_listeners: list[Callable[[Failure], None]] = []
        self._state = ConnectionState.CLOSED
        self._state_listeners: list[Callable[[ConnectionState], None]] = []
        #: the current connection (None while down); see ``rcon_core/bridge/linkbase.py``
        self.link: Link | None = None
        self._task: asyncio.Task[None] | None = None
        self._connected = asyncio.Event()
        self._closing = False

    # ================================================================== state

    @property
    def state(self) -> ConnectionState:
        return self._state

    @property
    def connected(self) -> bool:
        return self.link is not None

    @property
    def guard(self) -> LinkGuard:
        """Whether this link is view-only (``guard.set_view_only(reason)``, any thread; see ``guard.py``)."""
        guard: LinkGuard = self.session.guard
        return guard

    @property
    def envelope(self) -> Envelope | None:
        """The robot's safety envelope: every motion command published through this client is held to it
        (clamped, or refused when not a number; see ``envelope.py``). None: no speed limit. Any thread may
        set it (one attribute; the loop reads it at each publish)."""
        return self.session.envelope

    @envelope.setter
    def envelope(self, value: Envelope | None) -> None:
        if value is not None and not isinstance(value, Envelope):
            raise TypeError(f"envelope must be an Envelope or None, not {type(value).__name__}")
        self.session.envelope = value

    def node(self, label: str) -> Node:
        """A new node; its id is ``label``, made unique with a ``#n`` suffix when already taken."""
        if not isinstance(label, str) or not label:
            raise ValueError("node label must be a non-empty string")
        nodes = self.session.nodes
        node_id, n = label, 1
        while node_id in nodes:
            n += 1
            node_id = f"{label}#{n}"
        node = nodes[node_id] = Node(self, node_id)
        return node

    def add_state_listener(self, fn: Callable[[ConnectionState], None]) -> Callable[[], None]:
        """Call ``fn(state)`` on every change; returns a function that removes the listener."""
        self._state_listeners.append(fn)
        return lambda: self._state_listeners.remove(fn) if fn in self._state_listeners else None

    def add_failure_listener(self, fn: Callable[[Failure], None]) -> Callable[[], None]:
        """Call ``fn(failure)`` (on the loop thread) for each failed attempt: why in words, whether it is
        fatal, and ``retry_at`` (``time.monotonic()``) of the next attempt; returns a remover."""
        self._failure_listeners.append(fn)
        return lambda: self._failure_listeners.remove(fn) if fn in self._failure_listeners else None

    def _report(self, failure: Failure) -> None:
        self.failure = failure
        for fn in list(self._failure_listeners):
            try:
                fn(failure)
            except Exception:
                log.exception("failure listener raised")

    def _set_state(self, state: ConnectionState) -> None:
        if state is self._state:
            return
        self._state = state
        if self.link is not None:
            self.link.degraded = state is ConnectionState.DEGRADED
        for fn in list(self._state_listeners):
            try:
                fn(state)
            except Exception:
                log.exception("state listener raised")

    def _up(self) -> None:
        """The protocol says the fresh link is usable: ``connect()`` and ``wait_connected()`` return, CONNECTED."""
        self._connected.set()
        self._set_state(ConnectionState.CONNECTED)

    async def wait_connected(self) -> None:
        """Return once a link is open and usable; raises NotConnectedError when the client is not trying to
        connect."""
        if self._connected.is_set():
            return
        if self._task is None or self._task.done():
            raise NotConnectedError(f"not connected to {self.url}")
        await self._connected.wait()

    # ================================================================== what a protocol supplies

    async def call_service(self, name: str, args: dict[str, Any] | list | None = None,
                           timeout: float | None = None) -> Any:
        """Call a service on the robot (what a node's ``call_service`` reaches)."""
        raise NotImplementedError

    def _receiver(self) -> Any:
        """A fresh receiver for one link's messages (``rcon_core/bridge/receive.py``'s interface)."""
        raise NotImplementedError

    async def _link_up(self, link: Link) -> None:
        """A fresh link is open (``self.link``; its writer and pinger run): attach the protocol to it; call
        :meth:`_up` once it is usable."""
        raise NotImplementedError

    def _link_down(self, link: Link) -> None:
        """The link is gone (receiver, writer and pinger stopped; not released yet): drop what it queued,
        fail what waited on it."""
        raise NotImplementedError

    def _check_end(self, link: Link, seconds_open: float) -> None:
        """A served link ended (not by ``close()``): raise to give up rather than reconnect (fatal)."""

    def _closed(self) -> None:
        """``close()``: the run loop has ended; drop the protocol's own tasks."""

    def _why(self, exc: BaseException) -> Failure:
        """One failed attempt in words (``reasons.describe``)."""
        without_cert = self.url.startswith("wss:") and not self.client_cert
        return describe(exc, ca_file=self.ca_file, wss_without_cert=without_cert)

    # ================================================================== connecting

    def _ssl_context(self) -> ssl.SSLContext | None:
        if not self.url.startswith("wss://"):
            return None
        return ssl_context(self.ca_file, self.client_cert, self.client_key)

    async def _open(self) -> Link:
        """One connection attempt with the chosen transport (``transport.open_link``)."""
        ctx = self._ssl_context()
        receiver = self._receiver()
        offered = list(self.subprotocols) if self.subprotocols is not None else None
        link = await open_link(self.transport, self.url, receiver, self.session.stale_in_queue, ssl=ctx,
                               open_timeout=self.open_timeout, max_size=self.max_frame_size, subprotocols=offered)
        link.receiver = receiver
        return link

    async def connect(self, timeout: float | None = None) -> None:
        """Connect; returns once connected.  With ``reconnect=False`` the first failure is raised; with
        reconnect it keeps trying (until ``timeout``, then ``TimeoutError``) unless the error is fatal."""
        if self._connected.is_set():
            return
        self._closing = False
        if self._task is None or self._task.done():
            self._set_state(ConnectionState.CONNECTING)
            if not self.reconnect:
                try:
                    link = await self._open()
                except BaseException as exc:
                    self.last_error = exc
                    if isinstance(exc, Exception):
                        self._report(self._why(exc))
                    self._set_state(ConnectionState.CLOSED)
                    raise
                self._task = asyncio.create_task(self._serve_once(link))
            else:
                self._task = asyncio.create_task(self._run())
        waiter = asyncio.ensure_future(self._connected.wait())
        try:
            await asyncio.wait({waiter, self._task}, timeout=timeout, return_when=asyncio.FIRST_COMPLETED)
        finally:
            waiter.cancel()
        if self._connected.is_set():
            return
        if self._task.done():
            error = self._task.exception() if not self._task.cancelled() else None
            raise error or NotConnectedError(f"could not connect to {self.url}")
        raise TimeoutError(f"not connected to {self.url} within {timeout} s (last error: {self.last_error})")

    async def close(self) -> None:
        """Close the connection and stop reconnecting.  Nodes stay usable for a later ``connect()``."""
        self._closing = True
        task, self._task = self._task, None
        link = self.link
        if link is not None:
            try:
                await link.close()
            except Exception as exc:  # closing goes on: the run loop is stopped below
                log.debug("closing the link to %s: %s", self.url, safe_text(exc))
        if task is not None and not task.done():
            task.cancel()
        if task is not None:
            try:
                await task
            except (asyncio.CancelledError, Exception):
                pass
        self._closed()
        self._set_state(ConnectionState.CLOSED)

    async def __aenter__(self) -> Self:
        await self.connect()
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.close()

    async def _run(self) -> None:
        """Connect, serve, reconnect: a failed attempt is retried after :func:`backoff` unless it is fatal
        (``_why``); a lost link is reopened after a short random pause unless ``_check_end`` raises."""
        delays: Generator[float] | None = None
        try:
            while not self._closing:
                try:
                    link = await self._open()
                except Exception as exc:
                    self.last_error = exc
                    failure = self._why(exc)
                    if failure.fatal:
                        raise  # retrying cannot fix a certificate problem, a bad URL...
                    if self._state is not ConnectionState.CLOSED:
                        log.info("connecting to %s failed: %s", self.url, exc)
                    delays = delays or backoff(self.backoff_min, self.backoff_max)
                    wait = next(delays)
                    self._report(failure.retrying(wait))  # say why, and when the next attempt is
                    await asyncio.sleep(wait)
                    continue
                delays = None
                opened = _monotonic()
                await self._serve_once(link, final=False)
                if self._closing:
                    break
                self._check_end(link, _monotonic() - opened)
                self._set_state(ConnectionState.RECONNECTING)
                await asyncio.sleep(random.uniform(0, self.backoff_min))  # never a tight reconnect loop
        except asyncio.CancelledError:
            raise
        except Exception as exc:
            self.last_error = exc
            self._report(self._why(exc))
            log.error("giving up on %s: %s", self.url, exc)
            raise
        finally:
            self._set_state(ConnectionState.CLOSED)

    async def _serve_once(self, link: Link, final: bool = True) -> None:
        """Serve one open link until it is gone (see "The end of a link")."""
        self.link = link
        receiver = link.receiver
        self.stats.connects += 1
        writer = asyncio.create_task(link.run_writer())
        pinger = asyncio.create_task(self._pinger(link))
        try:
            await self._link_up(link)
            await link.wait_closed()
            # kept without its traceback: the frames it holds keep the dead connection's buffers alive
            self.last_error = without_traceback(link.closed_error())
            if receiver.task is not None:  # messages that arrived before the close are still delivered
                await asyncio.shield(receiver.task)
        finally:
            receiver.cancel()
            self.link = None
            self._connected.clear()
            writer.cancel()
            pinger.cancel()
            self._link_down(link)
            link.release()  # its buffers go now, not at the collector's next full pass (linkbase.py)
            if final:
                self._set_state(ConnectionState.CLOSED)
        if not self._closing:
            log.warning("connection to %s lost (%s)", self.url,
                        (link.close_reason or str(link.close_code or "no close frame"))[:200])

    # ================================================================== ping and stall watch

    async def _pinger(self, link: Link) -> None:
        """Without stall detection (``stall_timeout=None``): a ping every ``latency_interval``; a pong
        missing for ``pong_timeout`` drops the link.  With it, ``freshness.watch_link``."""
        if self.stall_timeout is not None:
            probe_interval = min(self.latency_interval, self.stall_timeout / 4)
            link.watch = LinkWatch(self.stall_timeout, probe_interval, _monotonic())
            await watch_link(link, link.watch, self.pong_timeout, self._link_event)
            return
        try:
            while True:
                waiter = await link.ping()
                try:
                    self.latency = await asyncio.wait_for(waiter, self.pong_timeout)
                except TimeoutError:
                    log.warning("no pong from %s within %.0f s; dropping the link", self.url, self.pong_timeout)
                    link.abort()
                    return
                await asyncio.sleep(self.latency_interval)
        except LinkClosedError:
            pass

    def _link_event(self, event: LinkEvent, detail: Any) -> bool:
        """What the watchdog (``freshness.watch_link``) reports; True when a stall counts (CONNECTED)."""
        if event is LinkEvent.LATENCY:
            self.latency = detail
        elif event is LinkEvent.STALLED:
            if self._state is not ConnectionState.CONNECTED:
                return False
            self.stats.degraded += 1
            log.warning("link to %s is degraded: %s", self.url, detail)
            self._set_state(ConnectionState.DEGRADED)
        elif event is LinkEvent.RECOVERED:
            log.info("link to %s has recovered", self.url)
            if self._state is ConnectionState.DEGRADED:
                self._set_state(ConnectionState.CONNECTED)
        elif event is LinkEvent.CUT:
            self.stats.stall_cuts += 1
            log.warning("link to %s stalled (%s) with commands in flight; cut it so they are never delivered "
                        "late; reconnecting", self.url, detail)
        else:
            log.warning("%s from %s; dropping the link", detail, self.url)
        return True
