"""SimServer: a rosbridge v2 server (``websockets``) around the simulated vessel.

Every client op of rosbridge 0.11 is handled the way the real server does it (the recorded frames in
``tests/recordings/``): no acknowledgements except service responses, errors only in the log, lenient
input parsing (in linear time, see ``frames.py``). No client costs the others their latency: each connection
has its own bounded, budgeted send queue that drops old publishes but never a reply (``connection.py``),
the loop is given back after every frame a client sends, fragments are reassembled in linear time within
bounds (``fragments.py``). Incoming messages are limited to ``max_frame`` bytes (32 MB) and to a decoded-size
budget; with ``auth_secret`` nothing but one small ``auth`` op is read before a client is authenticated
(``gate.py``), and an address that keeps failing it is locked out for a while (``auth.py``). Topics
clients made are forgotten when no one publishes or subscribes them any more.
``name`` makes the sim one vessel of a fleet: its own topics, services, action and node under ``/NAME``,
its own start position and camera scene (``identity.py``); without it the sim is unchanged.
"""

from __future__ import annotations

import asyncio
import collections
import contextlib
import inspect
import itertools
import logging
import threading
import time
from collections.abc import Callable, Iterator
from typing import Any

from websockets.asyncio.server import Server, ServerConnection, serve
from websockets.exceptions import ConnectionClosed

from rcon_core import priority
from rcon_core.msgs.names import pkg_type

from . import assembly, fanout, gate, ros2_clients
from .auth import AuthLockout
from .connection import Connection, SubOptions, TopicSubscription
from .convert import ConversionError
from .encoding import bounded
from .flavour import Flavour
from .fragments import FragmentError
from .frames import parse_frame
from .graph import BRIDGE_NODE, ROSOUT_NODE, InternalCallback, Service, ServiceHandler, Topic
from .identity import Identity
from .ops import OpError, field, nonneg_int, retype
from .params import ParamTree
from .published import PublishedLog
from .services import ServiceOps
from .typesource import TypeSource

log = logging.getLogger("rcon.sim")

COMPRESSIONS = {"none", "png", "cbor", "cbor-raw"}
#: distinct (op, name) keys ``ops_received`` counts; later new names are counted under (op, OTHER_NAMES)
OPS_RECEIVED_KEYS = 10_000
OTHER_NAMES = "(other names)"
#: messages websockets reads ahead of the handler per client (its default, 16, buffered 512 MB of 32 MB frames)
READ_AHEAD = 4


