"""``FoxgloveClient``: one Foxglove WebSocket connection, shared by many nodes, on one asyncio loop.

The async shell around :class:`~rcon_core.foxglove.session.FoxgloveSession` (the protocol state machine):
futures and timeouts here, and connecting, reconnecting with backoff, state and failure reporting, the stall
watch, TLS and close from the shell both robot links are built on
(:class:`~rcon_core.link.connection.ConnectionShell`, whose docstring states those decisions).  It offers
the robot-link interface (``rcon_core.link.RobotLink``) as ``BridgeClient`` does, so the app, the CLI, the
canvas and the widgets use either without knowing which (``client.protocol`` says).  The connection goes
through the rosbridge link's transports (picows where it imports, else websockets; ``transport=`` or
``RCON_TRANSPORT`` picks one, as for ``BridgeClient``), offering the Foxglove subprotocols, with messages
pushed into a ``FoxgloveReceiver`` (``ws.py``).

Reconnect
    A server that picks none of the Foxglove subprotocols is not retried: it speaks something else
    (rosbridge) and the failure says so.  After every (re)connect the session restores subscriptions,
    client channels, parameter subscriptions and the graph subscription (``session.py``).

State
    The link is CONNECTED once ``serverInfo`` arrived (``client.failure`` is then cleared), not when the
    WebSocket opens.

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
import time
from collections.abc import Callable
from typing import Any

from rcon_core.bridge.errors import (
    BridgeError,
    ConnectionLostError,
    NotConnectedError,
    ServiceError,
    ServiceTimeoutError,
)
from rcon_core.bridge.guard import ViewOnlyError
from rcon_core.bridge.inbound import BadFrames
from rcon_core.bridge.reasons import Failure
from rcon_core.bridge.rosinfo import RosInfo
from rcon_core.bridge.stats import FoxgloveStats
from rcon_core.link.connection import ConnectionShell

from . import wire
from .catalog import FoxgloveCatalog, FoxgloveParams
from .session import CANNOT, FoxgloveSession
from .ws import FoxgloveReceiver, Link

log = logging.getLogger(__name__)
_monotonic = time.monotonic
#: seconds after ``serverInfo`` within which the server's services are expected to be advertised
SERVICES_GRACE = 1.0


class NotFoxgloveError(BridgeError):
    """The server picked none of the Foxglove subprotocols (it speaks rosbridge, or nothing RCON knows)."""


class FoxgloveClient(ConnectionShell):
    """A Foxglove WebSocket protocol client.  Create, ``await connect()``, then ``node(label)``."""

    protocol = "foxglove"
    session: FoxgloveSession
    stats: FoxgloveStats
    subprotocols: tuple[str, ...]

    def __init__(self, url: str, *, reconnect: bool = True, ca_file: str | None = None,
                 client_cert: str | None = None, client_key: str | None = None, auth: Any = None,
                 call_timeout: float = 10.0, backoff_min: float = 0.25, backoff_max: float = 10.0,
                 latency_interval: float = 2.0, pong_timeout: float = 10.0, open_timeout: float = 10.0,
                 max_size: int = 64 << 20, stall_timeout: float | None = 1.0,
                 subprotocols: tuple[str, ...] = wire.SUBPROTOCOLS, transport: str | None = None,
                 **_ignored: Any) -> None:
        super().__init__(url, reconnect=reconnect, ca_file=ca_file, client_cert=client_cert, client_key=client_key,
                         backoff_min=backoff_min, backoff_max=backoff_max, latency_interval=latency_interval,
                         pong_timeout=pong_timeout, open_timeout=open_timeout, stall_timeout=stall_timeout,
                         max_frame_size=max_size, transport=transport, stats=FoxgloveStats())
        #: a rosauth secret cannot be used on this protocol: kept, never sent, said in ``notices``
        self.auth = auth
        self.notices: list[str] = [CANNOT["rosauth"]] if auth is not None else []
        self.call_timeout = call_timeout
        self.max_size = max_size
        self.subprotocols = tuple(subprotocols)
        self.subprotocol: str | None = None
        self._up_at = 0.0
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

    def add_status_listener(self, fn: Callable[[dict[str, Any]], None]) -> Callable[[], None]:
        """``fn({"op": "status", "level": "info"|"warning"|"error", "msg", "id"})`` for each server status."""
        self.session.status_listeners.append(fn)
        return lambda: self.session.status_listeners.remove(fn) if fn in self.session.status_listeners else None

    def set_level(self, level: str) -> None:
        """Kept for the interface: a Foxglove server sends every status; none is asked for."""
        self.level = level

    async def typedefs(self, type_name: str) -> list[dict[str, Any]]:
        return await self.catalog.message_details(type_name)

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
                cid = self.session.requests.start_call(name, args, done)
                return await fut
        except TimeoutError:
            raise ServiceTimeoutError(f"no answer to the service call within {budget:g} s", name) from None
        except BridgeError as exc:
            if isinstance(exc, ServiceError | ConnectionLostError | NotConnectedError | ViewOnlyError):
                raise
            raise ServiceError(str(exc), name) from None
        finally:
            if cid is not None:
                self.session.requests.forget_call(cid)

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
            self.failure = None
            self._up()

    # ================================================================== a link comes and goes (the shell's hooks)

    def _why(self, exc: BaseException) -> Failure:
        if isinstance(exc, NotFoxgloveError):
            return Failure(str(exc), True, str(exc))
        return super()._why(exc)

    def _receiver(self) -> FoxgloveReceiver:
        session = self.session
        return FoxgloveReceiver(session.receive_text, session.receive_binary, self.bad.failed)

    async def _open(self) -> Link:
        """One attempt (the shell's), refused when the server picked none of the Foxglove subprotocols."""
        link = await super()._open()
        if link.subprotocol not in self.subprotocols:
            link.receiver.cancel()
            await link.close()
            link.release()
            raise NotFoxgloveError(f"{self.url} picked none of the Foxglove subprotocols "
                                   f"({', '.join(self.subprotocols)}): it is not a Foxglove server (rosbridge?)")
        return link

    async def _link_up(self, link: Link) -> None:
        """Attach the session and hand it what arrived with the handshake; CONNECTED comes with ``serverInfo``."""
        self.subprotocol = link.subprotocol
        self.session.attached(_text_or_binary(link), _binary_command(link))
        self.session.guard.attached(asyncio.get_running_loop())
        link.receiver.start()

    def _link_down(self, link: Link) -> None:
        """Drop what the link still queued; the session forgets the server and fails the calls waiting."""
        dropped = link.drop_queue()
        if dropped:
            self.stats.dropped_on_disconnect += dropped
        self.session.detached()


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
    send = link.send_by

    def command(data: bytes, pub: Any, max_age: float) -> bool:
        now = _monotonic()
        return send(data, pub, now + max_age, now, True)

    return command
