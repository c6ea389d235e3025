"""``Session``: the rosbridge protocol state of one client, apart from the transport: sans-I/O.

A state machine in the manner of h11 and websockets' ``protocol.py`` (and of the Foxglove link's
``rcon_core/foxglove/session.py``): it keeps what the protocol is about -- nodes, topics and their shared
subscriptions (``topics.py``), advertisements, service calls waiting for their answer, the commands-held
watch, the view-only guard -- and none of the connection.  It imports no asyncio, makes no future, task or
timer and never touches a socket (``tests/test_bridge_session_pure.py`` holds that):

* frames in: :meth:`Session.handle` for each op from the server; :meth:`attached` / :meth:`detached` when a
  connection comes and goes;
* frames out as data: every frame the protocol sends is an :class:`Outgoing` appended to :attr:`outbox`,
  which the async shell drains (``shell.py``: it is told through ``wake`` right away, so frames keep their
  order and nothing waits); a publish is decided by :meth:`command`, which returns an :class:`Outgoing`
  (the bytes and, for a command, its deadline), :data:`KEPT` (a latched value held for the restore) or a
  :class:`Dropped`; the nodes' ``publish`` decides the same way and hands the frame to the link's
  ``write``/``send_by`` the shell lent while attached (one call on the hot path), else to the outbox;
* time in: the ``now`` of :meth:`command` and :meth:`take`, and the injectable ``clock`` (a publish's deadline,
  the commands-held watch);
* service calls as data: :meth:`open_call` makes a :class:`Call`, :meth:`start_call` sends it, the answer (or
  the failure) comes back through its ``done`` callback; futures and timeouts live in the shell (``shell.py``).
  (:class:`Outgoing`, :class:`Dropped`, :data:`KEPT` and :class:`Call` are defined in ``effects.py``.)

What runs user code or waits on the server -- services this client provides (``services.py``), action goals
(``goals.py``), actions this client provides (``action_server.py``) and the type lookups behind a cbor or
png subscription (``subscribe.py``) -- are the session's *parts*: the shell builds them
(:meth:`~rcon_core.bridge.shell.SessionShell.build_parts`) with its ``spawn`` and hands them over
(:meth:`Session.use_parts`); the session only dispatches frames to them and restores them in order.
``BridgeClient`` (``client.py``) keeps connect, reconnect, ping, stall watch; ``inbound.py`` reads.

Decision: after every (re)connect
    rosbridge forgets everything with the connection (``reconnect.jsonl:8``), so :meth:`attached` sends, after
    the client's ``auth``: ``set_level`` (when set), every advertisement (and the latest value of a latched
    topic published while down), every advertised service and action, then every subscription.

Decision: publishing while the link is down or stalled
    Nothing is queued for later, so a robot never receives a burst of stale commands.  For a **latched**
    topic only the latest value is kept and sent right after the advertisement is restored; every other
    publish made while down is dropped and counted (``Publisher.dropped``, ``stats.dropped_while_down``).
    Frames still in the outgoing queue when the link drops are dropped too (``stats.dropped_on_disconnect``).
    A publisher's ``max_age`` (0.25 s by default for non-latched topics) is its freshness limit: the
    :class:`Outgoing` of a command carries ``now + max_age`` as its deadline and is never written after it
    (``linkbase.Link.send_by``, ``freshness.py``; ``stats.stale_dropped``); a frame left in :attr:`outbox`
    past its deadline is dropped by :meth:`take` as well.  The frame around a message is encoded once per
    advertisement (``AdvertEntry.head``); ``latch`` is repeated in every publish (``client_publish.jsonl:26-30``:
    otherwise the topic is re-registered).

Decision: service calls
    Every call has a client-side timeout (``timeout`` or ``call_timeout``) even though rosbridge 0.11 and
    2.1.0 ignore the ``timeout`` field; a missing or hung service raises ``ServiceTimeoutError``, whose text
    names the op and the service.  rosbridge answers a request it cannot run -- an unknown op, a missing or
    mistyped field, text that is not JSON -- with silence (``rosbridge-ros2-2.1.0/malformed.jsonl``), and
    2.1.0 runs one call at a time per connection with no timeout, so one unanswered call holds up every
    later call on that connection (``services.jsonl:20-25``): a timeout that follows an earlier call still
    unanswered says so, naming it (:meth:`timed_out`).  A late answer to a call that timed out is dropped
    quietly.  A call made while reconnecting waits for the link inside the same budget (the shell).  Calls
    waiting when the link drops fail with ``ConnectionLostError``.  ``result: false`` fails with
    ``ServiceError`` carrying the server's string.  Every call written is watched until its answer arrives
    (``held.py``, :attr:`Session.held`): one unanswered past 0.5 s on a server that may run calls one at a
    time is reported as commands held.

Decision: a view-only link (``guard.py``)
    ``self.guard`` (``client.guard``) decides what a view-only link may send: :meth:`publish`,
    :meth:`command` and :meth:`open_call` refuse with ``ViewOnlyError`` before anything is written (and
    :meth:`start_call`, when the mark came while the call waited for the link), every frame of
    :meth:`send` passes ``guard.admit``, and setting or lifting the mark withdraws or offers again this
    link's advertisements, services and actions (:meth:`_guard_changed`).

What the session needs of its host (the client), by public names only: ``url``, ``stats`` and
``ros_version``.
"""

