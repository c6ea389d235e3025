"""``BridgeClient``: one rosbridge v2 connection, shared by many nodes, on one asyncio loop.

The client is the connection: connect, reconnect, auth, ping, stall watch and the writer task.  What the
protocol is about is the sans-I/O :class:`~rcon_core.bridge.session.Session` (``client.session``); its async
side, :class:`~rcon_core.bridge.shell.SessionShell` (``client.shell``: writing its outbox, futures, tasks), is
attached to each fresh link; messages come in through ``receive.py`` to ``inbound.py``, frames go out through
the link (``transport.py``, over ``pwlink.py`` or ``wslink.py``).  Where each behaviour is decided:

* reconnect, state, latency and stall detection: here (and ``freshness.py``, ``reasons.py``, ``secure.py``);
* the transport, direct writes and command freshness on the wire: ``transport.py`` (adapters ``pwlink.py``,
  ``wslink.py``); messages in, in order, sharing the loop: ``receive.py``;
* the hot path, big frames, fragments, png and bad input from the server: ``inbound.py``,
  ``offload.py``, ``safety.py``;
* restore after a reconnect, publishing while down, service calls: ``session.py``; shared subscriptions:
  ``topics.py``, ``subscribe.py``; services this client provides: ``services.py``; ROS 2 action goals:
  ``goals.py``; actions this client provides: ``action_server.py``;
* the safety envelope every motion command is held to (``client.envelope``): ``envelope.py``, applied in
  ``Session.publish``;
* ROS 1 or ROS 2: ``rosinfo.py`` (``detect_ros()``, once per connection), ``params.py`` (``client.params``),
  ``cdrdecode.py``; which rosapi calls may be sent at all: ``rosapi_guard.py`` (checked here, in
  :meth:`BridgeClient.call_service`, for every caller: widgets, the CLI, discovery, type lookups).

Test hooks (public, documented): ``client.session`` (``topics``, ``pending``, ``outbox``...), ``client.shell``,
``client.inbound`` (``inbound.fragments``), ``client.link`` (the current ``transport.Link`` or None: ``queued``,
``buffered()``, ``socket``, ``name``), ``client.transport`` (``picows`` or ``websockets``).

Reconnect
    One attempt at a time through the chosen transport (``transport.open_link``: picows or websockets, see
    ``transport.py``), with our own ``_delays``: capped exponential backoff (``backoff_min`` doubling up to
    ``backoff_max``) with full jitter.  After every
    (re)connect the client sends, in order: ``auth`` (when configured), ``set_level`` (when set), every
    advertisement, every advertised service and action, then every subscription -- rosbridge forgets all
    of them with the connection (``reconnect.jsonl:8``; ``session.py``).  TLS certificate errors and a refused
    ``auth`` are fatal rather than retried.  Each failed attempt is put in words by ``reasons.describe``; ``client.failure`` holds
    the last one and failure listeners get it, with the time of the next attempt (``retry_at``).

State
    CONNECTING (first attempt) -> CONNECTED -> RECONNECTING (link lost, retrying) -> CONNECTED ...;
    CLOSED after ``close()`` or a fatal error.  Listeners get ``fn(state)`` on the loop thread.
    CONNECTED <-> DEGRADED while the socket is open but the link is stalled (``freshness.py``): DEGRADED is
    a state of its own so every listener sees it and treats it as "not usable" (the app shows it, widgets
    mark their values link-down, teleop stops), while ``client.connected`` -- "a socket is open" -- stays
    True and nothing is restored when the link recovers.

Latency and stall detection
    With ``stall_timeout`` (1 s, the default) a WebSocket ping goes out every ``stall_timeout / 4`` while
    none is in flight; a ping unanswered for ``stall_timeout`` (or a write buffer not draining as long) is
    DEGRADED, and when commands written since the last answered ping are unconfirmed the link is cut with
    a TCP reset so they are never delivered late (``freshness.py``).  ``stall_timeout=None``: a ping every
    ``latency_interval`` (2 s) only.  ``client.latency`` is the ping/pong round trip.  It needs no rosapi and
    works on any server; a pong missing for ``pong_timeout`` seconds drops the link (then it reconnects).

Frames and messages above the hard ``max_frame_size`` (by default twice ``max_size``) make the transport
close the link (1009), which then reconnects.
"""

