"""``BridgeClient``: one rosbridge v2 connection, shared by many nodes, on one asyncio loop.

Behaviour decisions (see also ``topics.py`` for how nodes share subscriptions):

Reconnect
    ``async for ws in websockets.asyncio.client.connect(...)`` with our own ``reconnect_delays``: capped
    exponential backoff (``backoff_min`` doubling up to ``backoff_max``) with full jitter.  After every
    (re)connect the client sends, in order: ``auth`` (when configured), ``set_level`` (when set), every
    advertisement, every advertised service, then every subscription -- rosbridge forgets all of them with
    the connection (README point 30).  TLS certificate errors and a refused ``auth`` are fatal rather
    than retried.  Each failed attempt is put in words by ``reasons.describe``; ``client.failure`` holds
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

Publishing while the link is down or stalled
    Nothing is queued for later, so a robot never receives a burst of stale commands.  For a **latched**
    topic only the latest value is kept and sent right after the advertisement is restored; every other
    publish made while down is dropped and counted (``Publisher.dropped``, ``client.stats``).  Frames
    still in the outgoing queue when the link drops are dropped too (counted).  A publisher's ``max_age``
    (0.25 s by default for non-latched topics) is its freshness limit: a publish is never written after it
    -- dropped while DEGRADED or stalling, or when it waited that long in the outgoing queue (counted in
    ``stats["stale_dropped"]``); see ``freshness.py``.

Writing and reading (the hot paths)
    There is no batching and no timer: a frame (a publish, a subscribe...) is written to the transport
    before the call that made it returns, unless frames are already queued or the transport's buffer is
    above its high-water mark; then it waits in a queue that a writer task drains with ``ws.send`` (which
    waits for the transport), so frames always leave in order.  asyncio turns Nagle off on TCP sockets.
    The read loop does one ``recv``, one ``orjson.loads`` and calls a one-consumer topic's callback
    directly; anything else takes the slow path (``_handle_other``).  Frames above ``big_frame`` (1 MB)
    are decoded in a worker thread while the read loop waits for them, so the event loop keeps serving
    and the order of delivery is kept (``offload.py``).

Service calls
    Every call has a client-side timeout (``timeout`` or ``call_timeout``) even though rosbridge 0.11
    ignores the ``timeout`` field; a missing or hung service raises ``ServiceTimeoutError``.  A call made
    while reconnecting waits for the link inside the same budget.  Calls waiting when the link drops fail
    with ``ConnectionLostError``.  ``result: false`` raises ``ServiceError`` carrying the server's string.

Services this client provides
    A handler that raises or returns a non-dict is logged and answered with ``result: false`` and an
    *object*: the response type's default message (from the registry, else the server's
    ``/rosapi/service_response_details``, cached; ``{}`` when neither knows it), the error text in its
    ``message`` string field when it has one.  rosbridge 0.11 ignores ``result`` and rejects a
    non-object ``values``, which would leave the ROS caller waiting forever (README point 21).

ROS 2 actions
    ``node.send_action_goal`` sends the spec's ``send_action_goal`` (``feedback: true`` only when a
    feedback callback is given).  rosbridge answers a goal that *ran* -- succeeded, cancelled or aborted --
    with ``result: true`` and the GoalStatus in ``status``: ``goal.result()`` returns the result message and
    ``goal.status`` tells how it ended.  ``result: false`` (the goal could not be sent: no action server,
    bad args; ``values`` is then the error string), an error ``status`` naming the goal, or the optional
    client-side ``timeout`` raise ``ActionError``.  By default the client also asks
    ``/rosapi/action_servers`` and fails a goal to an unlisted action within ``call_timeout``, because a
    ROS 1 rosbridge drops ``send_action_goal`` without any answer.  Actions this client *provides*
    (``node.advertise_action``) live in ``action_server.py``: the server's ``send_action_goal`` and
    ``cancel_action_goal`` frames go to ``client.provided_actions``.

ROS 1 or ROS 2
    ``detect_ros()`` / ``ros_version`` (``rosinfo.py``); ``client.params`` names parameters the way the
    server's ROS does (``params.py``); ``cbor-raw`` payloads of a ROS 2 server are CDR (``cdrdecode.py``).

Bad input from the server
    No exception raised while handling one frame ends the read loop: the loop body and the slow path
    catch everything at the frame boundary (``stats["frame_errors"]``).  Invalid JSON, unknown ops,
    missing or mistyped fields, JSON nested too deep to format, broken fragments, ``png`` data that is no
    image, PNGs whose header declares more pixel bytes than ``max_size`` (refused before decoding,
    ``stats["png_refused"]``), publish frames whose ``msg`` is not an object
    (``stats["non_object_msgs"]``) and frames above ``max_size`` (32 MB by default, room for a 1080p
    rgb8 image in JSON; ``max_message_size`` is its older name) are logged (rate limited, with a bounded
    repr from ``safety.py``: never ``str()`` of an untrusted value), counted in ``client.stats`` and
    dropped; the connection, the process and other subscriptions carry on.  A callback that raises is
    logged and does not affect other callbacks.  Frames above the hard ``max_frame_size`` (by default
    twice ``max_size``) make the websockets library close the link, which then reconnects.
"""

from __future__ import annotations

import asyncio
import copy
import enum
import inspect
import logging
import random
import ssl
import time
from collections import deque
from collections.abc import Awaitable, Callable, Generator
from typing import Any

import orjson
from websockets.asyncio.client import ClientConnection, connect
from websockets.exceptions import ConnectionClosed
from websockets.protocol import State

from .action_server import ProvidedActions
from .cdrdecode import CdrDecoder, SniffingDecoder, flavour_from_typedefs
from .defaults import default_from_typedefs
from .errors import (
    ActionError,
    ActionTimeoutError,
    AuthRefusedError,
    BridgeError,
    ConnectionLostError,
    NotConnectedError,
    ProtocolError,
    ServiceError,
    ServiceTimeoutError,
)
from .freshness import LinkWatch, TimedFrame, watch_link
from .nodes import ActionGoal, Node, Publisher, ServiceServer, Subscription
from .offload import BigFrames, decode_big
from .params import Params
from .protocol import FragmentAssembler, RefusedFrame, decode_binary, decode_png, encode
from .rawdecode import RawDecoder, _short, has_fixed_arrays
from .reasons import Failure, describe, refused_auth
from .rosinfo import RosInfo
from .rosinfo import detect as detect_ros
from .safety import bounded_repr, safe_text
from .secure import ssl_context
from .topics import AdvertEntry, TopicEntry

