"""``Session``: the rosbridge protocol state of one client, apart from the transport.

As ``websockets`` keeps its protocol apart from asyncio, the session keeps what the protocol is about --
nodes, topics and their shared subscriptions (``topics.py``), advertisements, services this client provides
(``services.py``), service calls waiting for their answer, action goals (``goals.py``) and actions this
client provides (``action_server.py``) -- and none of the connection: events in (:meth:`Session.handle` for
each op from the server, :meth:`attached` / :meth:`detached` when a link comes and goes), frames out through
the :class:`~rcon_core.bridge.wslink.Link` the client attached (nothing is written while there is none),
and public methods for the nodes.  ``BridgeClient`` (``client.py``) keeps connect, reconnect, ping, stall
watch and writing; ``inbound.py`` reads.

Decision: after every (re)connect
    rosbridge forgets everything with the connection (``reconnect.jsonl:8``), so :meth:`attached` sends, after
    the client's ``auth``: ``set_level`` (when set), every advertisement (and the latest value of a latched
    topic published while down), every advertised service and action, then every subscription.

Decision: publishing while the link is down or stalled
    Nothing is queued for later, so a robot never receives a burst of stale commands.  For a **latched**
    topic only the latest value is kept and sent right after the advertisement is restored; every other
    publish made while down is dropped and counted (``Publisher.dropped``, ``stats.dropped_while_down``).
    Frames still in the outgoing queue when the link drops are dropped too (``stats.dropped_on_disconnect``).
    A publisher's ``max_age`` (0.25 s by default for non-latched topics) is its freshness limit: a publish
    is never written after it (``wslink.Link.send_command``, ``freshness.py``; ``stats.stale_dropped``).
    The frame around a message is encoded once per advertisement (``AdvertEntry.head``); ``latch`` is
    repeated in every publish (``client_publish.jsonl:26-30``: otherwise the topic is re-registered).

Decision: service calls
    Every call has a client-side timeout (``timeout`` or ``call_timeout``) even though rosbridge 0.11 and
    2.1.0 ignore the ``timeout`` field; a missing or hung service raises ``ServiceTimeoutError``, whose text
    names the op and the service.  rosbridge answers a request it cannot run -- an unknown op, a missing or
    mistyped field, text that is not JSON -- with silence (``rosbridge-ros2-2.1.0/malformed.jsonl``), and
    2.1.0 runs one call at a time per connection with no timeout, so one unanswered call holds up every
    later call on that connection (``services.jsonl:20-25``): a timeout that follows an earlier call still
    unanswered says so, naming it.  A late answer to a call that timed out is dropped quietly.  A call made
    while reconnecting waits for the link inside the same budget.  Calls waiting when the link drops fail
    with ``ConnectionLostError``.  ``result: false`` raises ``ServiceError`` carrying the server's string.

Decision: a view-only link (``guard.py``)
    ``self.guard`` (``client.guard``) decides what a view-only link may send: :meth:`publish` and
    :meth:`call_service` refuse with ``ViewOnlyError`` before anything is written, every frame of
    :meth:`send` passes ``guard.admit``, and setting or lifting the mark withdraws or offers again this
    link's advertisements, services and actions (:meth:`_guard_changed`).

What the session needs of its host (the client), by public names only: ``url``, ``call_timeout``,
``registry``, ``rosapi``, ``ros_version``, ``stats`` and ``await wait_connected()``.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Awaitable, Callable
from typing import TYPE_CHECKING, Any, Protocol

import orjson

from rcon_core.msgs import names

from .action_server import ProvidedActions
from .envelope import Envelope, enforce
from .errors import BridgeError, ConnectionLostError, ServiceError, ServiceTimeoutError
from .goals import Goals
from .guard import LinkGuard, ViewOnlyError, describe_call
from .inbound import BadFrames
from .protocol import encode
from .safety import MAX_ANSWER_DEPTH, LogBudget, bounded_repr, clip, nested_deeper, safe_text
from .services import ProvidedServices
from .stats import BridgeStats
from .subscribe import Subscriber
from .tap import OperatorTap
from .topics import AdvertEntry, TopicEntry

if TYPE_CHECKING:
    from .nodes import Node, Publisher, Subscription
    from .wslink import Link

log = logging.getLogger(__name__)
#: characters of a server's ``status`` text that are logged and shown (a server sent 10 MB lines)
STATUS_TEXT = 500

_dumps = orjson.dumps
_NUMPY = orjson.OPT_SERIALIZE_NUMPY
LOG_LEVELS = ("info", "warning", "error", "none")


class Host(Protocol):
    url: str
    call_timeout: float
    registry: Any
    rosapi: Any
    stats: BridgeStats

    @property
    def ros_version(self) -> int | None: ...

    async def wait_connected(self) -> None: ...


def _failure_text(values: Any) -> str:
    """The text of a ``result: false`` answer: rosbridge's string, or the ``message`` of an object answer
    (what a failed RCON handler sends), else the whole value."""
    if isinstance(values, str):
        return values
    if isinstance(values, dict) and isinstance(values.get("message"), str) and values["message"]:
        return values["message"]
    return bounded_repr(values, 200)


class Session:
    """The protocol state of one client (see the module docstring)."""

    def __init__(self, host: Host, bad: BadFrames) -> None:
        self.host = host
        self.bad = bad
        self.stats = host.stats
        self.link: Link | None = None
        self.nodes: dict[str, Node] = {}
        self.topics: dict[str, TopicEntry] = {}
        self.adverts: dict[str, AdvertEntry] = {}
        self.pending: dict[str, asyncio.Future[Any]] = {}  # service calls waiting for their answer
        #: calls that timed out and were never answered on this link: id -> service (bounded)
        self.unanswered: dict[str, str] = {}
        self._pending_names: dict[str, str] = {}  # id -> service of the calls in self.pending
        self.level: str | None = None
        #: the robot's safety envelope (``envelope.py``): every publish is held to it (``client.envelope``)
        self.envelope: Envelope | None = None
        self.tasks: set[asyncio.Task[Any]] = set()
        self._seq = 0
        self.services = ProvidedServices(self.send, self.spawn, host)
        self.goals = Goals(self.send, self.spawn, host)
        self.provided_actions = ProvidedActions(self.send)  # actions this client serves (ROS 2)
        self.subscriber = Subscriber(self, host)
        #: what the nodes send, told to listeners (the flight recorder): ``tap.py``
        self.tap = OperatorTap()
        #: whether this link is view-only, and what it offered the robot (``guard.py``)
        self.guard = LinkGuard(host.url)
        self.guard.add_listener(self._guard_changed)
        self._status_listeners: list[Callable[[dict[str, Any]], None]] = []
        #: the rate at which the server's ``status`` messages are logged (see ``_on_status``)
        self.status_log = LogBudget()
        self._ops: dict[str, Callable[[dict[str, Any]], None]] = {
            "publish": self._on_publish, "service_response": self._on_service_response,
            "call_service": self.services.on_call, "status": self._on_status,
            "action_feedback": self.goals.on_feedback, "action_result": self.goals.on_result,
            "send_action_goal": self.provided_actions.on_goal, "cancel_action_goal": self.provided_actions.on_cancel,
        }

    def next_id(self, kind: str, name: str) -> str:
        self._seq += 1
        return f"{kind}:{name}:{self._seq}"

    # ================================================================== frames out

    def send(self, op: dict[str, Any]) -> bool:
        """Send one frame on the current link; False when there is none."""
        link = self.link
        if link is None or not self.guard.admit(op):
            return False
        link.write(encode(op))
        return True

    def spawn(self, coro: Awaitable[Any]) -> asyncio.Task[Any]:
        task = asyncio.ensure_future(coro)
        self.tasks.add(task)
        task.add_done_callback(self._task_done)
        return task

    def _task_done(self, task: asyncio.Task[Any]) -> None:
        self.tasks.discard(task)
        if not task.cancelled() and task.exception() is not None:
            log.error("background task failed: %s", task.exception(), exc_info=task.exception())

    def cancel_tasks(self) -> None:
        for t in list(self.tasks):
            t.cancel()

    # ================================================================== the link comes and goes

    def attached(self, link: Link) -> None:
        """A fresh connection (after the client sent ``auth``): restore everything rosbridge forgot."""
        self.link = link
        self.guard.attached(asyncio.get_running_loop())
        if self.level is not None:
            self.send({"op": "set_level", "level": self.level})
        for advert in self.adverts.values():
            advert.active = False
            advert.active = self.send(advert.advertise_op())  # not on a view-only link (guard.py)
            if advert.pending is not None and advert.active:
                link.write(b"".join((advert.head, _dumps(advert.pending, option=_NUMPY), advert.tail)))
            advert.pending = None
        self.services.restore()
        self.provided_actions.restore()
        for topic in self.topics.values():
            topic.sid = None
            topic.sent_options = None
            self.subscriber.sync(topic)

    def detached(self) -> None:
        """The link is gone: frames still queued are dropped, calls and goals fail, served goals end."""
        link, self.link = self.link, None
        if link is not None:
            dropped = link.drop_queue()
            if dropped:
                self.stats.dropped_on_disconnect += dropped
        for advert in self.adverts.values():
            advert.active = False
        for topic in self.topics.values():
            topic.sid = None
            topic.sent_options = None
        for fut in list(self.pending.values()):
            if not fut.done():
                fut.set_exception(ConnectionLostError("connection lost before the answer arrived"))
        self.pending.clear()
        self.unanswered.clear()
        self.goals.disconnected()
        self.provided_actions.disconnected()

    def _guard_changed(self, view_only: bool) -> None:
        """The link was marked view-only (withdraw what it offered the robot) or the mark was lifted
        (offer it again); on the loop thread."""
        if self.link is None:
            return  # the next connection restores under the mark as it is then
        if view_only:
            for op in self.guard.withdrawals():
                self.send(op)
            for advert in self.adverts.values():
                advert.active = False
                advert.pending = None
            self.provided_actions.disconnected()  # goals being served end (their results are not sent)
            return
        for advert in self.adverts.values():
            if not advert.active:
                advert.active = self.send(advert.advertise_op())
        self.services.restore()
        self.provided_actions.restore()

    # ================================================================== events in

    def handle(self, m: Any) -> None:
        """One op from the server (not the fast path of ``inbound.py``); bad frames are counted, not raised."""
        if not isinstance(m, dict):
            self.bad.report("shape", f"frame is a JSON {type(m).__name__}, not an object; ignored")
            return
        op = m.get("op")
        handler = self._ops.get(op) if isinstance(op, str) else None
        if handler is None:
            if "op" not in m:
                self.bad.report("op", f"frame without 'op' ignored: {bounded_repr(m, 80)}")
            else:
                self.bad.report("op", f"unknown op {bounded_repr(op, 80)} ignored")
            return
        try:
            handler(m)
        except (KeyError, TypeError, ValueError, AttributeError) as exc:
            self.bad.report("field", f"malformed {op!r} frame ignored ({safe_text(exc)})")

    def _on_publish(self, m: dict[str, Any]) -> None:
        topic = m.get("topic")
        if not isinstance(topic, str):
            raise TypeError(f"'topic' must be a string, got {type(topic).__name__}")
        if "msg" not in m:
            raise KeyError("publish frame has no 'msg'")
        entry = self.topics.get(topic)
        if entry is None:
            return
        msg = m["msg"]
        if not isinstance(msg, dict):
            self.stats.non_object_msgs += 1
            self.bad.report("msg", f"publish on {topic}: 'msg' is a JSON {type(msg).__name__}, not an object; "
                                   "dropped")
            return
        entry.deliver(msg)

    def _on_service_response(self, m: dict[str, Any]) -> None:
        cid = m.get("id")
        fut = self.pending.pop(cid, None) if isinstance(cid, str) else None
        if fut is None:
            late = self.unanswered.pop(cid, None) if isinstance(cid, str) else None
            log.debug("service_response for unknown or finished call %r%s", cid,
                      f" (a late answer from {late})" if late else "")
            return
        if fut.done():
            return
        values = m.get("values")
        service = m.get("service") if isinstance(m.get("service"), str) else None
        if nested_deeper(values):  # bounded for everything that walks an answer (see safety.py)
            self.bad.report("depth", f"answer of {bounded_repr(service, 80)} nested deeper than "
                                     f"{MAX_ANSWER_DEPTH} levels; the call failed")
            fut.set_exception(ServiceError(f"the answer is nested deeper than {MAX_ANSWER_DEPTH} levels; refused",
                                           service))
        elif m.get("result", True) is False:
            fut.set_exception(ServiceError(_failure_text(values), service))
        else:
            fut.set_result({} if values is None else values)

    def add_status_listener(self, fn: Callable[[dict[str, Any]], None]) -> Callable[[], None]:
        self._status_listeners.append(fn)
        return lambda: self._status_listeners.remove(fn) if fn in self._status_listeners else None

    def _on_status(self, m: dict[str, Any]) -> None:
        """A ``status`` op: logged cut to ``STATUS_TEXT`` characters and at most ``status_log``'s rate (the
        rest counted in ``stats["status_not_logged"]`` and said with the next line); an error naming a call
        or goal fails it with the same cut text."""
        level = m.get("level", "info")
        text = m.get("msg", "")
        sid = m.get("id")
        if not isinstance(level, str):
            level = bounded_repr(level, 40)
        text = clip(text, STATUS_TEXT) if isinstance(text, str) else bounded_repr(text, 200)
        held = self.status_log.take()
        if held is None:
            self.stats.status_not_logged += 1
        else:
            pylevel = {"error": logging.ERROR, "warning": logging.WARNING}.get(clip(level, 20), logging.INFO)
            more = f" ({held} more status messages were not logged)" if held else ""
            log.log(pylevel, "server status (%s)%s: %s%s", clip(level, 20),
                    f" for {bounded_repr(sid, 80)}" if sid else "", text, more)
        if level == "error" and isinstance(sid, str):
            fut = self.pending.pop(sid, None)
            if fut is not None and not fut.done():
                fut.set_exception(ServiceError(text))
            self.goals.on_error_status(sid, text)
        for fn in list(self._status_listeners):
            try:
                fn(m)
            except Exception:
                log.exception("status listener raised")

    # ================================================================== for the nodes

    def node_closed(self, node: Node) -> None:
        if self.nodes.get(node.id) is node:
            del self.nodes[node.id]

    def set_level(self, level: str) -> None:
        if level not in LOG_LEVELS:
            raise ValueError(f"level must be one of {', '.join(LOG_LEVELS)}; got {level!r}")
        self.level = level
        self.send({"op": "set_level", "level": level})

    def add_subscription(self, sub: Subscription) -> None:
        entry = self.topics.get(sub.topic)
        if entry is None:
            entry = self.topics[sub.topic] = TopicEntry(sub.topic, self.bad.report)
        entry.subs.append(sub)
        entry.rebuild()
        self.subscriber.sync(entry)

    def remove_subscription(self, sub: Subscription) -> None:
        entry = self.topics.get(sub.topic)
        if entry is None or sub not in entry.subs:
            return
        entry.subs.remove(sub)
        if not entry.subs:
            del self.topics[sub.topic]
            if entry.sid is not None:
                self.send({"op": "unsubscribe", "id": entry.sid, "topic": entry.topic})
            entry.sid = None
            entry.raw_type = None
            entry.rebuild()
            return
        entry.rebuild()
        self.subscriber.sync(entry)

    def add_publisher(self, pub: Publisher) -> None:
        entry = self.adverts.get(pub.topic)
        if entry is None:
            entry = self.adverts[pub.topic] = AdvertEntry(pub.topic, pub.type)
        elif names.pkg_type(entry.type) != names.pkg_type(pub.type):
            raise BridgeError(f"{pub.topic} is already advertised as {entry.type}, not {pub.type}")
        entry.pubs.append(pub)
        changed = entry.merge()
        if self.link is not None and (not entry.active or changed):
            entry.active = self.send(entry.advertise_op())  # False on a view-only link

    def remove_publisher(self, pub: Publisher) -> None:
        entry = self.adverts.get(pub.topic)
        if entry is None or pub not in entry.pubs:
            return
        entry.pubs.remove(pub)
        if not entry.pubs:
            del self.adverts[pub.topic]
            if entry.active:
                self.send({"op": "unadvertise", "id": f"adv:{entry.topic}", "topic": entry.topic})
            return
        entry.merge()

    def publish(self, pub: Publisher, msg: dict[str, Any]) -> bool:
        """Write one message now, or drop it (counted) -- see "publishing while the link is down".
        Raises ``ViewOnlyError`` on a view-only link. A motion command is first held to the safety envelope
        (``envelope.py``; raises ``EnvelopeRefused``)."""
        if self.guard.reason is not None:
            raise self.guard.refuse(f"publishing on {pub.topic}")
        entry = self.adverts[pub.topic]
        msg = enforce(self.envelope, entry.type, msg, self.stats)
        link = self.link
        if link is not None and entry.active:
            data = b"".join((entry.head, _dumps(msg, option=_NUMPY), entry.tail))
            if pub.max_age is None:
                link.write(data)
            elif not link.send_command(data, pub, pub.max_age):
                self.drop_stale(pub)
                return False
            pub.sent += 1
            return True
        if entry.latch:
            entry.pending = msg  # latest value wins; sent after the advertisement is restored
            return True
        pub.dropped += 1
        entry.dropped += 1
        self.stats.dropped_while_down += 1
        return False

    def drop_stale(self, pub: Publisher, counted_sent: bool = False) -> None:
        """Count a command dropped at its freshness limit (``counted_sent``: it was already counted sent)."""
        if counted_sent:
            pub.sent -= 1
        pub.dropped += 1
        self.stats.stale_dropped += 1

    def stale_in_queue(self, pub: Publisher) -> None:
        """A queued command passed its deadline (the link's writer drops it)."""
        self.drop_stale(pub, counted_sent=True)

    async def call_service(self, name: str, args: dict[str, Any] | list | None = None,
                           timeout: float | None = None) -> Any:
        """Call a service; returns its ``values``.  Raises ServiceError / ServiceTimeoutError."""
        if not isinstance(name, str) or not name:
            raise ValueError(f"service name must be a non-empty string, got {name!r}")
        if args is not None and not isinstance(args, dict | list):
            raise TypeError(f"args must be a dict or list, got {type(args).__name__}")
        self.guard.check_call(name, args)  # ViewOnlyError on a view-only link, unless it only reads
        budget = self.host.call_timeout if timeout is None else timeout
        cid = self.next_id("call", name)
        op: dict[str, Any] = {"op": "call_service", "id": cid, "service": name}
        if args is not None:
            op["args"] = args
        if timeout is not None:
            op["timeout"] = timeout
        fut: asyncio.Future[Any] = asyncio.get_running_loop().create_future()
        try:
            async with asyncio.timeout(budget):
                await self.host.wait_connected()
                self.pending[cid] = fut
                self._pending_names[cid] = name
                if not self.send(op) and self.guard.view_only:  # marked while it waited for the link
                    raise ViewOnlyError(self.guard.sentence(describe_call(name, args)))
                return await fut
        except TimeoutError:
            before = list(self._pending_names)[: list(self._pending_names).index(cid)] \
                if cid in self._pending_names else []
            earlier = list(self.unanswered.values()) + [self._pending_names[c] for c in before]
            text = f"no answer to call_service within {budget:g} s"
            if earlier:
                text += (f"; an earlier call on this connection ({earlier[0]}) is still unanswered, and rosbridge "
                         "2.1.0 runs calls one at a time")
            if self.link is not None:
                self.unanswered[cid] = name
                while len(self.unanswered) > 32:
                    self.unanswered.pop(next(iter(self.unanswered)))
            raise ServiceTimeoutError(text, name) from None
        finally:
            self.pending.pop(cid, None)
            self._pending_names.pop(cid, None)