from __future__ import annotations

import logging
import time
from collections import deque
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Protocol

import orjson

from rcon_core.msgs import names

from .effects import DOWN, KEPT, Call, Done, Dropped, Kept, Outgoing
from .envelope import Envelope, enforce
from .errors import BridgeError, ConnectionLostError, ServiceError, ServiceTimeoutError
from .guard import LinkGuard, ViewOnlyError, describe_call
from .held import HeldWatch
from .protocol import encode
from .safety import MAX_ANSWER_DEPTH, LogBudget, bounded_repr, clip, nested_deeper, safe_text
from .stats import BridgeStats
from .tap import OperatorTap
from .topics import AdvertEntry, TopicEntry

if TYPE_CHECKING:
    from .action_server import ProvidedActions
    from .goals import Goals
    from .inbound import BadFrames
    from .nodes import Node, Publisher, Subscription
    from .services import ProvidedServices
    from .subscribe import Subscriber

log = logging.getLogger(__name__)
#: characters of a server's ``status`` text that are logged and shown (a server sent 10 MB lines)
STATUS_TEXT = 500
#: calls that timed out unanswered and are remembered, to name them in the next timeout's text
UNANSWERED_KEPT = 32

_dumps = orjson.dumps
_NUMPY = orjson.OPT_SERIALIZE_NUMPY
LOG_LEVELS = ("info", "warning", "error", "none")
__all__ = ["DOWN", "KEPT", "LOG_LEVELS", "Call", "Dropped", "Kept", "Outgoing", "Session"]

