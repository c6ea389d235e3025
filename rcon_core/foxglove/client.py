"""``FoxgloveClient``: one Foxglove WebSocket connection, shared by many nodes, on one asyncio loop.

The async shell around :class:`~rcon_core.foxglove.session.FoxgloveSession` (the protocol state machine):
connect, reconnect, the stall watch, the read loop, futures and timeouts.  It offers the robot-link
interface (``rcon_core.link.RobotLink``) as ``BridgeClient`` does, so the app, the CLI, the canvas and the
widgets use either without knowing which (``client.protocol`` says).  The connection goes through the
WebSocket seam in ``ws.py``: the rosbridge link's transports (picows where it imports, else websockets;
``transport=`` or ``RCON_TRANSPORT`` picks one, as for ``BridgeClient``), messages pushed into a
``FoxgloveReceiver``.

Reconnect
    Capped exponential backoff with full jitter (``backoff_min`` doubling to ``backoff_max``), as the
    rosbridge link.  A server that picks none of the Foxglove subprotocols is not retried: it speaks
    something else (rosbridge) and the failure says so.  After every (re)connect the session restores
    subscriptions, client channels, parameter subscriptions and the graph subscription (``session.py``).

State
    CONNECTING -> CONNECTED (once ``serverInfo`` arrived) -> RECONNECTING -> CONNECTED ...; CLOSED after
    ``close()`` or a fatal error; CONNECTED <-> DEGRADED while the link is stalled (``freshness.py``: the
    same watch as the rosbridge link, WebSocket pings every ``stall_timeout / 4``, a cut when commands are
    unconfirmed).

Service calls
    Every call has a client-side budget (``timeout`` or ``call_timeout``).  A call made before the server
    advertised its services waits for them inside the budget; a service still not advertised
    :data:`SERVICES_GRACE` seconds after the link came up raises ``ServiceError`` naming it.  A
    ``serviceCallFailure`` raises ``ServiceError`` with the server's text; calls waiting when the link
    drops raise ``ConnectionLostError``.
"""

from __future__ import annotations

import asyncio
import logging
import random
import time
from collections.abc import Callable
from typing import Any

from rcon_core.bridge.client import ConnectionState
from rcon_core.bridge.envelope import Envelope
from rcon_core.bridge.errors import (
    BridgeError,
    ConnectionLostError,
    NotConnectedError,
    ServiceError,
    ServiceTimeoutError,
)
from rcon_core.bridge.freshness import LinkWatch, watch_link
from rcon_core.bridge.guard import LinkGuard, ViewOnlyError
from rcon_core.bridge.inbound import BadFrames
from rcon_core.bridge.nodes import Node
from rcon_core.bridge.reasons import Failure, describe
from rcon_core.bridge.rosinfo import RosInfo
from rcon_core.bridge.secure import ssl_context
from rcon_core.bridge.stats import FoxgloveStats

from . import wire
from .catalog import FoxgloveCatalog, FoxgloveParams
from .session import CANNOT, FoxgloveSession
from .ws import FoxgloveReceiver, Link, LinkClosedError, choose, open_connection

log = logging.getLogger(__name__)
_monotonic = time.monotonic
#: seconds after ``serverInfo`` within which the server's services are expected to be advertised
SERVICES_GRACE = 1.0


class NotFoxgloveError(BridgeError):
    """The server picked none of the Foxglove subprotocols (it speaks rosbridge, or nothing RCON knows)."""


