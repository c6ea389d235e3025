"""``BridgeClient``: one rosbridge v2 connection, shared by many nodes, on one asyncio loop.

The client is the connection.  Connecting, reconnecting with backoff, state and failure reporting, the
ping and stall watch, TLS and close are the shell it is built on, shared with the Foxglove link
(:class:`~rcon_core.link.connection.ConnectionShell`, whose docstring states those decisions); what is
rosbridge's is here: ``auth``, rosapi, and what happens on a fresh link and when it goes.  What the
protocol is about is the sans-I/O :class:`~rcon_core.bridge.session.Session` (``client.session``); its async
side, :class:`~rcon_core.bridge.shell.SessionShell` (``client.shell``: writing its outbox, futures, tasks), is
attached to each fresh link; messages come in through ``receive.py`` to ``inbound.py``, frames go out through
the link (``transport.py``, over ``pwlink.py`` or ``wslink.py``).  Where each behaviour is decided:

* reconnect, state, latency and stall detection: ``rcon_core/link/connection.py`` (and ``freshness.py``,
  ``reasons.py``, ``secure.py``); ``auth`` and its refusal: here;
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

After every (re)connect
    The client sends, in order: ``auth`` (when configured), ``set_level`` (when set), every advertisement,
    every advertised service and action, then every subscription -- rosbridge forgets all of them with the
    connection (``reconnect.jsonl:8``; ``session.py``).  The link is CONNECTED once ``auth`` is written
    (rosbridge never answers it).  A refused ``auth`` is fatal rather than retried: the robot closing the
    link right after it is read as a refusal (``reasons.refused_auth``).

Frames and messages above the hard ``max_frame_size`` (by default twice ``max_size``) make the transport
close the link (1009), which then reconnects.
"""

from __future__ import annotations

import asyncio
import inspect
import logging
from collections.abc import Callable
from typing import Any

from rcon_core.link.connection import ConnectionShell, ConnectionState

from . import rosapi_guard
from .action_server import ProvidedActions
from .errors import AuthRefusedError, RosapiRefusedError, ServiceError
from .inbound import BadFrames, Inbound
from .linkbase import Link
from .params import Params
from .protocol import encode
from .reasons import refused_auth
from .receive import Receiver
from .rosinfo import RosInfo
from .rosinfo import detect as detect_ros
from .session import LOG_LEVELS, Session
from .shell import SessionShell, later
from .stats import BridgeStats
from .traffic import Traffic

log = logging.getLogger(__name__)

AUTH_FIELDS = ("mac", "client", "dest", "rand", "t", "level", "end")
__all__ = ["BridgeClient", "ConnectionState", "LOG_LEVELS"]


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


class BridgeClient(ConnectionShell):
    """A rosbridge v2 client.  Create, ``await connect()``, then hand out ``node(label)`` to consumers.
    One of the two implementations of ``rcon_core.link.RobotLink``; connecting, reconnecting, state and
    close are the shell's (``rcon_core/link/connection.py``)."""

    protocol = "rosbridge"
    session: Session

    def __init__(self, url: str, *, reconnect: bool = True, ca_file: str | None = None,
                 auth: dict[str, Any] | Callable[[], Any] | None = None, call_timeout: float = 10.0,
                 registry: Any = None, typed_arrays: str = "list", backoff_min: float = 0.25,
                 backoff_max: float = 10.0, latency_interval: float = 2.0, pong_timeout: float = 10.0,
                 open_timeout: float = 10.0, max_size: int = 32 << 20, max_message_size: int | None = None,
                 max_frame_size: int | None = None, fragment_timeout: float = 10.0, big_frame: int = 1 << 20,
                 stall_timeout: float | None = 1.0, client_cert: str | None = None,
                 client_key: str | None = None, max_decoded: int | None = None,
                 transport: str | None = None) -> None:
        size = max_size if max_message_size is None else max_message_size
        super().__init__(url, reconnect=reconnect, ca_file=ca_file, client_cert=client_cert, client_key=client_key,
                         backoff_min=backoff_min, backoff_max=backoff_max, latency_interval=latency_interval,
                         pong_timeout=pong_timeout, open_timeout=open_timeout, stall_timeout=stall_timeout,
                         max_frame_size=max_frame_size or max(2 * size, size + (1 << 20)), transport=transport,
                         stats=BridgeStats())
        if typed_arrays not in ("list", "numpy"):
            raise ValueError("typed_arrays must be 'list' or 'numpy'")
        if isinstance(auth, dict):
            _check_auth(auth)
        self.auth = auth
        self.call_timeout = call_timeout
        self.registry = registry
        self.typed_arrays = typed_arrays
        #: the largest message the client accepts (``max_message_size`` is the older name of the same limit)
        self.max_size = self.max_message_size = size
        self.big_frame = min(big_frame, self.max_message_size)
        #: the bytes of Python objects one (big) frame may decode to; a frame over it is refused (offload.py)
        self.max_decoded = 4 * self.max_message_size if max_decoded is None else max_decoded
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

    def add_status_listener(self, fn: Callable[[dict[str, Any]], None]) -> Callable[[], None]:
        """Call ``fn(frame)`` for each ``status`` op the server sends (``level``, ``msg``, ``id``)."""
        return self.session.add_status_listener(fn)

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

    # ================================================================== a link comes and goes (the shell's hooks)

    def _receiver(self) -> Receiver:
        return Receiver(self.inbound)

    async def _link_up(self, link: Link) -> None:
        """``auth`` first (when configured), then the session's shell restores the rest: CONNECTED."""
        self.inbound.waiting = link.receiver.waiting
        await self._send_auth(link)
        self.shell.attached(link)
        self._up()

    def _link_down(self, link: Link) -> None:
        self.inbound.disconnected()
        self.inbound.waiting = None
        self.shell.detached(link)

    def _check_end(self, link: Link, seconds_open: float) -> None:
        """rosbridge never answers ``auth``: a close right after it is a refusal, fatal (``reasons.py``)."""
        if refused_auth(link.close_code, link.close_reason, auth_sent=self.auth is not None,
                        seconds_open=seconds_open):
            raise AuthRefusedError(f"{self.url} closed the link after the auth op")

    def _closed(self) -> None:
        self.shell.cancel_tasks()
        self.inbound.close()

    async def _send_auth(self, link: Link) -> None:
        """The ``auth`` op first on a fresh connection (when configured); the session restores the rest."""
        if self.auth is not None:
            auth = self.auth() if callable(self.auth) else self.auth
            if inspect.isawaitable(auth):
                auth = await auth
            link.write(encode(_check_auth(auth)))