class Host(Protocol):
    url: str
    stats: BridgeStats

    @property
    def ros_version(self) -> int | None: ...


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

    services: ProvidedServices
    goals: Goals
    provided_actions: ProvidedActions
    subscriber: Subscriber

    def __init__(self, host: Host, bad: BadFrames, *, clock: Callable[[], float] = time.monotonic,
                 schedule: Callable[[float, Callable[[], Any]], Any] | None = None) -> None:
        """``clock``: monotonic seconds (the deadlines of commands, the held watch); ``schedule(delay, fn)``:
        a later check of the held watch (the shell's timer; None: checked at the next event only)."""
        self.host = host
        self.bad = bad
        self.stats = host.stats
        self.clock = clock
        #: whether a connection is attached (frames are written only then)
        self.up = False
        #: frames to write, oldest first: the shell drains it (:meth:`take`)
        self.outbox: deque[Outgoing] = deque()
        #: ``wake()``: called after a frame was added to the outbox (the shell drains it at once)
        self.wake: Callable[[], None] | None = None
        #: the link's ``write(data)`` and ``send_by(data, pub, deadline, now) -> bool`` (False: refused at its
        #: freshness limit), lent by the shell while a connection is attached, so a publish is one call to
        #: the link (as the Foxglove session's ``write``/``command``); None: publishes go to the outbox
        self.write: Callable[[bytes], Any] | None = None
        self.send_by: Callable[[bytes, Any, float, float], bool] | None = None
        self.nodes: dict[str, Node] = {}
        self.topics: dict[str, TopicEntry] = {}
        self.adverts: dict[str, AdvertEntry] = {}
        #: service calls waiting for their answer, oldest first: id -> :class:`Call`
        self.pending: dict[str, Call] = {}
        #: calls that timed out and were never answered on this link: id -> service (bounded)
        self.unanswered: dict[str, str] = {}
        #: calls written and not answered yet: commands may be held behind them (``held.py``)
        self.held = HeldWatch(clock=clock, may_hold=lambda: host.ros_version != 1, schedule=schedule)
        self.level: str | None = None
        #: the robot's safety envelope (``envelope.py``): every publish is held to it (``client.envelope``)
        self.envelope: Envelope | None = None
        self._seq = 0
        #: what the nodes send, told to listeners (the flight recorder): ``tap.py``
        self.tap = OperatorTap()
        #: whether this link is view-only, and what it offered the robot (``guard.py``)
        self.guard = LinkGuard(host.url)
        self.guard.add_listener(self._guard_changed)
        self._status_listeners: list[Callable[[dict[str, Any]], None]] = []
        #: the rate at which the server's ``status`` messages are logged (see ``_on_status``)
        self.status_log = LogBudget()
        self._ops: dict[str, Callable[[dict[str, Any]], None]] = {
            "publish": self._on_publish, "service_response": self._on_service_response, "status": self._on_status,
        }

    def use_parts(self, services: ProvidedServices, goals: Goals, provided_actions: ProvidedActions,
                  subscriber: Subscriber) -> None:
        """The parts that run user code or wait on the server (built by the shell; see the module docstring)."""
        self.services, self.goals, self.provided_actions, self.subscriber = services, goals, provided_actions, subscriber
        self._ops.update({
            "call_service": services.on_call, "action_feedback": goals.on_feedback, "action_result": goals.on_result,
            "send_action_goal": provided_actions.on_goal, "cancel_action_goal": provided_actions.on_cancel,
        })

    def next_id(self, kind: str, name: str) -> str:
        self._seq += 1
        return f"{kind}:{name}:{self._seq}"

    # ================================================================== frames out

    def send(self, op: dict[str, Any]) -> bool:
        """Put one frame in the outbox; False when no connection is attached or the guard refuses it."""
        if not self.up or not self.guard.admit(op):
            return False
        self._put(Outgoing(encode(op)))
        return True

    def _put(self, out: Outgoing) -> None:
        self.outbox.append(out)
        wake = self.wake
        if wake is not None:
            wake()

    def take(self, now: float | None = None) -> list[Outgoing]:
        """Every frame of the outbox, oldest first, and empty it; a command past its deadline at ``now`` is
        dropped and counted instead (``stats.stale_dropped``)."""
        out = self.outbox
        if not out:
            return []
        items = list(out)
        out.clear()
        if now is None:
            now = self.clock()
        fresh = []
        for item in items:
            if item.deadline is not None and now > item.deadline:
                self.drop_stale(item.pub, counted_sent=True)
                continue
            fresh.append(item)
        return fresh

    # ================================================================== the link comes and goes

    def attached(self) -> None:
        """A fresh connection (after the client sent ``auth``): restore everything rosbridge forgot, in order."""
        self.up = True
        if self.level is not None:
            self.send({"op": "set_level", "level": self.level})
        for advert in self.adverts.values():
            advert.active = False
            advert.active = self.send(advert.advertise_op())  # not on a view-only link (guard.py)
            if advert.pending is not None and advert.active:
                self._put(Outgoing(b"".join((advert.head, _dumps(advert.pending, option=_NUMPY), advert.tail))))
            advert.pending = None
        self.services.restore()
        self.provided_actions.restore()
        for topic in self.topics.values():
            topic.sid = None
            topic.sent_options = None
            self.subscriber.sync(topic)

    def detached(self) -> None:
        """The link is gone: frames not written are dropped, calls and goals fail, served goals end."""
        self.up = False
        if self.outbox:
            self.stats.dropped_on_disconnect += len(self.outbox)
            self.outbox.clear()
        for advert in self.adverts.values():
            advert.active = False
        for topic in self.topics.values():
            topic.sid = None
            topic.sent_options = None
        calls = list(self.pending.values())
        self.pending.clear()
        for call in calls:
            call.settle(None, ConnectionLostError("connection lost before the answer arrived"))
        self.unanswered.clear()
        self.held.reset()
        self.goals.disconnected()
        self.provided_actions.disconnected()

    def _guard_changed(self, view_only: bool) -> None:
        """The link was marked view-only (withdraw what it offered the robot) or the mark was lifted
        (offer it again); on the loop thread."""
        if not self.up:
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
        if isinstance(cid, str):
            self.held.answered(cid)  # the server is free again, whoever still waits for the answer
        call = self.pending.pop(cid, None) if isinstance(cid, str) else None
        if call is None:
            late = self.unanswered.pop(cid, None) if isinstance(cid, str) else None
            log.debug("service_response for unknown or finished call %r%s", cid,
                      f" (a late answer from {late})" if late else "")
            return
        values = m.get("values")
        service = m.get("service") if isinstance(m.get("service"), str) else None
        if nested_deeper(values):  # bounded for everything that walks an answer (see safety.py)
            self.bad.report("depth", f"answer of {bounded_repr(service, 80)} nested deeper than "
                                     f"{MAX_ANSWER_DEPTH} levels; the call failed")
            call.settle(None, ServiceError(f"the answer is nested deeper than {MAX_ANSWER_DEPTH} levels; refused",
                                           service))
        elif m.get("result", True) is False:
            call.settle(None, ServiceError(_failure_text(values), service))
        else:
            call.settle({} if values is None else values, None)

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
            call = self.pending.pop(sid, None)
            if call is not None:
                call.settle(None, ServiceError(text))
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
        if self.up and (not entry.active or changed):
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

    def command(self, pub: Publisher, msg: dict[str, Any], now: float) -> Outgoing | Dropped | Kept:
        """Decide one publish at ``now`` (see "publishing while the link is down"): the frame to write (with
        ``now + max_age`` as its deadline), :data:`KEPT` or :data:`DOWN` (counted).  Raises ``ViewOnlyError``
        on a view-only link; a motion command is first held to the safety envelope (``envelope.py``;
        raises ``EnvelopeRefused``).  :meth:`publish` decides the same way, inlined (the hot path)."""
        if self.guard.reason is not None:
            raise self.guard.refuse(f"publishing on {pub.topic}")
        entry = self.adverts[pub.topic]
        msg = enforce(self.envelope, entry.type, msg, self.stats)
        if not (self.up and entry.active):
            return self._not_written(entry, pub, msg)
        max_age = pub.max_age
        return Outgoing(b"".join((entry.head, _dumps(msg, option=_NUMPY), entry.tail)),
                        None if max_age is None else now + max_age, pub)

    def publish(self, pub: Publisher, msg: dict[str, Any]) -> bool:
        """The nodes' publish: decided as :meth:`command` decides, the frame handed to the link's ``write``
        (or ``send_by`` with its deadline) the shell lent, else put in the outbox; True when it was written
        or kept, False when it was dropped (counted)."""
        if self.guard.reason is not None:
            raise self.guard.refuse(f"publishing on {pub.topic}")
        entry = self.adverts[pub.topic]
        msg = enforce(self.envelope, entry.type, msg, self.stats)
        if not (self.up and entry.active):
            return self._not_written(entry, pub, msg) is KEPT
        data = b"".join((entry.head, _dumps(msg, option=_NUMPY), entry.tail))
        max_age = pub.max_age
        if max_age is None:
            write = self.write
            if write is None:
                self._put(Outgoing(data, None, pub))
            else:
                write(data)
        else:
            send_by = self.send_by
            now = self.clock()
            if send_by is None:
                self._put(Outgoing(data, now + max_age, pub))
            elif not send_by(data, pub, now + max_age, now):  # the link is degraded or stalling (freshness.py)
                self.drop_stale(pub)
                return False
        pub.sent += 1
        return True

    def _not_written(self, entry: AdvertEntry, pub: Publisher, msg: dict[str, Any]) -> Dropped | Kept:
        """A publish while the link is down (or the advertisement not accepted): a latched value is kept,
        latest wins, and sent after the advertisement is restored; anything else is dropped, counted."""
        if entry.latch:
            entry.pending = msg
            return KEPT
        pub.dropped += 1
        entry.dropped += 1
        self.stats.dropped_while_down += 1
        return DOWN

    def drop_stale(self, pub: Publisher, counted_sent: bool = False) -> None:
        """Count a command dropped at its freshness limit (``counted_sent``: it was already counted sent)."""
        if counted_sent:
            pub.sent -= 1
        pub.dropped += 1
        self.stats.stale_dropped += 1

    def stale_in_queue(self, pub: Publisher) -> None:
        """A queued command passed its deadline (the link's writer drops it)."""
        self.drop_stale(pub, counted_sent=True)

    # ================================================================== service calls, as data

    def open_call(self, name: str, args: dict[str, Any] | list | None = None, timeout: float | None = None,
                  done: Done | None = None) -> Call:
        """A new call (checked, not yet sent): ``ValueError``/``TypeError`` for a bad name or args,
        ``ViewOnlyError`` on a view-only link unless it only reads (``guard.check_call``)."""
        if not isinstance(name, str) or not name:
            raise ValueError(f"service name must be a non-empty string, got {name!r}")
        if args is not None and not isinstance(args, dict | list):
            raise TypeError(f"args must be a dict or list, got {type(args).__name__}")
        self.guard.check_call(name, args)
        cid = self.next_id("call", name)
        op: dict[str, Any] = {"op": "call_service", "id": cid, "service": name}
        if args is not None:
            op["args"] = args
        if timeout is not None:
            op["timeout"] = timeout
        return Call(cid, name, op, done)

    def start_call(self, call: Call) -> bool:
        """Wait for ``call``'s answer and send it (once a connection is attached: the shell waits for one);
        True when it was written.  Raises ``ViewOnlyError`` when the link was marked view-only meanwhile."""
        self.pending[call.id] = call
        if self.send(call.op):
            self.held.started(call.id, call.name)  # until its answer arrives, however late
            return True
        if self.guard.view_only:
            del self.pending[call.id]
            raise ViewOnlyError(self.guard.sentence(describe_call(call.name, call.op.get("args"))))
        return False

    def timed_out(self, call: Call, budget: float) -> ServiceTimeoutError:
        """``call`` got no answer within ``budget`` s: forget it (a late answer is dropped quietly) and say
        so, naming an earlier call still unanswered on this connection."""
        ids = list(self.pending)
        before = ids[: ids.index(call.id)] if call.id in self.pending else []
        earlier = list(self.unanswered.values()) + [self.pending[c].name for c in before]
        self.forget_call(call)
        text = f"no answer to call_service within {budget:g} s"
        if earlier:
            text += (f"; an earlier call on this connection ({earlier[0]}) is still unanswered, and rosbridge "
                     "2.1.0 runs calls one at a time")
        if self.up:
            self.unanswered[call.id] = call.name
            while len(self.unanswered) > UNANSWERED_KEPT:
                self.unanswered.pop(next(iter(self.unanswered)))
        return ServiceTimeoutError(text, call.name)

    def forget_call(self, call: Call) -> None:
        """The caller stopped waiting (answered, timed out or cancelled)."""
        if self.pending.get(call.id) is call:
            del self.pending[call.id]
        call.done = None