from __future__ import annotations

import asyncio
import enum
import inspect
import logging
import random
import ssl
import time
from collections.abc import Callable, Generator
from typing import Any

from . import rosapi_guard
from .action_server import ProvidedActions
from .envelope import Envelope
from .errors import AuthRefusedError, LinkClosedError, NotConnectedError, RosapiRefusedError, ServiceError
from .freshness import LinkEvent, LinkWatch, watch_link
from .guard import LinkGuard
from .inbound import BadFrames, Inbound
from .linkbase import Link
from .nodes import Node
from .params import Params
from .protocol import encode
from .reasons import Failure, describe, refused_auth
from .receive import Receiver
from .rosinfo import RosInfo
from .rosinfo import detect as detect_ros
from .safety import without_traceback
from .secure import ssl_context
from .session import LOG_LEVELS, Session
from .shell import SessionShell, later
from .stats import BridgeStats
from .traffic import Traffic
from .transport import choose, open_link

log = logging.getLogger(__name__)

_monotonic = time.monotonic
AUTH_FIELDS = ("mac", "client", "dest", "rand", "t", "level", "end")
__all__ = ["BridgeClient", "ConnectionState", "LOG_LEVELS"]


class ConnectionState(enum.Enum):
    CONNECTING = "connecting"
    CONNECTED = "connected"
    DEGRADED = "degraded"
    RECONNECTING = "reconnecting"
    CLOSED = "closed"


def _check_auth(auth: dict[str, Any]) -> dict[str, Any]:
    if not isinstance(auth, dict):
        raise TypeError(f"auth must be a dict of rosauth fields, got {type(auth).__name__}")
    missing = [f for f in AUTH_FIELDS if f not in auth]
    if missing:
        raise ValueError(f"auth is missing rosauth field(s): {', '.join(missing)}")
    return {"op": "auth", **{f: auth[f] for f in AUTH_FIELDS}}


class _Unguarded:
    """The client's calls without the rosapi guard: what ``detect_ros`` itself asks (``rosinfo.detect``)."""

    def __init__(self, client: BridgeClient) -> None:
        self.call_timeout = client.call_timeout
        self._shell = client.shell

    async def call_service(self, name: str, args: dict[str, Any] | list | None = None,
                           timeout: float | None = None) -> Any:
        return await self._shell.call_service(name, args, timeout)