log = logging.getLogger(__name__)

_OPEN = State.OPEN
_loads = orjson.loads
_dumps = orjson.dumps
_NUMPY = orjson.OPT_SERIALIZE_NUMPY
_monotonic = time.monotonic
LOG_LEVELS = ("info", "warning", "error", "none")
AUTH_FIELDS = ("mac", "client", "dest", "rand", "t", "level", "end")


class ConnectionState(enum.Enum):
    CONNECTING = "connecting"
    CONNECTED = "connected"
    DEGRADED = "degraded"
    RECONNECTING = "reconnecting"
    CLOSED = "closed"


def _error_values(default: tuple[dict[str, Any], set[str]], text: str) -> dict[str, Any]:
    """A copy of a default response with ``text`` in its ``message`` string field when it has one."""
    values = copy.deepcopy(default[0])
    if "message" in default[1]:
        values["message"] = text
    return values


def _failure_text(values: Any) -> str:
    """The text of a ``result: false`` answer: rosbridge's string, or the ``message`` of an object answer
    (what a failed RCON handler sends), else the whole value."""
    if isinstance(values, str):
        return values
    if isinstance(values, dict) and isinstance(values.get("message"), str) and values["message"]:
        return values["message"]
    return bounded_repr(values, 200)


def _check_auth(auth: dict[str, Any]) -> dict[str, Any]:
    if not isinstance(auth, dict):
        raise TypeError(f"auth must be a dict of rosauth fields, got {type(auth).__name__}")
    missing = [f for f in AUTH_FIELDS if f not in auth]
    if missing:
        raise ValueError(f"auth is missing rosauth field(s): {', '.join(missing)}")
    return {"op": "auth", **{f: auth[f] for f in AUTH_FIELDS}}


def _direct_writer(ws: ClientConnection) -> Callable[[bytes], bool] | None:
    """A function that writes one text frame to ``ws`` synchronously and returns True, or returns False
    when it cannot right now (the connection is not open, or the transport is above its high-water mark:
    then the caller queues the frame for ``ws.send``, which waits for the drain).  It does what
    ``ws.send`` does minus the waiting: the Sans-I/O protocol builds the frame, ``send_data`` writes it.
    None when this websockets version lacks those pieces (every frame then goes through ``ws.send``)."""
    protocol = getattr(ws, "protocol", None)
    flush = getattr(ws, "send_data", None)
    transport = getattr(ws, "transport", None)
    if protocol is None or flush is None or transport is None or not hasattr(protocol, "send_text"):
        return None
    buffered = transport.get_write_buffer_size
    closing = transport.is_closing
    high = transport.get_write_buffer_limits()[1]

    def write_now(data: bytes) -> bool:
        if protocol.state is not _OPEN or closing() or buffered() > high:
            return False
        protocol.send_text(data)
        flush()
        return True

    return write_now


class _RegistryDecoder:
    __slots__ = ("registry",)

    def __init__(self, registry: Any) -> None:
        self.registry = registry

    def decode(self, type_name: str, data: bytes) -> dict[str, Any]:
        return self.registry.deserialize_ros1(type_name, data)