class FoxgloveClient:
    """A Foxglove WebSocket protocol client.  Create, ``await connect()``, then ``node(label)``."""

    protocol = "foxglove"

    def __init__(self, url: str, *, reconnect: bool = True, ca_file: str | None = None,
                 client_cert: str | None = None, client_key: str | None = None, auth: Any = None,
                 call_timeout: float = 10.0, backoff_min: float = 0.25, backoff_max: float = 10.0,
                 latency_interval: float = 2.0, pong_timeout: float = 10.0, open_timeout: float = 10.0,
                 max_size: int = 64 << 20, stall_timeout: float | None = 1.0,
                 subprotocols: tuple[str, ...] = wire.SUBPROTOCOLS, transport: str | None = None,
                 **_ignored: Any) -> None:
        if not isinstance(url, str) or not url.startswith(("ws://", "wss://")):
            raise ValueError(f"url must start with ws:// or wss://, got {url!r}")
        self.url = url
        #: the WebSocket library carrying the link: ``picows`` or ``websockets`` (``transport.choose``)
        self.transport = choose(transport)
        self.reconnect = reconnect
        self.ca_file, self.client_cert, self.client_key = ca_file, client_cert, client_key
        #: a rosauth secret cannot be used on this protocol: kept, never sent, said in ``notices``
        self.auth = auth
        self.notices: list[str] = [CANNOT["rosauth"]] if auth is not None else []
        self.call_timeout = call_timeout
        self.backoff_min, self.backoff_max = backoff_min, backoff_max
        self.latency_interval, self.pong_timeout = latency_interval, pong_timeout
        self.open_timeout, self.max_size = open_timeout, max_size
        self.stall_timeout = stall_timeout
        self.subprotocols = tuple(subprotocols)
        self.subprotocol: str | None = None
        self.latency: float | None = None
        self.last_error: BaseException | None = None
        self.failure: Failure | None = None
        self.stats = FoxgloveStats()
        self._state = ConnectionState.CLOSED
        self._state_listeners: list[Callable[[ConnectionState], None]] = []
        self._failure_listeners: list[Callable[[Failure], None]] = []
        self.link: Link | None = None
        self._task: asyncio.Task[None] | None = None
        self._connected = asyncio.Event()
        self._up_at = 0.0
        self._closing = False
        self._services_changed: asyncio.Event | None = None
        self.bad = BadFrames(url, self.stats)
        #: the protocol state (``session.py``)
        self.session = FoxgloveSession(url, self.stats, self.bad)
        self.session.listeners.append(self._session_event)
        self.rosapi = self.catalog = FoxgloveCatalog(self)
        self.params = FoxgloveParams(self)
        self.level: str | None = None
        self.session.watch_graph()  # discovery: who publishes, subscribes, provides

    # ================================================================== the robot-link interface

    @property
    def state(self) -> ConnectionState:
        return self._state

    @property
    def connected(self) -> bool:
        return self.link is not None

    @property
    def guard(self) -> LinkGuard:
        return self.session.guard

    @property
    def envelope(self) -> Envelope | None:
        """The robot's safety envelope (``rcon_core/bridge/envelope.py``), as on the rosbridge link."""
        return self.session.envelope

    @envelope.setter
    def envelope(self, value: Envelope | None) -> None:
        if value is not None and not isinstance(value, Envelope):
            raise TypeError(f"envelope must be an Envelope or None, not {type(value).__name__}")
        self.session.envelope = value

    @property
    def registry(self) -> Any:
        """The types this link learned (ROS 2 schemas; ``session.codecs.ros1`` holds ROS 1 ones)."""
        return self.session.codecs.ros2

    @property
    def server_time(self) -> int | None:
        """The server's latest ``time`` (ns), or None when it sends none."""
        return self.session.time_ns

    @property
    def ros_version(self) -> int | None:
        return self.ros_info.version

    @property
    def ros_info(self) -> RosInfo:
        encodings = {c.schema_encoding for c in self.session.channels.values()}
        version = 2 if "ros2msg" in encodings or "ros2idl" in encodings else 1 if "ros1msg" in encodings else None
        return RosInfo(version, source="foxglove channel schemas")

    async def detect_ros(self, refresh: bool = False) -> RosInfo:
        """Which ROS the robot runs, from its channels' schema encodings (no rosapi on this protocol)."""
        return self.ros_info

    def describe(self) -> dict[str, Any]:
        """Which protocol and which server: ``rcon info`` and the connection bar show it."""
        server = self.session.server or {}
        return {"protocol": "foxglove", "subprotocol": self.subprotocol, "server": server.get("name") or "",
                "capabilities": self.session.capabilities, "encodings": self.session.encodings,
                "session_id": server.get("sessionId"), "metadata": server.get("metadata") or {},
                "cannot": [CANNOT["actions"]] + self.notices}

    def node(self, label: str) -> Node:
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
        self._state_listeners.append(fn)
        return lambda: self._state_listeners.remove(fn) if fn in self._state_listeners else None

    def add_status_listener(self, fn: Callable[[dict[str, Any]], None]) -> Callable[[], None]:
        """``fn({"op": "status", "level": "info"|"warning"|"error", "msg", "id"})`` for each server status."""
        self.session.status_listeners.append(fn)
        return lambda: self.session.status_listeners.remove(fn) if fn in self.session.status_listeners else None

    def add_failure_listener(self, fn: Callable[[Failure], None]) -> Callable[[], None]:
        self._failure_listeners.append(fn)
        return lambda: self._failure_listeners.remove(fn) if fn in self._failure_listeners else None

    def set_level(self, level: str) -> None:
        """Kept for the interface: a Foxglove server sends every status; none is asked for."""
        self.level = level

    async def typedefs(self, type_name: str) -> list[dict[str, Any]]:
        return await self.catalog.message_details(type_name)

    async def wait_connected(self) -> None:
        if self._connected.is_set():
            return
        if self._task is None or self._task.done():
            raise NotConnectedError(f"not connected to {self.url}")
        await self._connected.wait()

    async def call_service(self, name: str, args: dict[str, Any] | list | None = None,
                           timeout: float | None = None) -> Any:
        """Call a service the server advertises; returns the decoded answer (see the module docstring)."""
        if not isinstance(name, str) or not name:
            raise ValueError(f"service name must be a non-empty string, got {name!r}")
        if args is not None and not isinstance(args, dict | list):
            raise TypeError(f"args must be a dict or list, got {type(args).__name__}")
        self.guard.check(f"the call to {name}")
        budget = self.call_timeout if timeout is None else timeout
        loop = asyncio.get_running_loop()
        fut: asyncio.Future[Any] = loop.create_future()
        cid: int | None = None

        def done(values: Any, error: BaseException | None) -> None:
            if fut.done():
                return
            if error is not None:
                fut.set_exception(error)
            else:
                fut.set_result({} if values is None else values)

        try:
            async with asyncio.timeout(budget):
                await self.wait_connected()
                await self._service_known(name)
                cid = self.session.start_call(name, args, done)
                return await fut
        except TimeoutError:
            raise ServiceTimeoutError(f"no answer to the service call within {budget:g} s", name) from None
        except BridgeError as exc:
            if isinstance(exc, ServiceError | ConnectionLostError | NotConnectedError | ViewOnlyError):
                raise
            raise ServiceError(str(exc), name) from None
        finally:
            if cid is not None:
                self.session.forget_call(cid)

    async def _service_known(self, name: str) -> None:
        while name not in self.session.service_by_name:
            left = self._up_at + SERVICES_GRACE - _monotonic()
            if left <= 0:
                raise ServiceError(f"the robot advertises no service {name}", name)
            event = self._services_changed = self._services_changed or asyncio.Event()
            event.clear()
            try:
                await asyncio.wait_for(event.wait(), left)
            except TimeoutError:
                pass

    def _session_event(self, kind: str) -> None:
        if kind == "catalog" and self._services_changed is not None:
            self._services_changed.set()
        elif kind == "server" and self.link is not None and not self._connected.is_set():
            self._up_at = _monotonic()  # serverInfo arrived: the link is up
            self._connected.set()
            self.failure = None
            self._set_state(ConnectionState.CONNECTED)

    # ================================================================== connecting

    def _report(self, failure: Failure) -> None:
        self.failure = failure
        for fn in list(self._failure_listeners):
            try:
                fn(failure)
            except Exception:
                log.exception("failure listener raised")

    def _why(self, exc: BaseException) -> Failure:
        if isinstance(exc, NotFoxgloveError):
            return Failure(str(exc), True, str(exc))
        return describe(exc, ca_file=self.ca_file, wss_without_cert=self.url.startswith("wss:") and not self.client_cert)

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

    async def _open(self) -> Link:
        ctx = ssl_context(self.ca_file, self.client_cert, self.client_key) if self.url.startswith("wss://") else None
        session = self.session
        receiver = FoxgloveReceiver(session.receive_text, session.receive_binary, self.bad.failed)
        link = await open_connection(self.transport, self.url, list(self.subprotocols), receiver,
                                     session.stale_in_queue, ssl_context=ctx, open_timeout=self.open_timeout,
                                     max_size=self.max_size)
        if link.subprotocol not in self.subprotocols:
            receiver.cancel()
            await link.close()
            link.release()
            raise NotFoxgloveError(f"{self.url} picked none of the Foxglove subprotocols "
                                   f"({', '.join(self.subprotocols)}): it is not a Foxglove server (rosbridge?)")
        return link

    async def connect(self, timeout: float | None = None) -> None:
        """Connect; returns once ``serverInfo`` arrived.  With ``reconnect=False`` the first failure is
        raised; with reconnect it keeps trying (until ``timeout``) unless the error is fatal."""
        if self.link is not None and self._connected.is_set():
            return
        self._closing = False
        if self._task is None or self._task.done():
            self._set_state(ConnectionState.CONNECTING)
            if not self.reconnect:
                try:
                    ws = await self._open()
                except BaseException as exc:
                    self.last_error = exc
                    if isinstance(exc, Exception):
                        self._report(self._why(exc))
                    self._set_state(ConnectionState.CLOSED)
                    raise
                self._task = asyncio.create_task(self._serve_once(ws))
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
        self._closing = True
        task, self._task = self._task, None
        link = self.link
        if link is not None:
            try:
                await link.close()
            except Exception:
                pass
        if task is not None and not task.done():
            task.cancel()
        if task is not None:
            try:
                await task
            except (asyncio.CancelledError, Exception):
                pass
        self._set_state(ConnectionState.CLOSED)

    async def __aenter__(self) -> FoxgloveClient:
        await self.connect()
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.close()

    async def _run(self) -> None:
        delay = self.backoff_min
        try:
            while not self._closing:
                try:
                    ws = await self._open()
                except asyncio.CancelledError:
                    raise
                except Exception as exc:
                    self.last_error = exc
                    failure = self._why(exc)
                    if failure.fatal:
                        raise
                    wait = random.uniform(self.backoff_min / 2, delay)
                    self._report(failure.retrying(wait))
                    self._set_state(ConnectionState.RECONNECTING if self.stats.connects else
                                    ConnectionState.CONNECTING)
                    await asyncio.sleep(wait)
                    delay = min(delay * 2, self.backoff_max)
                    continue
                delay = self.backoff_min
                await self._serve_once(ws, final=False)
                if self._closing:
                    break
                self._set_state(ConnectionState.RECONNECTING)
                await asyncio.sleep(random.uniform(0, self.backoff_min))
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
        session = self.session
        self.link = link
        receiver: FoxgloveReceiver = link.receiver
        self.subprotocol = link.subprotocol
        self.stats.connects += 1
        writer = asyncio.create_task(link.run_writer())
        pinger = asyncio.create_task(self._pinger(link))
        session.attached(_text_or_binary(link), _binary_command(link))
        session.guard.attached(asyncio.get_running_loop())
        receiver.start()
        try:
            await link.wait_closed()  # messages are pushed into the receiver meanwhile (ws.py)
            self.last_error = link.closed_error().with_traceback(None)
            if receiver.task is not None:  # messages that arrived before the close are still delivered
                await asyncio.shield(receiver.task)
        finally:
            receiver.cancel()
            self.link = None
            self._connected.clear()
            writer.cancel()
            pinger.cancel()
            dropped = link.drop_queue()
            if dropped:
                self.stats.dropped_on_disconnect += dropped
            calls = list(session.calls.values())
            session.calls.clear()
            session.param_requests.clear()
            session.detached()
            for _srv, done, _dec in calls:
                done(None, ConnectionLostError("connection lost before the answer arrived"))
            link.release()  # its buffers go now, not at the collector's next full pass (linkbase.py)
            if final:
                self._set_state(ConnectionState.CLOSED)
        if not self._closing:
            log.warning("connection to %s lost (%s)", self.url,
                        (link.close_reason or str(link.close_code or "no close frame"))[:200])

    async def _pinger(self, link: Link) -> None:
        if self.stall_timeout is not None:
            probe = min(self.latency_interval, self.stall_timeout / 4)
            link.watch = LinkWatch(self.stall_timeout, probe, _monotonic())
            await watch_link(link, link.watch, self.pong_timeout, self._link_event)
            return
        try:
            while True:
                waiter = await link.ping()
                try:
                    self.latency = await asyncio.wait_for(waiter, self.pong_timeout)
                except TimeoutError:
                    link.abort()
                    return
                await asyncio.sleep(self.latency_interval)
        except LinkClosedError:
            pass

    def _link_event(self, event: str, detail: Any) -> bool:
        if event == "latency":
            self.latency = detail
        elif event == "stalled":
            if self._state is not ConnectionState.CONNECTED:
                return False
            self.stats.degraded += 1
            log.warning("link to %s is degraded: %s", self.url, detail)
            self._set_state(ConnectionState.DEGRADED)
        elif event == "recovered":
            if self._state is ConnectionState.DEGRADED:
                self._set_state(ConnectionState.CONNECTED)
        elif event == "cut":
            self.stats.stall_cuts += 1
            log.warning("link to %s stalled (%s) with commands in flight; cut it", self.url, detail)
        else:
            log.warning("%s from %s; dropping the link", detail, self.url)
        return True


def _text_or_binary(link: Link) -> Callable[[str | bytes], None]:
    """The session's ``write``: a ``str`` goes out as a text frame (a JSON op), ``bytes`` as a binary one."""
    write, write_binary = link.write, link.write_binary

    def write_frame(frame: str | bytes) -> None:
        if frame.__class__ is str:
            write(frame.encode())  # type: ignore[union-attr]
        else:
            write_binary(frame)  # type: ignore[arg-type]

    return write_frame


def _binary_command(link: Link) -> Callable[[bytes, Any, float], bool]:
    """The session's ``command``: a client message with a freshness limit, a binary frame."""
    send = link.send_command

    def command(data: bytes, pub: Any, max_age: float) -> bool:
        return send(data, pub, max_age, True)

    return command