class BridgeClient:
    """A rosbridge v2 client.  Create, ``await connect()``, then hand out ``node(label)`` to consumers.
    One of the two implementations of ``rcon_core.link.RobotLink``."""

    protocol = "rosbridge"

    def __init__(self, url: str, *, reconnect: bool = True, ca_file: str | None = None,
                 auth: dict[str, Any] | Callable[[], Any] | None = None, call_timeout: float = 10.0,
                 registry: Any = None, typed_arrays: str = "list", backoff_min: float = 0.25,
                 backoff_max: float = 10.0, latency_interval: float = 2.0, pong_timeout: float = 10.0,
                 open_timeout: float = 10.0, max_size: int = 32 << 20, max_message_size: int | None = None,
                 max_frame_size: int | None = None, fragment_timeout: float = 10.0, big_frame: int = 1 << 20,
                 stall_timeout: float | None = 1.0, client_cert: str | None = None,
                 client_key: str | None = None, max_decoded: int | None = None,
                 transport: str | None = None) -> None:
        if not isinstance(url, str) or not url.startswith(("ws://", "wss://")):
            raise ValueError(f"url must start with ws:// or wss://, got {url!r}")
        if typed_arrays not in ("list", "numpy"):
            raise ValueError("typed_arrays must be 'list' or 'numpy'")
        if isinstance(auth, dict):
            _check_auth(auth)
        self.url = url
        #: the WebSocket library carrying the link: ``picows`` or ``websockets`` (``transport.choose``)
        self.transport = choose(transport)
        self.reconnect = reconnect
        self.ca_file = ca_file
        self.client_cert, self.client_key = client_cert, client_key
        self.auth = auth
        self.call_timeout = call_timeout
        self.registry = registry
        self.typed_arrays = typed_arrays
        self.backoff_min = backoff_min
        self.backoff_max = backoff_max
        self.latency_interval = latency_interval
        self.pong_timeout = pong_timeout
        self.open_timeout = open_timeout
        #: the largest frame the client accepts (``max_message_size`` is the older name of the same limit)
        self.max_size = self.max_message_size = max_size if max_message_size is None else max_message_size
        self.max_frame_size = max_frame_size or max(2 * self.max_message_size, self.max_message_size + (1 << 20))
        self.big_frame = min(big_frame, self.max_message_size)
        #: the bytes of Python objects one (big) frame may decode to; a frame over it is refused (offload.py)
        self.max_decoded = 4 * self.max_message_size if max_decoded is None else max_decoded
        self.stall_timeout = stall_timeout
        self.latency: float | None = None
        self.last_error: BaseException | None = None
        self.failure: Failure | None = None
        self._failure_listeners: list[Callable[[Failure], None]] = []
        #: what the client counts (``stats.py``)
        self.stats = BridgeStats()
        self._state = ConnectionState.CLOSED
        self._state_listeners: list[Callable[[ConnectionState], None]] = []
        #: the current connection (None while down); see ``linkbase.py``
        self.link: Link | None = None
        self._task: asyncio.Task[None] | None = None
        self._connected = asyncio.Event()
        self._closing = False
        from .rosapi import Rosapi

        self.rosapi = Rosapi(self)
        self.ros_info: RosInfo | None = None  # set by detect_ros(); see rosinfo.py
        self._info_link: Link | None = None  # the connection ros_info was learned on
        self._detecting: dict[bool, asyncio.Future[RosInfo]] = {}  # quick / full detection in flight
        self._profile: RosInfo | None = None  # the quick one (rosapi listing + get_ros_version)
        self._profile_link: Link | None = None
        self.params = Params(self)  # ROS 1 and ROS 2 parameters; see params.py
        bad = BadFrames(url, self.stats)
        self.session = Session(self, bad, schedule=later)  # the protocol state, sans-I/O (session.py)
        self.shell = SessionShell(self.session, self)  # its async side (shell.py)
        #: frames in (``inbound.py``)
        self.inbound = Inbound(self.session, bad, self.stats, typed_arrays=typed_arrays,
                               max_size=self.max_message_size, big_frame=self.big_frame,
                               fragment_timeout=fragment_timeout, max_decoded=self.max_decoded)

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
        return self.session.guard

    @property
    def traffic(self) -> Traffic:
        """Bytes received by topic since this client was made (``traffic.py``; any thread may snapshot it)."""
        return self.inbound.traffic

    @property
    def catalog(self) -> Any:
        """The robot-link catalogue (``rcon_core.link.Catalog``): on rosbridge, rosapi (``client.rosapi``)."""
        return self.rosapi

    def describe(self) -> dict[str, Any]:
        """Which protocol and server (the robot-link interface; ``rcon info`` adds what rosapi tells)."""
        info = self.ros_info
        return {"protocol": "rosbridge", "server": "rosbridge", "ros": info.version if info else None,
                "rosapi_services": list(info.rosapi_services) if info else [], "cannot": []}

    @property
    def provided_actions(self) -> ProvidedActions:
        """Actions this client serves (``node.advertise_action``; see ``action_server.py``)."""
        return self.session.provided_actions

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

    @property
    def ros_version(self) -> int | None:
        """1 or 2 once ``detect_ros()`` found out (or ``ros_info`` was set), else None."""
        return self.ros_info.version if self.ros_info is not None else None

    async def detect_ros(self, refresh: bool = False) -> RosInfo:
        """Which ROS the server runs and which rosapi services it lists: asked once per connection (the
        server behind a URL may have been restarted with another release) and by one caller at a time;
        ``refresh`` asks again.  See ``rosinfo.py``."""
        if self.ros_info is not None and not refresh and (self.link is None or self._info_link is self.link):
            return self.ros_info
        profile = None if refresh else await self.rosapi_profile()
        if profile is not None and profile.version is not None:
            info = profile
        else:
            info = await self._detect(quick=False)
        self.ros_info, self._info_link = info, self._profile_link if info is profile else self.link
        return info

    async def rosapi_profile(self) -> RosInfo:
        """The rosapi services the server lists and, where rosapi 2.x tells, its ROS and distro: asked once
        per connection (``rosinfo.detect(quick=True)``); what ``rosapi_guard`` and ``rosapi.py`` go by."""
        if self.ros_info is not None and self._info_link is self.link and self.link is not None:
            return self.ros_info
        if self._profile is not None and (self.link is None or self._profile_link is self.link):
            return self._profile
        link = self.link
        info = await self._detect(quick=True)
        self._profile, self._profile_link = info, link
        return info

    async def _detect(self, quick: bool) -> RosInfo:
        """One detection at a time per kind; concurrent callers share it."""
        running = self._detecting.get(quick)
        if running is not None and not running.done():
            return await asyncio.shield(running)
        future: asyncio.Future[RosInfo] = asyncio.get_running_loop().create_future()
        self._detecting[quick] = future
        try:
            info = await detect_ros(_Unguarded(self), quick=quick)
        except BaseException as exc:
            future.set_exception(exc)
            future.exception()
            raise
        future.set_result(info)
        return info

    def add_state_listener(self, fn: Callable[[ConnectionState], None]) -> Callable[[], None]:
        """Call ``fn(state)`` on every change; returns a function that removes the listener."""
        self._state_listeners.append(fn)
        return lambda: self._state_listeners.remove(fn) if fn in self._state_listeners else None

    def add_status_listener(self, fn: Callable[[dict[str, Any]], None]) -> Callable[[], None]:
        """Call ``fn(frame)`` for each ``status`` op the server sends (``level``, ``msg``, ``id``)."""
        return self.session.add_status_listener(fn)

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

    def _why(self, exc: BaseException) -> Failure:
        without_cert = self.url.startswith("wss:") and not self.client_cert
        return describe(exc, ca_file=self.ca_file, wss_without_cert=without_cert)

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

    # ================================================================== the protocol, by the session

    async def call_service(self, name: str, args: dict[str, Any] | list | None = None,
                           timeout: float | None = None) -> Any:
        """Call a service; returns its ``values``.  Raises ServiceError / ServiceTimeoutError (see
        ``session.py``), and RosapiRefusedError, without sending anything, for a rosapi call that would
        kill the server's rosapi (``rosapi_guard.py``)."""
        if rosapi_guard.rosapi_name(name) is not None:
            await self._check_rosapi_call(name, args, timeout)
        return await self.shell.call_service(name, args, timeout)

    async def _check_rosapi_call(self, name: str, args: Any, timeout: float | None) -> None:
        """Refuse a rosapi call the server's release cannot survive (``rosapi_guard.refusal``); a lookup
        the judgement needs (is the node listed? has a listed service that type?) is made only when the
        arguments alone do not settle it."""
        info = await self.rosapi_profile()
        reason = rosapi_guard.refusal(name, args, info)
        need = rosapi_guard.needs(name, info)
        what = args.get("node" if need == "node" else "type") if isinstance(args, dict) else None
        if reason is None and need is not None and isinstance(what, str):
            try:
                if need == "node":
                    found = await self.shell.call_service("/rosapi/nodes", {}, timeout)
                    listed = what in (found or {}).get("nodes", [])
                else:
                    found = await self.shell.call_service("/rosapi/services_for_type", {"type": what}, timeout)
                    listed = bool((found or {}).get("services"))
            except ServiceError as exc:
                raise RosapiRefusedError(f"not sent: could not check it is safe for this rosapi ({exc.message})",
                                         name) from None
            reason = rosapi_guard.refusal(name, args, info, node_listed=listed, type_listed=listed)
        if reason is not None:
            log.info("not sending %s to %s: %s", name, self.url, reason)
            raise RosapiRefusedError(f"not sent: {reason}", name)

    async def typedefs(self, type_name: str) -> list[dict[str, Any]]:
        """rosapi typedefs of a message type, from the server (cached), else from the local registry."""
        return await self.session.subscriber.typedefs(type_name)

    def set_level(self, level: str) -> None:
        """Ask the server for ``status`` messages at ``level`` (info, warning, error, none); kept across
        reconnects."""
        self.session.set_level(level)

    async def wait_connected(self) -> None:
        """Return once a link is open and restored (after ``auth``); raises NotConnectedError when the client
        is not trying to connect."""
        if self._connected.is_set():
            return
        if self._task is None or self._task.done():
            raise NotConnectedError(f"not connected to {self.url}")
        await self._connected.wait()

    # ================================================================== connecting

    def _ssl_context(self) -> ssl.SSLContext | None:
        if not self.url.startswith("wss://"):
            return None
        return ssl_context(self.ca_file, self.client_cert, self.client_key)

    def _delays(self) -> Generator[float]:
        delay = self.backoff_min
        while True:
            wait = random.uniform(self.backoff_min / 2, delay)  # jitter
            if self.last_error is not None:  # drawn right after a failed attempt: say why, and when next
                self._report(self._why(self.last_error).retrying(wait))
            yield wait
            delay = min(delay * 2, self.backoff_max)

    async def _open(self) -> Link:
        """One connection attempt with the chosen transport (``transport.open_link``)."""
        receiver = Receiver(self.inbound)
        link = await open_link(self.transport, self.url, receiver, self.session.stale_in_queue,
                               ssl=self._ssl_context(), open_timeout=self.open_timeout, max_size=self.max_frame_size)
        link.receiver = receiver
        return link

    async def connect(self, timeout: float | None = None) -> None:
        """Connect; returns once connected.  With ``reconnect=False`` the first failure is raised; with
        reconnect it keeps trying (until ``timeout``, then ``TimeoutError``) unless the error is fatal."""
        if self.link is not None:
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
        if self.link is not None:
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
            await link.close()
        if task is not None and not task.done():
            task.cancel()
        if task is not None:
            try:
                await task
            except (asyncio.CancelledError, Exception):
                pass
        self.shell.cancel_tasks()
        self.inbound.close()
        self._set_state(ConnectionState.CLOSED)

    async def __aenter__(self) -> BridgeClient:
        await self.connect()
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.close()

    async def _run(self) -> None:
        """Connect, serve, reconnect: a failed attempt is retried after ``_delays()`` unless it is fatal
        (``reasons.describe``); a lost link is reconnected after a short random pause."""
        delays: Generator[float] | None = None
        try:
            while True:
                try:
                    link = await self._open()
                except Exception as exc:
                    self.last_error = exc
                    if describe(exc).fatal:
                        raise  # retrying cannot fix a certificate problem, a bad URL...
                    if self._state is not ConnectionState.CLOSED:
                        log.info("connecting to %s failed: %s", self.url, exc)
                    delays = delays or self._delays()
                    await asyncio.sleep(next(delays))
                    continue
                delays = None
                opened = time.monotonic()
                await self._serve_once(link, final=False)
                if self._closing:
                    break
                if refused_auth(link.close_code, link.close_reason, auth_sent=self.auth is not None,
                                seconds_open=time.monotonic() - opened):
                    raise AuthRefusedError(f"{self.url} closed the link after the auth op")
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
        self.link = link
        receiver: Receiver = link.receiver
        self.inbound.waiting = receiver.waiting
        self.stats.connects += 1
        writer = asyncio.create_task(link.run_writer())
        pinger = asyncio.create_task(self._pinger(link))
        try:
            await self._send_auth(link)
            self.shell.attached(link)
            self._connected.set()
            self._set_state(ConnectionState.CONNECTED)
            await link.wait_closed()
            closed = link.closed_error()
            # kept without its traceback: the frames it holds keep the dead connection's buffers alive
            self.last_error = without_traceback(closed) if closed is not None else None
            if receiver.task is not None:  # messages that arrived before the close are still delivered
                await asyncio.shield(receiver.task)
        finally:
            receiver.cancel()
            self.link = None
            self._connected.clear()
            writer.cancel()
            pinger.cancel()
            self.inbound.disconnected()
            self.inbound.waiting = None
            self.shell.detached(link)
            link.release()  # its buffers go now, not at the collector's next full pass (wslink.py)
            if final:
                self._set_state(ConnectionState.CLOSED)
        if not self._closing:
            log.warning("connection to %s lost (%s)", self.url, link.close_reason or link.close_code or "no close frame")

    async def _send_auth(self, link: Link) -> None:
        """The ``auth`` op first on a fresh connection (when configured); the session restores the rest."""
        if self.auth is not None:
            auth = self.auth() if callable(self.auth) else self.auth
            if inspect.isawaitable(auth):
                auth = await auth
            link.write(encode(_check_auth(auth)))

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