class BridgeClient:
    """A rosbridge v2 client.  Create, ``await connect()``, then hand out ``node(label)`` to consumers."""

    def __init__(self, url: str, *, reconnect: bool = True, ca_file: str | None = None,
                 auth: dict[str, Any] | Callable[[], Any] | None = None, call_timeout: float = 10.0,
                 registry: Any = None, typed_arrays: str = "list", backoff_min: float = 0.25,
                 backoff_max: float = 10.0, latency_interval: float = 2.0, pong_timeout: float = 10.0,
                 open_timeout: float = 10.0, max_size: int = 32 << 20, max_message_size: int | None = None,
                 max_frame_size: int | None = None, fragment_timeout: float = 10.0, big_frame: int = 1 << 20,
                 stall_timeout: float | None = 1.0, client_cert: str | None = None,
                 client_key: str | None = None) -> None:
        if not isinstance(url, str) or not url.startswith(("ws://", "wss://")):
            raise ValueError(f"url must start with ws:// or wss://, got {url!r}")
        if typed_arrays not in ("list", "numpy"):
            raise ValueError("typed_arrays must be 'list' or 'numpy'")
        if isinstance(auth, dict):
            _check_auth(auth)
        self.url = url
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
        self.stall_timeout = stall_timeout
        self._watch: LinkWatch | None = None
        self._big = BigFrames(typed_arrays, self.max_message_size)
        self._deferred: Callable[[], Awaitable[Any]] | None = None
        self.latency: float | None = None
        self.last_error: BaseException | None = None
        self.failure: Failure | None = None
        self._failure_listeners: list[Callable[[Failure], None]] = []
        self.stats: dict[str, int] = {"connects": 0, "bad_frames": 0, "dropped_while_down": 0,
                                      "dropped_on_disconnect": 0, "oversize_frames": 0, "frame_errors": 0,
                                      "png_refused": 0, "non_object_msgs": 0, "big_frames": 0,
                                      "stale_dropped": 0, "degraded": 0, "stall_cuts": 0}
        self._state = ConnectionState.CLOSED
        self._state_listeners: list[Callable[[ConnectionState], None]] = []
        self._status_listeners: list[Callable[[dict[str, Any]], None]] = []
        self._ws: ClientConnection | None = None
        self._task: asyncio.Task[None] | None = None
        self._connected = asyncio.Event()
        self._closing = False
        self._out: deque[bytes | TimedFrame] = deque()
        self._out_event = asyncio.Event()
        self._write_now: Callable[[bytes], bool] | None = None
        self._nodes: dict[str, Node] = {}
        self._topics: dict[str, TopicEntry] = {}
        self._adverts: dict[str, AdvertEntry] = {}
        self._services: dict[str, ServiceServer] = {}
        self._pending: dict[str, asyncio.Future[Any]] = {}
        self._goals: dict[str, ActionGoal] = {}
        self._typedefs: dict[str, list[dict[str, Any]]] = {}
        self._response_defaults: dict[str, tuple[dict[str, Any], set[str]]] = {}
        self._raw = RawDecoder()
        self._cdr = CdrDecoder()  # cbor-raw from ROS 2 servers (CDR)
        warn = self._fragment_warning
        self._fragments = FragmentAssembler(timeout=fragment_timeout, max_bytes=self.max_message_size, warn=warn)
        self._png_fragments = FragmentAssembler(timeout=fragment_timeout, max_bytes=self.max_message_size, warn=warn)
        self._level: str | None = None
        self._seq = 0
        self._bad_counts: dict[str, int] = {}
        self._tasks: set[asyncio.Task[Any]] = set()
        self.provided_actions = ProvidedActions(self._send)  # actions this client serves (ROS 2)
        self._ops: dict[str, Callable[[dict[str, Any]], None]] = {
            "publish": self._on_publish, "fragment": self._on_fragment, "png": self._on_png,
            "service_response": self._on_service_response, "call_service": self._on_call_service,
            "status": self._on_status, "action_feedback": self._on_action_feedback,
            "action_result": self._on_action_result, "send_action_goal": self.provided_actions.on_goal,
            "cancel_action_goal": self.provided_actions.on_cancel,
        }
        from .rosapi import Rosapi

        self.rosapi = Rosapi(self)
        self.ros_info: RosInfo | None = None  # set by detect_ros(); see rosinfo.py
        self.params = Params(self)  # ROS 1 and ROS 2 parameters; see params.py

    # ================================================================== state

    @property
    def state(self) -> ConnectionState:
        return self._state

    @property
    def connected(self) -> bool:
        return self._ws is not None

    @property
    def ros_version(self) -> int | None:
        """1 or 2 once ``detect_ros()`` found out (or ``ros_info`` was set), else None."""
        return self.ros_info.version if self.ros_info is not None else None

    async def detect_ros(self, refresh: bool = False) -> RosInfo:
        """Which ROS the server runs (asked once; ``refresh`` asks again).  See ``rosinfo.py``."""
        if self.ros_info is None or refresh:
            self.ros_info = await detect_ros(self)
        return self.ros_info

    def add_state_listener(self, fn: Callable[[ConnectionState], None]) -> Callable[[], None]:
        """Call ``fn(state)`` on every change; returns a function that removes the listener."""
        self._state_listeners.append(fn)
        return lambda: self._state_listeners.remove(fn) if fn in self._state_listeners else None

    def add_status_listener(self, fn: Callable[[dict[str, Any]], None]) -> Callable[[], None]:
        """Call ``fn(frame)`` for each ``status`` op the server sends (``level``, ``msg``, ``id``)."""
        self._status_listeners.append(fn)
        return lambda: self._status_listeners.remove(fn) if fn in self._status_listeners else None

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
        for fn in list(self._state_listeners):
            try:
                fn(state)
            except Exception:
                log.exception("state listener raised")

    def node(self, label: str) -> Node:
        """A new node; its id is ``label``, made unique with a ``#n`` suffix when already taken."""
        if not isinstance(label, str) or not label:
            raise ValueError("node label must be a non-empty string")
        node_id, n = label, 1
        while node_id in self._nodes:
            n += 1
            node_id = f"{label}#{n}"
        node = self._nodes[node_id] = Node(self, node_id)
        return node

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

    def _process_exception(self, exc: Exception) -> Exception | None:
        self.last_error = exc
        if describe(exc).fatal:
            return exc  # retrying cannot fix a certificate problem, a bad URL...
        if self._state is not ConnectionState.CLOSED:
            log.info("connecting to %s failed: %s", self.url, exc)
        return None

    def _connector(self) -> connect:
        return connect(self.url, ssl=self._ssl_context(), compression=None, ping_interval=None,
                       open_timeout=self.open_timeout, max_size=self.max_frame_size,
                       process_exception=self._process_exception, reconnect_delays=self._delays,
                       close_timeout=2)

    async def connect(self, timeout: float | None = None) -> None:
        """Connect; returns once connected.  With ``reconnect=False`` the first failure is raised; with
        reconnect it keeps trying (until ``timeout``, then ``TimeoutError``) unless the error is fatal."""
        if self._ws is not None:
            return
        self._closing = False
        if self._task is None or self._task.done():
            self._set_state(ConnectionState.CONNECTING)
            if not self.reconnect:
                try:
                    ws = await self._connector()
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
            done, _ = await asyncio.wait({waiter, self._task}, timeout=timeout,
                                         return_when=asyncio.FIRST_COMPLETED)
        finally:
            waiter.cancel()
        if self._ws is not None:
            return
        if self._task.done():
            error = self._task.exception() if not self._task.cancelled() else None
            raise error or NotConnectedError(f"could not connect to {self.url}")
        raise TimeoutError(f"not connected to {self.url} within {timeout} s (last error: {self.last_error})")

    async def close(self) -> None:
        """Close the connection and stop reconnecting.  Nodes stay usable for a later ``connect()``."""
        self._closing = True
        task, self._task = self._task, None
        ws = self._ws
        if ws is not None:
            await ws.close()
        if task is not None and not task.done():
            task.cancel()
        if task is not None:
            try:
                await task
            except (asyncio.CancelledError, Exception):
                pass
        for t in list(self._tasks):
            t.cancel()
        self._big.close()
        self._set_state(ConnectionState.CLOSED)

    async def __aenter__(self) -> BridgeClient:
        await self.connect()
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.close()

    async def _run(self) -> None:
        try:
            async for ws in self._connector():
                opened = time.monotonic()
                await self._serve_once(ws, final=False)
                if self._closing:
                    break
                if refused_auth(ws.close_code, ws.close_reason, auth_sent=self.auth is not None,
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

    async def _serve_once(self, ws: ClientConnection, final: bool = True) -> None:
        self._ws = ws
        self._write_now = _direct_writer(ws)
        self.stats["connects"] += 1
        writer = asyncio.create_task(self._writer(ws))
        pinger = asyncio.create_task(self._pinger(ws))
        try:
            await self._restore()
            self._connected.set()
            self._set_state(ConnectionState.CONNECTED)
            await self._read(ws)
        except ConnectionClosed as exc:
            self.last_error = exc
        finally:
            self._ws = None
            self._watch = None
            self._write_now = None
            self._connected.clear()
            writer.cancel()
            pinger.cancel()
            self._on_disconnect()
            if final:
                self._set_state(ConnectionState.CLOSED)
        if not self._closing:
            log.warning("connection to %s lost (%s)", self.url, ws.close_reason or ws.close_code or "no close frame")

    async def _restore(self) -> None:
        """Send auth, level, advertisements, services and subscriptions on a fresh connection."""
        if self.auth is not None:
            auth = self.auth() if callable(self.auth) else self.auth
            if inspect.isawaitable(auth):
                auth = await auth
            self._send(_check_auth(auth))
        if self._level is not None:
            self._send({"op": "set_level", "level": self._level})
        for advert in self._adverts.values():
            advert.active = False
            self._send(advert.advertise_op())
            advert.active = True
            if advert.pending is not None:
                self._send_publish(advert, advert.pending)
                advert.pending = None
        for srv in self._services.values():
            self._send({"op": "advertise_service", "service": srv.service, "type": srv.type})
        self.provided_actions.restore()
        for topic in self._topics.values():
            topic.sid = None
            topic.sent_options = None
            self._sync_topic(topic)

    def _on_disconnect(self) -> None:
        self._deferred = None  # a big message of the lost connection is not delivered on the next one
        dropped = len(self._out)
        if dropped:
            self.stats["dropped_on_disconnect"] += dropped
            self._out.clear()
        for advert in self._adverts.values():
            advert.active = False
        for topic in self._topics.values():
            topic.sid = None
            topic.sent_options = None
        for fut in list(self._pending.values()):
            if not fut.done():
                fut.set_exception(ConnectionLostError("connection lost before the answer arrived"))
        self._pending.clear()
        for gid, goal in list(self._goals.items()):
            goal._settle(error=ConnectionLostError(f"connection lost while goal {gid} was active"))
        self._goals.clear()
        self.provided_actions.disconnected()

    # ================================================================== writing

    def _send(self, op: dict[str, Any]) -> bool:
        """Send one frame on the current connection; False when there is none."""
        if self._ws is None:
            return False
        self._write(encode(op))
        return True

    def _write(self, data: bytes) -> None:
        """Hand one encoded frame to the connection.  When nothing is queued and the transport's buffer is
        below its high-water mark the frame is written at once (it is on its way before ``publish()``
        returns: no task switch, no timer); otherwise it is queued for the writer task, which waits for the
        transport to drain.  Either way frames leave in the order they were sent."""
        if not self._out:
            write_now = self._write_now
            if write_now is not None and write_now(data):
                return
        self._out.append(data)
        self._out_event.set()

    async def _writer(self, ws: ClientConnection) -> None:
        out = self._out
        event = self._out_event
        try:
            while True:
                while out:
                    item = out.popleft()
                    if item.__class__ is TimedFrame:  # a command: never written after its freshness limit
                        now = _monotonic()
                        if now > item.deadline or self._state is ConnectionState.DEGRADED:  # type: ignore[union-attr]
                            self._drop_stale(item.pub, counted_sent=True)  # type: ignore[union-attr]
                            continue
                        if self._watch is not None:
                            self._watch.command(now)
                        item = item.data  # type: ignore[union-attr]
                    await ws.send(item, text=True)
                event.clear()
                await event.wait()
        except ConnectionClosed:
            pass

    async def _pinger(self, ws: ClientConnection) -> None:
        """Without stall detection (``stall_timeout=None``): a ping every ``latency_interval``; a pong
        missing for ``pong_timeout`` drops the link.  With it, ``freshness.watch_link``."""
        if self.stall_timeout is not None:
            probe_interval = min(self.latency_interval, self.stall_timeout / 4)
            self._watch = LinkWatch(self.stall_timeout, probe_interval, _monotonic())
            await watch_link(ws, self._watch, self.pong_timeout, self._link_event)
            return
        try:
            while True:
                waiter = await ws.ping()
                try:
                    self.latency = await asyncio.wait_for(waiter, self.pong_timeout)
                except TimeoutError:
                    log.warning("no pong from %s within %.0f s; dropping the link", self.url, self.pong_timeout)
                    ws.transport.abort()
                    return
                await asyncio.sleep(self.latency_interval)
        except ConnectionClosed:
            pass

    def _link_event(self, event: str, detail: Any) -> bool:
        """What the watchdog (``freshness.watch_link``) reports; True when a stall counts (CONNECTED)."""
        if event == "latency":
            self.latency = detail
        elif event == "stalled":
            if self._state is not ConnectionState.CONNECTED:
                return False
            self.stats["degraded"] += 1
            log.warning("link to %s is degraded: %s", self.url, detail)
            self._set_state(ConnectionState.DEGRADED)
        elif event == "recovered":
            log.info("link to %s has recovered", self.url)
            if self._state is ConnectionState.DEGRADED:
                self._set_state(ConnectionState.CONNECTED)
        elif event == "cut":
            self.stats["stall_cuts"] += 1
            log.warning("link to %s stalled (%s) with commands in flight; cut it so they are never delivered "
                        "late; reconnecting", self.url, detail)
        else:
            log.warning("%s from %s; dropping the link", detail, self.url)
        return True

    # ================================================================== reading (hot path)

    async def _read(self, ws: ClientConnection) -> None:
        """Read frames until the connection closes.  Per message: one ``recv``, one ``orjson.loads`` (CBOR for
        binary frames), a few dict lookups and a direct call of the topic's ``fast`` function -- for a topic
        with one consumer, its callback.  Everything unusual (other ops, unknown topics, malformed frames)
        goes to ``_handle_other``."""
        loads = _loads
        topics = self._topics
        big = self.big_frame
        other = self._handle_other
        recv = ws.recv
        while True:
            raw = await recv()
            try:  # the frame boundary: nothing raised while handling one frame ends the loop
                if len(raw) > big:
                    m = await self._decode_big(raw)
                    if m is None:
                        continue
                elif isinstance(raw, str):
                    try:
                        m = loads(raw)
                    except orjson.JSONDecodeError as exc:
                        self._bad_frame("json", f"text frame is not valid JSON ({exc}): {raw[:80]!r}")
                        continue
                else:
                    m = self._decode_binary(raw)
                    if m is None:
                        continue
                try:
                    entry = topics[m["topic"]] if m["op"] == "publish" else None
                    msg = m["msg"]
                except (KeyError, TypeError):  # not a publish of a subscribed topic, or malformed: slow path
                    entry = None
                if entry is not None and msg.__class__ is dict:
                    try:
                        entry.fast(msg)
                    except Exception:
                        entry.callback_failed()
                    continue
                other(m)
                while self._deferred is not None:  # a big message completed by fragments: decoded off the loop
                    job, self._deferred = self._deferred, None
                    inner = await job()
                    if inner is not None:
                        other(inner)
            except Exception as exc:
                self._frame_failed(exc)

    async def _decode_big(self, raw: str | bytes) -> Any:
        """Decode a frame above ``big_frame`` in the worker thread (see ``offload.py``); None when dropped."""
        if len(raw) > self.max_message_size:
            self._oversize(raw)
            return None
        return await self._offloaded(decode_big, raw, self.typed_arrays, self.max_message_size)

    async def _offloaded(self, fn: Callable[..., Any], *args: Any) -> Any:
        self.stats["big_frames"] += 1
        try:
            return await self._big.run(fn, *args)
        except ProtocolError as exc:
            if isinstance(exc, RefusedFrame):
                self.stats["png_refused"] += 1
            self._bad_frame("big", f"big frame dropped: {exc}")
            return None

    def _frame_failed(self, exc: BaseException) -> None:
        """A frame whose handling raised: counted, logged with a bounded text, dropped; the loop goes on."""
        self.stats["frame_errors"] += 1
        self._bad_frame("error", f"handling a frame failed, dropped it ({safe_text(exc)})")

    def _dispatch_text(self, text: str | bytes) -> None:
        """Handle a frame reconstructed from fragments or a png frame."""
        try:
            m = _loads(text)
        except orjson.JSONDecodeError as exc:
            self._bad_frame("json", f"reassembled frame is not valid JSON ({exc})")
            return
        self._handle_other(m)

    def _decode_binary(self, raw: bytes) -> Any:
        try:
            return decode_binary(raw, self.typed_arrays)
        except Exception as exc:
            self._bad_frame("binary", f"binary frame of {len(raw)} bytes dropped: {exc}")
            return None

    def _oversize(self, raw: str | bytes) -> None:
        self.stats["oversize_frames"] += 1
        self._bad_frame("size", f"frame of {len(raw)} bytes exceeds max_message_size={self.max_message_size}; dropped")

    def _fragment_warning(self, message: str) -> None:
        self._bad_frame("fragment", message)

    def _bad_frame(self, kind: str, message: str) -> None:
        """Log a bad frame from the server (the first 20 of each kind, then every 1000th) and count it."""
        self.stats["bad_frames"] += 1
        n = self._bad_counts[kind] = self._bad_counts.get(kind, 0) + 1
        if n <= 20 or n % 1000 == 0:
            log.warning("bad frame from %s: %s", self.url, message)
        elif n == 21:
            log.warning("bad frame from %s: %s (more %s problems are counted in stats and logged every 1000th)",
                        self.url, message, kind)

    def _handle_other(self, m: Any) -> None:
        """The slow path (and what fragments and png frames carry); never raises."""
        try:
            self._handle_op(m)
        except Exception as exc:
            self._frame_failed(exc)

    def _handle_op(self, m: Any) -> None:
        if not isinstance(m, dict):
            self._bad_frame("shape", f"frame is a JSON {type(m).__name__}, not an object; ignored")
            return
        op = m.get("op")
        handler = self._ops.get(op) if isinstance(op, str) else None
        if handler is None:
            if "op" not in m:
                self._bad_frame("op", f"frame without 'op' ignored: {bounded_repr(m, 80)}")
            else:
                self._bad_frame("op", f"unknown op {bounded_repr(op, 80)} ignored")
            return
        try:
            handler(m)
        except (KeyError, TypeError, ValueError, AttributeError) as exc:
            self._bad_frame("field", f"malformed {op!r} frame ignored ({safe_text(exc)})")

    # ------------------------------------------------------------------ op handlers (slow path)

    def _on_publish(self, m: dict[str, Any]) -> None:
        topic = m.get("topic")
        if not isinstance(topic, str):
            raise TypeError(f"'topic' must be a string, got {type(topic).__name__}")
        if "msg" not in m:
            raise KeyError("publish frame has no 'msg'")
        entry = self._topics.get(topic)
        if entry is None:
            return
        msg = m["msg"]
        if not isinstance(msg, dict):
            self.stats["non_object_msgs"] += 1
            self._bad_frame("msg", f"publish on {topic}: 'msg' is a JSON {type(msg).__name__}, not an object; "
                                   "dropped")
            return
        entry.deliver(msg)

    def _on_fragment(self, m: dict[str, Any]) -> None:
        try:
            text = self._fragments.add(m)
        except ProtocolError as exc:
            self._bad_frame("fragment", str(exc))
            return
        if text is not None and len(text) > self.big_frame:
            self._deferred = lambda: self._decode_big(text)  # the read loop awaits it (order is kept)
        elif text is not None:
            self._dispatch_text(text)

    def _on_png(self, m: dict[str, Any]) -> None:
        try:
            data = m["data"]
            if "num" in m and "total" in m:
                data = self._png_fragments.add(m)
                if data is None:
                    return
            if not isinstance(data, str):
                raise ProtocolError(f"png frame: 'data' must be a string, got {type(data).__name__}")
            if len(data) > self.big_frame:
                self._deferred = lambda: self._offloaded(decode_png, data, self.max_message_size)
                return
            inner = decode_png(data, self.max_message_size)
        except ProtocolError as exc:
            if isinstance(exc, RefusedFrame):
                self.stats["png_refused"] += 1
            self._bad_frame("png", str(exc))
            return
        self._handle_other(inner)

    def _on_service_response(self, m: dict[str, Any]) -> None:
        cid = m.get("id")
        fut = self._pending.pop(cid, None) if isinstance(cid, str) else None
        if fut is None:
            log.debug("service_response for unknown or finished call %r (late answer?)", cid)
            return
        if fut.done():
            return
        values = m.get("values")
        if m.get("result", True) is False:
            fut.set_exception(ServiceError(_failure_text(values), m.get("service")))
        else:
            fut.set_result({} if values is None else values)

    def _on_status(self, m: dict[str, Any]) -> None:
        level = m.get("level", "info")
        text = m.get("msg", "")
        sid = m.get("id")
        if not isinstance(level, str):
            level = bounded_repr(level, 40)
        if not isinstance(text, str):
            text = bounded_repr(text, 200)
        pylevel = {"error": logging.ERROR, "warning": logging.WARNING}.get(level, logging.INFO)
        log.log(pylevel, "server status (%s)%s: %s", level, f" for {bounded_repr(sid, 80)}" if sid else "", text)
        if level == "error" and isinstance(sid, str):
            fut = self._pending.pop(sid, None)
            if fut is not None and not fut.done():
                fut.set_exception(ServiceError(str(text)))
            goal = self._goals.get(sid)
            if goal is not None:
                self._fail_goal(goal, ActionError(str(text), goal.action), cancel=False)
        for fn in list(self._status_listeners):
            try:
                fn(m)
            except Exception:
                log.exception("status listener raised")

    # ================================================================== subscriptions

    def _add_subscription(self, sub: Subscription) -> None:
        entry = self._topics.get(sub.topic)
        if entry is None:
            entry = self._topics[sub.topic] = TopicEntry(self, sub.topic)
            entry.decoder = self._raw
        entry.subs.append(sub)
        entry.rebuild()
        self._sync_topic(entry)

    def _remove_subscription(self, sub: Subscription) -> None:
        entry = self._topics.get(sub.topic)
        if entry is None or sub not in entry.subs:
            return
        entry.subs.remove(sub)
        if not entry.subs:
            del self._topics[sub.topic]
            if entry.sid is not None:
                self._send({"op": "unsubscribe", "id": entry.sid, "topic": entry.topic})
            entry.sid = None
            entry.raw_type = None
            entry.rebuild()
            return
        entry.rebuild()
        self._sync_topic(entry)

    def _sync_topic(self, entry: TopicEntry) -> None:
        """Make the server-side subscription match what the nodes want (resubscribe when it changed)."""
        if self._ws is None or not entry.subs:
            return
        wanted = entry.wanted()
        if wanted == entry.sent_options:
            return
        entry.sent_options = wanted
        if wanted["compression"] in ("cbor", "cbor-raw"):
            self._spawn(self._resolve_and_subscribe(entry, wanted))
        else:
            self._subscribe_now(entry, wanted)

    async def _resolve_and_subscribe(self, entry: TopicEntry, wanted: dict[str, Any]) -> None:
        opts = dict(wanted)
        try:
            type_name = opts.get("type") or await self.rosapi.topic_type(entry.topic)
            if not type_name:
                raise BridgeError(f"the server does not know the type of {entry.topic}")
            opts["type"] = type_name
            typedefs = await self.typedefs(type_name)
            if opts["compression"] == "cbor" and has_fixed_arrays(type_name, typedefs):
                log.info("%s [%s] has fixed-size arrays, which rosbridge's cbor encoder cannot send; "
                         "using cbor-raw instead", entry.topic, type_name)
                opts["compression"] = "cbor-raw"
            if opts["compression"] == "cbor-raw":
                self._learn_raw_flavour(type_name, typedefs)
        except Exception as exc:
            log.warning("%s: cannot prepare %s compression (%s); subscribing without compression",
                        entry.topic, opts["compression"], exc)
            opts["compression"] = "none"
        if self._topics.get(entry.topic) is not entry or entry.sent_options is not wanted or self._ws is None:
            return  # superseded while we were asking the server
        self._subscribe_now(entry, opts)

    def _subscribe_now(self, entry: TopicEntry, opts: dict[str, Any]) -> None:
        self._seq += 1
        sid = f"sub:{entry.topic}:{self._seq}"
        op = {"op": "subscribe", "id": sid, "topic": entry.topic, **opts}
        entry.raw_type = opts["type"] if opts["compression"] == "cbor-raw" else None
        if entry.raw_type is not None:
            entry.decoder = self._raw_decoder(entry.raw_type)
        old, entry.sid = entry.sid, sid
        entry.rebuild()
        self._send(op)
        if old is not None:
            self._send({"op": "unsubscribe", "id": old, "topic": entry.topic})

    def _learn_raw_flavour(self, type_name: str, typedefs: list[dict[str, Any]]) -> None:
        """cbor-raw is CDR from a ROS 2 server: hand the typedefs to the CDR decoder when the server is (or
        its typedefs look) ROS 2; when neither tells, each payload is sniffed (``cdrdecode.py``)."""
        version = self.ros_version or flavour_from_typedefs(typedefs)
        if version != 1:
            self._cdr.add_typedefs(typedefs)
        if version is None:
            self._cdr.uncertain.add(_short(type_name))
        else:
            self._cdr.uncertain.discard(_short(type_name))

    def _raw_decoder(self, type_name: str) -> Any:
        """cbor-raw decoding: CDR for types learned from a ROS 2 server (sniffed per payload when the flavour
        is unknown); else the registry's ``deserialize_ros1`` when a registry is given and knows the type (it
        learns the server's typedefs in ``typedefs()``), else the built-in typedef-driven decoder."""
        if self._cdr.knows(type_name):
            if _short(type_name) in self._cdr.uncertain:
                return SniffingDecoder(self._cdr, self._ros1_decoder(type_name))
            return self._cdr
        return self._ros1_decoder(type_name)

    def _ros1_decoder(self, type_name: str) -> Any:
        reg = self.registry
        if reg is not None and hasattr(reg, "deserialize_ros1"):
            try:
                known = reg.has(type_name)
            except Exception:
                known = False
            if known:
                return _RegistryDecoder(reg)
        return self._raw

    async def typedefs(self, type_name: str) -> list[dict[str, Any]]:
        """rosapi typedefs of a message type, from the server (cached), else from the local registry."""
        key = _short(type_name)
        cached = self._typedefs.get(key)
        if cached is not None:
            return cached
        try:
            typedefs = await self.rosapi.message_details(key if "/msg/" not in type_name else type_name)
        except (ServiceError, NotConnectedError) as exc:
            if self.registry is None or not self.registry.has(type_name):
                raise
            log.info("rosapi message_details failed for %s (%s); using the local registry", type_name, exc)
            typedefs = self.registry.typedefs(type_name)
        if not typedefs and self.registry is not None and self.registry.has(type_name):
            typedefs = self.registry.typedefs(type_name)  # rosapi 2.x answers [] for what it cannot load
        if not typedefs:
            raise BridgeError(f"the server has no definition for {type_name}")
        self._typedefs[key] = typedefs
        self._raw.add_typedefs(typedefs)
        if self.registry is not None and hasattr(self.registry, "add_typedefs"):
            try:
                self.registry.add_typedefs(typedefs)
            except Exception as exc:
                log.debug("registry did not take typedefs of %s: %s", type_name, exc)
        return typedefs

    # ================================================================== publishing

    def _add_publisher(self, pub: Publisher) -> None:
        entry = self._adverts.get(pub.topic)
        if entry is None:
            entry = self._adverts[pub.topic] = AdvertEntry(pub.topic, pub.type)
        elif _short(entry.type) != _short(pub.type):
            raise BridgeError(f"{pub.topic} is already advertised as {entry.type}, not {pub.type}")
        entry.pubs.append(pub)
        changed = entry.merge()
        if self._ws is not None and (not entry.active or changed):
            self._send(entry.advertise_op())
            entry.active = True

    def _remove_publisher(self, pub: Publisher) -> None:
        entry = self._adverts.get(pub.topic)
        if entry is None or pub not in entry.pubs:
            return
        entry.pubs.remove(pub)
        if not entry.pubs:
            del self._adverts[pub.topic]
            if entry.active:
                self._send({"op": "unadvertise", "id": f"adv:{entry.topic}", "topic": entry.topic})
            return
        entry.merge()

    def _publish(self, pub: Publisher, msg: dict[str, Any]) -> bool:
        entry = self._adverts[pub.topic]
        if self._ws is not None and entry.active:
            if pub.max_age is not None:
                return self._publish_command(entry, pub, msg)
            self._send_publish(entry, msg)
            pub.sent += 1
            return True
        if entry.latch:
            entry.pending = msg  # latest value wins; sent after the advertisement is restored
            return True
        pub.dropped += 1
        entry.dropped += 1
        self.stats["dropped_while_down"] += 1
        return False

    def _publish_command(self, entry: AdvertEntry, pub: Publisher, msg: dict[str, Any]) -> bool:
        """Publish with a freshness limit (``freshness.py``): dropped when the link cannot carry it in time,
        else written now or queued with its deadline."""
        now = _monotonic()
        watch = self._watch
        if self._state is ConnectionState.DEGRADED or (watch is not None and watch.overdue(now) > pub.max_age):
            self._drop_stale(pub)
            return False
        data = b"".join((entry.head, _dumps(msg, option=_NUMPY), b',"latch":true}' if entry.latch else b"}"))
        write_now = self._write_now
        if not self._out and write_now is not None and write_now(data):
            if watch is not None:
                watch.command(now)
        else:
            self._out.append(TimedFrame(data, now + pub.max_age, pub))  # type: ignore[arg-type]
            self._out_event.set()
        pub.sent += 1
        return True

    def _drop_stale(self, pub: Publisher, counted_sent: bool = False) -> None:
        if counted_sent:
            pub.sent -= 1
        pub.dropped += 1
        self.stats["stale_dropped"] += 1

    def _send_publish(self, entry: AdvertEntry, msg: dict[str, Any]) -> None:
        # The frame around the message is encoded once per advertisement (``entry.head``); latch is repeated
        # in every publish (README point 25: otherwise the topic is re-registered).
        self._write(b"".join((entry.head, _dumps(msg, option=_NUMPY), b',"latch":true}' if entry.latch else b"}")))

    # ================================================================== services

    async def call_service(self, name: str, args: dict[str, Any] | list | None = None,
                           timeout: float | None = None) -> Any:
        """Call a service; returns its ``values``.  Raises ServiceError / ServiceTimeoutError."""
        if not isinstance(name, str) or not name:
            raise ValueError(f"service name must be a non-empty string, got {name!r}")
        if args is not None and not isinstance(args, dict | list):
            raise TypeError(f"args must be a dict or list, got {type(args).__name__}")
        budget = self.call_timeout if timeout is None else timeout
        self._seq += 1
        cid = f"call:{name}:{self._seq}"
        op: dict[str, Any] = {"op": "call_service", "id": cid, "service": name}
        if args is not None:
            op["args"] = args
        if timeout is not None:
            op["timeout"] = timeout
        fut: asyncio.Future[Any] = asyncio.get_running_loop().create_future()
        try:
            async with asyncio.timeout(budget):
                await self._wait_connected()
                self._pending[cid] = fut
                self._send(op)
                return await fut
        except TimeoutError:
            raise ServiceTimeoutError(f"no answer within {budget:g} s", name) from None
        finally:
            self._pending.pop(cid, None)

    async def _wait_connected(self) -> None:
        if self._ws is not None:
            return
        if self._task is None or self._task.done():
            raise NotConnectedError(f"not connected to {self.url}")
        await self._connected.wait()

    def _add_service(self, srv: ServiceServer) -> None:
        if srv.service in self._services:
            other = self._services[srv.service]
            raise BridgeError(f"service {srv.service} is already advertised by node {other.node.id}")
        self._services[srv.service] = srv
        self._send({"op": "advertise_service", "service": srv.service, "type": srv.type})

    def _remove_service(self, srv: ServiceServer) -> None:
        if self._services.get(srv.service) is srv:
            del self._services[srv.service]
            self._send({"op": "unadvertise_service", "service": srv.service})

    def _on_call_service(self, m: dict[str, Any]) -> None:
        name = m["service"]
        if not isinstance(name, str):
            raise TypeError(f"'service' must be a string, got {type(name).__name__}")
        srv = self._services.get(name)
        if srv is None:
            log.warning("server called %s, which this client does not provide; answered with an empty message",
                        name)
            self._respond(m, {}, False)  # an object, so the ROS caller is answered rather than left waiting
            return
        args = m.get("args")
        if args is None:
            args = {}
        srv.calls += 1
        try:
            result = srv.handler(args)
        except Exception as exc:
            self._handler_failed(m, srv, exc)
            return
        if inspect.isawaitable(result):
            self._spawn(self._finish_call(m, srv, result))
        else:
            self._answer(m, srv, result)

    async def _finish_call(self, m: dict[str, Any], srv: ServiceServer, pending: Awaitable[Any]) -> None:
        try:
            result = await pending
        except Exception as exc:
            self._handler_failed(m, srv, exc)
            return
        self._answer(m, srv, result)

    def _answer(self, m: dict[str, Any], srv: ServiceServer, result: Any) -> None:
        if result is None:
            result = {}
        if not isinstance(result, dict):
            self._handler_failed(m, srv, TypeError(f"handler returned {type(result).__name__}, expected a dict"))
            return
        self._respond(m, result, True)

    def _handler_failed(self, m: dict[str, Any], srv: ServiceServer, exc: BaseException) -> None:
        """Answer a failed handler with ``result: false`` and an *object*: the response type's default
        message, with the error text in its ``message`` string field when it has one (Trigger, SetBool...).
        rosbridge 0.11 ignores ``result`` and rejects a non-object ``values``, leaving the ROS caller
        waiting forever (README point 21), so the error string alone would never reach anybody."""
        srv.failures += 1
        text = f"{type(exc).__name__}: {exc}"
        log.error("handler of %s (node %s) failed: %s", srv.service, srv.node.id, text, exc_info=exc)
        cached = self._response_defaults.get(_short(srv.type))
        if cached is not None:
            self._respond(m, _error_values(cached, text), False)
        else:
            self._spawn(self._answer_failure(m, srv, text))

    async def _answer_failure(self, m: dict[str, Any], srv: ServiceServer, text: str) -> None:
        self._respond(m, _error_values(await self._response_default(srv.type), text), False)

    async def _response_default(self, srv_type: str) -> tuple[dict[str, Any], set[str]]:
        """The default response of a service type and its string field names: from the registry when it
        knows the type, else from ``/rosapi/service_response_details`` (cached), else ``({}, set())``."""
        key = _short(srv_type)
        cached = self._response_defaults.get(key)
        if cached is not None:
            return cached
        found: tuple[dict[str, Any], set[str]] | None = None
        reg = self.registry
        if reg is not None and hasattr(reg, "has_service"):
            try:
                if reg.has_service(srv_type):
                    part = reg.service_part_name(srv_type, "response")
                    found = (reg.default(part), {f.name for f in reg.fields(part)
                                                 if f.base in ("string", "wstring") and f.array_len is None})
            except Exception as exc:
                log.debug("registry has no default response for %s: %s", srv_type, exc)
        if found is None:
            try:
                typedefs = await self.rosapi.service_response_details(srv_type, timeout=min(self.call_timeout, 2.0))
            except BridgeError as exc:
                log.warning("cannot learn the response type of %s (%s); answering the failed call with {}",
                            srv_type, exc)
                return {}, set()
            found = default_from_typedefs(typedefs)
        self._response_defaults[key] = found
        return found

    def _respond(self, m: dict[str, Any], values: Any, result: bool) -> None:
        resp: dict[str, Any] = {"op": "service_response", "service": m.get("service"), "values": values,
                                "result": result}
        if "id" in m:
            resp["id"] = m["id"]
        self._send(resp)

    # ================================================================== actions (ROS 2)

    def _send_goal(self, node: Node, action: str, action_type: str, args: dict[str, Any] | list | None,
                   feedback: Callable[[Any], None] | None, timeout: float | None, check: bool) -> ActionGoal:
        self._seq += 1
        goal = ActionGoal(node, action, action_type, f"goal:{action}:{self._seq}", feedback)
        op = {"op": "send_action_goal", "id": goal.id, "action": action, "action_type": action_type,
              "args": {} if args is None else args, "feedback": feedback is not None}
        if not self._send(op):
            goal._settle(error=NotConnectedError(f"not connected to {self.url}"))
            return goal
        self._goals[goal.id] = goal
        if timeout is not None:
            goal._timer = asyncio.get_running_loop().call_later(timeout, self._goal_timed_out, goal, timeout)
        if check:
            self._spawn(self._check_action_exists(goal))
        return goal

    def _fail_goal(self, goal: ActionGoal, error: ActionError, cancel: bool) -> None:
        if self._goals.get(goal.id) is goal:
            del self._goals[goal.id]
        if cancel and not goal.done:
            self._send({"op": "cancel_action_goal", "id": goal.id, "action": goal.action})
        if goal._settle(error=error):
            log.warning("%s", error)

    def _goal_timed_out(self, goal: ActionGoal, timeout: float) -> None:
        goal._timer = None
        self._fail_goal(goal, ActionTimeoutError(f"no result within {timeout:g} s; goal cancelled", goal.action),
                        cancel=True)

    async def _check_action_exists(self, goal: ActionGoal) -> None:
        """Fail the goal with a clear error when rosapi says the action does not exist (or cannot)."""
        try:
            servers = await self.rosapi.action_servers()
        except (ServiceTimeoutError, ConnectionLostError, NotConnectedError) as exc:
            log.debug("could not check that %s exists: %s", goal.action, exc)
            return
        except ServiceError as exc:
            if not goal.done:
                self._fail_goal(goal, ActionError(
                    f"cannot check that the action exists ({exc}); a rosbridge without /rosapi/action_servers "
                    "(ROS 1) has no ROS 2 actions (pass check=False to send anyway)", goal.action), cancel=True)
            return
        if goal.done or goal.action in servers or goal.action.lstrip("/") in (s.lstrip("/") for s in servers):
            return
        listed = ", ".join(servers) if servers else "none"
        self._fail_goal(goal, ActionError(f"action does not exist (action servers: {listed})", goal.action),
                        cancel=True)

    def _on_action_feedback(self, m: dict[str, Any]) -> None:
        goal = self._goals.get(m["id"])
        if goal is None:
            log.debug("action_feedback for unknown goal %r", m.get("id"))
            return
        goal.feedback_count += 1
        goal.last_feedback = m.get("values")
        if goal.feedback_callback is not None:
            values = m.get("values")
            try:
                goal.feedback_callback({} if values is None else values)
            except Exception:
                log.exception("feedback callback of %s raised", goal.action)

    def _on_action_result(self, m: dict[str, Any]) -> None:
        goal = self._goals.pop(m["id"], None)
        if goal is None or goal.done:
            log.debug("action_result for unknown or finished goal %r", m.get("id"))
            return
        values = m.get("values")
        status = m.get("status")
        goal.status = status if isinstance(status, int) and not isinstance(status, bool) else None
        if m.get("result", True) is False:
            text = values if isinstance(values, str) else bounded_repr(values, 200)
            goal._settle(error=ActionError(text or "the server could not run the goal", goal.action, goal.status))
        else:
            goal._settle({} if values is None else values)

    # ================================================================== misc ops

    def set_level(self, level: str) -> None:
        """Ask the server for ``status`` messages at ``level`` (info, warning, error, none); kept across
        reconnects."""
        if level not in LOG_LEVELS:
            raise ValueError(f"level must be one of {', '.join(LOG_LEVELS)}; got {level!r}")
        self._level = level
        self._send({"op": "set_level", "level": level})

    def _spawn(self, coro: Awaitable[Any]) -> asyncio.Task[Any]:
        task = asyncio.ensure_future(coro)
        self._tasks.add(task)
        task.add_done_callback(self._task_done)
        return task

    def _task_done(self, task: asyncio.Task[Any]) -> None:
        self._tasks.discard(task)
        if not task.cancelled() and task.exception() is not None:
            log.error("background task failed: %s", task.exception(), exc_info=task.exception())