class SimServer:
    """The embedded simulated robot, served over rosbridge v2."""

    def __init__(self, host: str = "127.0.0.1", port: int = 0, ros2: bool = False, rate_scale: float = 1.0,
                 auth_secret: str | None = None, *, robot: bool = True, max_frame: int = gate.DEFAULT_MAX_FRAME,
                 auth_frame_limit: int = gate.AUTH_FRAME_LIMIT, auth_timeout: float = gate.AUTH_TIMEOUT_S,
                 plugin_types: bool = False, ssl: Any = None, name: str | None = None,
                 index: int | None = None, namespace: bool = True) -> None:
        if rate_scale <= 0:
            raise ValueError(f"rate_scale must be positive, got {rate_scale}")
        if max_frame < 1024 or auth_frame_limit < 256 or auth_timeout <= 0:
            raise ValueError("max_frame must be at least 1024 bytes, auth_frame_limit at least 256 bytes and "
                             "auth_timeout positive")
        #: the vessel's name, namespace, start position and looks (``name``, ``index``, ``namespace``:
        #: whether a named vessel's topics go under /NAME; see identity.py)
        self.identity = Identity.of(name, index, namespace)
        self.max_frame = max_frame
        self.auth_frame_limit = auth_frame_limit
        self.auth_timeout = auth_timeout
        self.host = host
        self._requested_port = port
        self.ros2 = ros2
        self.rate_scale = rate_scale
        self.auth_secret = auth_secret
        self.ssl = ssl  # an ssl.SSLContext (server side): serve wss://
        self.flavour = Flavour(ros2)
        #: ``plugin_types``: also know the types installed widget plugins contribute (see TypeSource)
        self.types = TypeSource(ros2, lambda: self.flavour.time(), plugin_types=plugin_types)
        self.topics: dict[str, Topic] = {}
        self.services: dict[str, Service] = {}
        self.service_ops = ServiceOps(self)  # call_service and the services clients provide (services.py)
        self.connections: set[Connection] = set()
        self.params_tree = ParamTree()
        self.rosapi: Any = None
        self.loop: asyncio.AbstractEventLoop | None = None
        self.started_at = time.time()
        self.with_robot = robot  # start() adds the simulated vessel
        self.robot: Any = None  # the simulated vessel (vessel.Vessel); None for robot=False or before start
        #: the robot's node (its cameras, published counts: robot_node.RobotNode); None for ``robot=False``
        self.robot_node: Any = None
        self.navigate_action: Any = None  # ROS 2: the robot's action server (actions.NavigateActionServer)
        self.action_hub: Any = None  # ROS 2: ros2_actions.ActionHub
        self._server: Server | None = None
        self._port = 0
        self._client_ids = itertools.count(0)
        self.published_log = PublishedLog()  # what clients published (bounded by count and bytes)
        self._published_event: asyncio.Event | None = None
        self._tasks: set[asyncio.Task[Any]] = set()
        #: ``absorb(conn, topic, msg) -> bool``: when set and it answers True, a client's publish goes no
        #: further than this (a recording played as a robot takes commands nowhere: ``playback.py``)
        self.absorb: Callable[[Connection, str, dict[str, Any]], bool] | None = None
        #: every operation clients sent, by (op, topic/service/action name): what tests check reached it
        #: (at most OPS_RECEIVED_KEYS names; the rest under OTHER_NAMES)
        self.ops_received: collections.Counter[tuple[str, str]] = collections.Counter()
        #: failed auth ops per peer address (auth.py)
        self.auth_lockout = AuthLockout()
        #: client frames whose handling failed in an unexpected way (each logged in one bounded line)
        self.op_failures = 0

    # -- lifecycle ------------------------------------------------------------------------------------

    @property
    def port(self) -> int:
        return self._port

    @property
    def name(self) -> str | None:
        """The robot's name (None for the unnamed sim)."""
        return self.identity.name

    def topic(self, name: str) -> str:
        """The graph name of one of the robot's own topics/services/actions: ``/cmd_vel`` -> ``/boat2/cmd_vel``."""
        return self.identity.topic(name)

    @property
    def url(self) -> str:
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"{'wss' if self.ssl is not None else 'ws'}://{host}:{self._port}"

    async def start(self) -> None:
        """Bind the socket, set up rosapi and the robot (``assembly.py``), and start simulating."""
        self.loop = asyncio.get_running_loop()
        self._published_event = asyncio.Event()
        self.started_at = time.time()
        if self.types.plugin_types:
            _ = self.types.registry  # load the plugins' definitions now, not on a client's first op
        self.advertise_internal("/rosout", self.flavour.msg("rosgraph_msgs", "Log") if not self.ros2
                                else self.flavour.msg("rcl_interfaces", "Log"), ROSOUT_NODE, latched=True)
        if not self.ros2:
            self.advertise_internal("/rosout_agg", self.flavour.msg("rosgraph_msgs", "Log"), ROSOUT_NODE)
        self.advertise_internal("/client_count", self.flavour.msg("std_msgs", "Int32"), BRIDGE_NODE, latched=True)
        ros2_clients.advertise(self)
        assembly.furnish(self)
        limits: dict[str, Any] = {"max_size": self.max_frame}
        if self.auth_secret is not None:  # the first message is small; the gate raises the limit after it
            limits = {"max_size": self.auth_frame_limit,
                      "create_connection": gate.gated_connection(self.auth_secret, self.max_frame)}
        self._server = await serve(self._handle, self.host, self._requested_port, ssl=self.ssl, compression=None,
                                   ping_interval=20, ping_timeout=20, max_queue=READ_AHEAD, **limits)
        sock = next(iter(self._server.sockets))
        self._port = sock.getsockname()[1]
        self.publish("/client_count", {"data": 0}, BRIDGE_NODE)
        self.log(BRIDGE_NODE, "info", f"Rosbridge WebSocket server started on port {self._port}")
        log.info("sim %s listening on %s (ros2=%s, rate_scale=%s)", self.name or "(unnamed)", self.url, self.ros2,
                 self.rate_scale)

    async def stop(self) -> None:
        """Stop simulating and close every connection."""
        if self.robot_node is not None:
            await self.robot_node.stop()
        if self.action_hub is not None:
            await self.action_hub.stop()
        for task in list(self._tasks):
            task.cancel()
        for task in list(self._tasks):
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await task
        if self._server is not None:
            self._server.close()
            with contextlib.suppress(Exception):
                await asyncio.wait_for(self._server.wait_closed(), 5)
            self._server = None
        for conn in list(self.connections):
            await conn.close()

    async def __aenter__(self) -> SimServer:
        await self.start()
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.stop()

    @classmethod
    @contextlib.contextmanager
    def in_thread(cls, host: str = "127.0.0.1", port: int = 0, **kwargs: Any) -> Iterator[SimServer]:
        """Run a SimServer on its own event loop in a daemon thread (for sync code)."""
        server = cls(host=host, port=port, **kwargs)
        loop = asyncio.new_event_loop()
        def run() -> None:
            priority.raise_this_thread()  # the loop that receives commands (rcon_core/priority.py)
            loop.run_forever()

        thread = threading.Thread(target=run, name="rcon-sim", daemon=True)
        thread.start()
        try:
            asyncio.run_coroutine_threadsafe(server.start(), loop).result(timeout=30)
            yield server
        finally:
            with contextlib.suppress(Exception):
                asyncio.run_coroutine_threadsafe(server.stop(), loop).result(timeout=10)
            loop.call_soon_threadsafe(loop.stop)
            thread.join(timeout=10)
            if not thread.is_alive():
                loop.close()

    def run_sync(self, fn: Callable[[], Any], timeout: float = 10.0) -> Any:
        """Run a plain function on the server's loop from another thread and return its result."""
        assert self.loop is not None

        async def call() -> Any:
            return fn()

        return asyncio.run_coroutine_threadsafe(call(), self.loop).result(timeout)

    def spawn(self, coro: Any) -> asyncio.Task[Any]:
        """Run ``coro`` as a task the server cancels when it stops; what it raises is logged in one line."""
        task = asyncio.get_running_loop().create_task(coro)
        self._tasks.add(task)
        task.add_done_callback(self._task_done)
        return task

    def _task_done(self, task: asyncio.Task[Any]) -> None:
        self._tasks.discard(task)
        if not task.cancelled() and (exc := task.exception()) is not None:
            self.op_failures += 1
            log.error("a task of the sim failed: %s: %s", type(exc).__name__, bounded(str(exc)))

    # -- inspection (tests) ---------------------------------------------------------------------------

    def topic_subscriber_count(self, topic: str) -> int:
        """How many client connections are currently subscribed to ``topic``."""
        t = self.topics.get(topic)
        return len(t.client_subscribers) if t else 0

    def robot_published(self) -> dict[str, int]:
        """How many messages the robot published per topic (its names before the namespace)."""
        return dict(self.robot_node.published_counts) if self.robot_node is not None else {}

    def published(self, topic: str) -> list[dict[str, Any]]:
        """Messages clients published on ``topic`` (the most recent ones, oldest first; published.py)."""
        return self.published_log.messages(topic)

    async def wait_for_published(self, topic: str, predicate: Callable[[dict[str, Any]], bool] | None = None,
                                 timeout: float = 5.0) -> dict[str, Any]:
        """The newest message a client published on ``topic`` that fits ``predicate``, waiting for one."""
        assert self._published_event is not None, "server not started"
        deadline = time.monotonic() + timeout
        while True:
            for msg in reversed(self.published(topic)):
                if predicate is None or predicate(msg):
                    return msg
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError(f"no matching message published on {topic} within {timeout} s")
            self._published_event.clear()
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(self._published_event.wait(), left)

    def wait_for_published_sync(self, topic: str, predicate: Callable[[dict[str, Any]], bool] | None = None,
                                timeout: float = 5.0) -> dict[str, Any]:
        """``wait_for_published`` for code outside the server's loop (``in_thread``)."""
        assert self.loop is not None
        fut = asyncio.run_coroutine_threadsafe(self.wait_for_published(topic, predicate, timeout), self.loop)
        return fut.result(timeout + 5)

    # -- graph API used by the robot and rosapi -------------------------------------------------------

    def advertise_internal(self, name: str, type_name: str, node: str, latched: bool = False) -> Topic:
        topic = self.topics.get(name)
        if topic is None:
            topic = self.topics[name] = Topic(name, type_name, latched)
        topic.latched = topic.latched or latched
        topic.publishers[node] += 1
        return topic

    def subscribe_internal(self, name: str, type_name: str, node: str, callback: InternalCallback) -> Topic:
        topic = self.topics.get(name)
        if topic is None:
            topic = self.topics[name] = Topic(name, type_name)
        topic.internal_subscribers.setdefault(node, []).append(callback)
        return topic

    def add_service(self, name: str, type_name: str, node: str, handler: ServiceHandler) -> Service:
        svc = Service(name, type_name, node, handler=handler)
        self.services[name] = svc
        return svc

    def has_subscribers(self, name: str) -> bool:
        topic = self.topics.get(name)
        return topic is not None and topic.has_subscribers()

    def wants_text(self, name: str) -> bool:
        """Whether a client takes topic ``name`` as JSON text (whose ``bytes`` are then sent as base64)."""
        topic = self.topics.get(name)
        return topic is not None and fanout.wants_text(topic)

    def publish(self, name: str, msg: dict[str, Any], node: str) -> None:
        """Publish ``msg`` on topic ``name`` as ``node``: latch it, call internal subscribers, fan out."""
        topic = self.topics[name]
        header = msg.get("header")
        if isinstance(header, dict) and "seq" in header and not self.ros2:
            if topic.has_subscribers():
                topic.seq += 1
            header["seq"] = topic.seq
        if topic.latched:
            topic.latched_msgs[node] = msg
        for callbacks in list(topic.internal_subscribers.values()):
            for cb in list(callbacks):
                try:
                    cb(msg)
                except Exception:  # noqa: BLE001 - one broken callback must not stop the others
                    log.exception("subscriber callback on %s failed", name)
        if topic.client_subscribers:
            fanout.fan_out(topic, msg, self.flavour, self.types)

    def log(self, node: str, level: str, text: str, *, function: str = "", line: int = 0) -> None:
        """A /rosout line from ``node`` (``level``: debug, info, warn, error, fatal)."""
        getattr(log, {"warn": "warning", "fatal": "critical"}.get(level, level))("%s: %s", node, text)
        if "/rosout" not in self.topics:
            return
        if self.ros2:
            levels = {"debug": 10, "info": 20, "warn": 30, "error": 40, "fatal": 50}
            msg: dict[str, Any] = {"stamp": self.flavour.time(), "level": levels[level], "name": node.lstrip("/"),
                                   "msg": text, "file": "", "function": function, "line": line}
        else:
            levels = {"debug": 1, "info": 2, "warn": 4, "error": 8, "fatal": 16}
            topics = sorted(t.name for t in self.topics.values() if t.publishers[node] > 0)
            msg = {"header": self.flavour.header(""), "level": levels[level], "name": node, "msg": text,
                   "file": "", "function": function, "line": line, "topics": topics}
        self.publish("/rosout", msg, node)
        if "/rosout_agg" in self.topics:
            self.publish("/rosout_agg", dict(msg), ROSOUT_NODE)

    async def call(self, name: str, args: Any = None) -> tuple[bool, Any]:
        """Call a service of the graph: ``(True, values)`` or ``(False, error text)`` (``services.py``)."""
        return await self.service_ops.call(name, args)

    # -- connections ----------------------------------------------------------------------------------

    async def _handle(self, ws: ServerConnection) -> None:
        if self.auth_secret is not None and not await gate.authenticate(ws, self.auth_timeout, self.auth_lockout):
            return
        conn = Connection(ws, next(self._client_ids), max_frame=self.max_frame)
        conn.start()
        self.connections.add(conn)
        self.log(BRIDGE_NODE, "info", f"Client connected.  {len(self.connections)} clients total.")
        self.publish("/client_count", {"data": len(self.connections)}, BRIDGE_NODE)
        ros2_clients.publish(self)
        try:
            async for message in ws:
                try:
                    await self._receive(conn, message)
                except Exception as exc:  # noqa: BLE001 - bad input never takes the connection down
                    self._failed(conn, "a frame", exc)
                # fairness: the others (and the robot's timers) get the loop between two frames of one client,
                # which is read within its budget, and not while its unread replies pile up (connection.py)
                await conn.read_pause(len(message))
                await conn.room_for_replies()
        except ConnectionClosed:
            pass
        finally:
            self.connections.discard(conn)
            self._cleanup(conn)
            await conn.close()
            with contextlib.suppress(Exception):
                await ws.close()
            self.log(BRIDGE_NODE, "info", f"Client disconnected. {len(self.connections)} clients total.")
            if "/client_count" in self.topics:
                self.publish("/client_count", {"data": len(self.connections)}, BRIDGE_NODE)
            ros2_clients.publish(self)

    def _cleanup(self, conn: Connection) -> None:
        for name in list(conn.subscriptions):
            topic = self.topics.get(name)
            if topic is not None:
                topic.client_subscribers.discard(conn)
                self._forget_if_unused(name)
        conn.subscriptions.clear()
        conn.fragments.clear()
        for name in list(conn.advertised):
            self._unadvertise(conn, name)
        self.service_ops.connection_closed(conn)
        if self.action_hub is not None:
            self.action_hub.connection_closed(conn)

    async def _receive(self, conn: Connection, message: str | bytes) -> None:
        frames = parse_frame(message, conn.label, warn=conn.log)
        conn.frame_size = len(message) // max(1, len(frames))  # what one message of this frame weighs
        for frame in frames:
            await self._dispatch(conn, frame)

    def _failed(self, conn: Connection, what: str, exc: BaseException, msg: Any = None) -> None:
        """A frame whose handling raised unexpectedly: one bounded line (rate limited per client), counted."""
        self.op_failures += 1
        ident = f"[id: {bounded(repr(msg.get('id')), 60)}] " if isinstance(msg, dict) and "id" in msg else ""
        conn.log(logging.ERROR, "%sfailed to handle %s: %s: %s", ident, bounded(what, 60), type(exc).__name__,
                 bounded(str(exc)), logger=log)

    async def _dispatch(self, conn: Connection, msg: Any) -> None:
        if not isinstance(msg, dict) or "op" not in msg:
            if isinstance(msg, dict) and "receiver" in msg:
                conn.log(logging.ERROR, "Received a rosbridge v1.0 message.  Please refer to rosbridge.org for the "
                         "correct format of rosbridge v2.0 messages.", logger=log)
            else:
                conn.log(logging.ERROR, "Received a message without an op.  All messages require 'op' field with "
                         "value one of: %s.", sorted(self._ops()), logger=log)
            return
        op = msg["op"]
        target = msg.get("topic") or msg.get("service") or msg.get("action") or ""
        self._count_op(conn, str(op)[:40], target if isinstance(target, str) else "")
        handler = self._ops().get(op) if isinstance(op, str) else None
        if handler is None:
            conn.log(logging.ERROR, "[id: %s] Unknown operation: %s.  Allowed operations: %s",
                     bounded(str(msg.get("id")), 60), bounded(str(op), 60), sorted(self._ops()), logger=log)
            return
        try:
            result = handler(conn, msg)
            if inspect.isawaitable(result):
                await result
        except (OpError, FragmentError) as exc:
            conn.log(logging.ERROR, "[id: %s] %s: %s", bounded(str(msg.get("id")), 60), op, bounded(str(exc), 300),
                     logger=log)
        except Exception as exc:  # noqa: BLE001 - a malformed op is one bounded line, never a traceback
            self._failed(conn, f"op {op}", exc, msg)

    def _count_op(self, conn: Connection, op: str, name: str) -> None:
        for counts in (self.ops_received, conn.ops_received):
            key = (op, name)
            if key not in counts and len(counts) >= OPS_RECEIVED_KEYS:
                key = (op, OTHER_NAMES)
            counts[key] += 1

    def _ops(self) -> dict[str, Callable[[Connection, dict[str, Any]], Any]]:
        ops: dict[str, Callable[[Connection, dict[str, Any]], Any]] = {
            "advertise": self._op_advertise,
            "unadvertise": self._op_unadvertise,
            "publish": self._op_publish,
            "subscribe": self._op_subscribe,
            "unsubscribe": self._op_unsubscribe,
            "fragment": self._op_fragment,
            "set_level": lambda conn, msg: None,
            "auth": lambda conn, msg: None,  # already authenticated (or no auth configured)
        }
        ops.update(self.service_ops.ops())
        if self.action_hub is not None:
            ops.update(self.action_hub.ops())
        return ops

    # -- topic ops ------------------------------------------------------------------------------------

    def _op_advertise(self, conn: Connection, msg: dict[str, Any]) -> None:
        name = field(msg, "topic", str)
        type_name = field(msg, "type", str)
        if not self.types.has(type_name):
            raise OpError(f"Unable to import msg class {type_name.rsplit('/', 1)[-1]} from package "
                           f"{type_name.split('/', 1)[0]}")
        topic = self.topics.get(name)
        if topic is not None and topic.is_alive() and pkg_type(topic.type) != pkg_type(type_name):
            raise OpError(f"Tried to register topic {name} with type {type_name} but it is already "
                           f"established with type {topic.type}")
        latch = bool(msg.get("latch", False))
        if name in conn.advertised:
            if topic is not None:
                topic.latched = topic.latched or latch
            return
        if topic is None or not topic.is_alive():
            topic = self.topics[name] = Topic(name, self.flavour.wire(type_name), latch) if topic is None \
                else retype(topic, self.flavour.wire(type_name))
        topic.latched = topic.latched or latch
        topic.publishers[BRIDGE_NODE] += 1
        conn.advertised[name] = topic.type
        log.info("%s Advertised %s", conn.label, name)

    def _op_unadvertise(self, conn: Connection, msg: dict[str, Any]) -> None:
        name = field(msg, "topic", str)
        if name not in conn.advertised:
            raise OpError(f"Topic {name} has not been advertised by this client")
        self._unadvertise(conn, name)

    def _unadvertise(self, conn: Connection, name: str) -> None:
        conn.advertised.pop(name, None)
        topic = self.topics.get(name)
        if topic is not None:
            topic.publishers[BRIDGE_NODE] -= 1
            if topic.publishers[BRIDGE_NODE] <= 0:
                del topic.publishers[BRIDGE_NODE]
                topic.latched_msgs.pop(BRIDGE_NODE, None)
            self._forget_if_unused(name)

    def _forget_if_unused(self, name: str) -> None:
        """Forget a topic no one publishes, subscribes or latched on (100,000 made /rosapi/topics 455 ms)."""
        topic = self.topics.get(name)
        if topic is not None and not topic.is_alive() and not topic.latched_msgs:
            del self.topics[name]

    def _op_publish(self, conn: Connection, msg: dict[str, Any]) -> None:
        name = field(msg, "topic", str)
        topic = self.topics.get(name)
        if topic is None or not topic.is_alive():
            raise OpError(f"Cannot infer topic type for topic {name} as it is not yet advertised")
        if name not in conn.advertised:  # publish without advertise: rosbridge registers a publisher
            conn.advertised[name] = topic.type
            topic.publishers[BRIDGE_NODE] += 1
        if msg.get("latch"):
            topic.latched = True
        body = msg.get("msg", {})
        converter = self.types.converter(topic.type)
        if converter is not None:
            try:
                body = converter.convert(body)
            except ConversionError as exc:
                raise OpError(str(exc)) from exc
        elif not isinstance(body, dict):
            raise OpError(f"Expected a JSON object for type {topic.type}")
        self.published_log.add(name, body, conn.frame_size)
        assert self._published_event is not None
        self._published_event.set()
        if self.absorb is not None and self.absorb(conn, name, body):
            return
        self.publish(name, body, BRIDGE_NODE)

    def _op_subscribe(self, conn: Connection, msg: dict[str, Any]) -> None:
        name = field(msg, "topic", str)
        type_name = msg.get("type")
        if type_name is not None and not isinstance(type_name, str):
            raise OpError(f"Expected field type to be one of (<class 'str'>,). Invalid value: {type_name}")
        topic = self.topics.get(name)
        if topic is None or not topic.is_alive():
            if not type_name:
                raise OpError(f"Cannot infer topic type for topic {name} as it is not yet advertised")
            if not self.types.has(type_name):
                raise OpError(f"Unable to load the type {type_name}")
            topic = self.topics[name] = Topic(name, self.flavour.wire(type_name)) if topic is None \
                else retype(topic, self.flavour.wire(type_name))
        elif type_name and pkg_type(type_name) != pkg_type(topic.type):
            raise OpError(f"Tried to register topic {name} with type {type_name} but it is already established "
                           f"with type {topic.type}")
        fragment_size = msg.get("fragment_size")
        if isinstance(fragment_size, int) and not isinstance(fragment_size, bool) and fragment_size > 0:
            conn.fragment_size = fragment_size
        sub_id = msg.get("id")
        if isinstance(sub_id, dict | list):
            raise OpError(f"Expected field id to be a string or a number. Invalid value: {bounded(str(sub_id), 60)}")
        compression = msg.get("compression") or "none"
        if not isinstance(compression, str) or compression not in COMPRESSIONS:
            conn.log(logging.WARNING, "unknown compression %s, sending plain JSON", bounded(repr(compression), 60),
                     logger=log)
            compression = "none"
        options = SubOptions(
            throttle_rate=nonneg_int(msg.get("throttle_rate")),
            queue_length=nonneg_int(msg.get("queue_length")),
            compression=compression,
        )
        sub = conn.subscriptions.get(name)
        if sub is None:
            sub = conn.subscriptions[name] = TopicSubscription(name, topic.type)
        sub.ids[sub_id] = options
        sub.compression = compression
        first = conn not in topic.client_subscribers
        topic.client_subscribers.add(conn)
        log.info("%s Subscribed to %s", conn.label, name)
        if first and topic.latched_msgs:
            now = time.monotonic()
            for latched in list(topic.latched_msgs.values()):
                payload = fanout.encoded({}, topic, latched, sub.compression, self.flavour, self.types)
                if payload is not None:
                    conn.send(payload, topic=name, fragment_size=conn.fragment_size)
            sub.last_sent = now

    def _op_unsubscribe(self, conn: Connection, msg: dict[str, Any]) -> None:
        name = field(msg, "topic", str)
        sub = conn.subscriptions.get(name)
        if sub is None:
            return
        sub_id = msg.get("id")
        if sub_id is None:
            sub.ids.clear()
        elif not isinstance(sub_id, dict | list):
            sub.ids.pop(sub_id, None)
        if not sub.ids:
            del conn.subscriptions[name]
            topic = self.topics.get(name)
            if topic is not None:
                topic.client_subscribers.discard(conn)
                self._forget_if_unused(name)
            log.info("%s Unsubscribed from %s", conn.label, name)

    def _op_fragment(self, conn: Connection, msg: dict[str, Any]) -> None:
        """Reassemble fragments a client sends (by id; linear and bounded, fragments.py), then handle the
        joined frame (in a task of its own: a joined frame may hold fragments again)."""
        text = conn.fragments.add(msg)
        if text is not None:
            self.spawn(self._receive(conn, text))
