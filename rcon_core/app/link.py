"""The app's link to the robot: one BridgeClient living on a BridgeThread, seen from the GUI thread.

Every network operation runs on the bridge thread.  The GUI reads what the bridge thread left behind:
the connection state (a :class:`rcon_core.bridge.ConnectionState`: the app's link has no state the
bridge client lacks, so the app compares and stores that enum, never its words) in a :class:`LatestValue` mailbox, the latency as a float attribute, the topic
and service catalogue in another mailbox, and why the last attempt failed (a
:class:`rcon_core.bridge.reasons.Failure`, None once connected) in a third.  Nothing here blocks the GUI
thread.  Connecting to another robot, or disconnecting, empties the catalogue at once: the previous
robot's topics never stay on screen as if they were the new one's; so does losing the link (the list
comes back when the robot does), and ``catalog_state`` says which of these the (empty) lists are in.

Decision: the catalogue loop diffs, batches and paces
    Every ``CATALOG_PERIOD`` (or, for a big graph, ``CATALOG_SHARE`` times what the last listing took,
    whichever is longer) the loop asks ``/rosapi/topics`` and ``/rosapi/services`` once each and asks the
    type of only the services it has not seen on this connection (``Rosapi.services_with_types(known)``,
    a few calls in flight at a time). A listing that takes long is published as it goes (names first,
    types as they come), and a catalogue equal to the last one is not published again: the GUI does
    nothing when nothing changed. 10^5 services were asked all at once every 5 s (a 22 s stall, the
    link cut by the watchdog).
"""

from __future__ import annotations

import asyncio
import ipaddress
import logging
import re
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any
from urllib.parse import urlparse

from rcon_core.app.link_detect import ProtocolFinder
from rcon_core.bridge import BridgeClient, ConnectionState
from rcon_core.bridge.envelope import Envelope
from rcon_core.bridge.secure import confirm_auth, rosauth
from rcon_core.bridge.threaded import BridgeThread, LatestValue

log = logging.getLogger(__name__)

#: how often the catalogue is fetched from rosapi while connected (s)
CATALOG_PERIOD = 5.0
#: ... and at least this many times what the last listing took, apart (a big graph is listed less often)
CATALOG_SHARE = 4.0
#: a listing that takes longer is published as it goes, this often (s)
CATALOG_PROGRESS_EVERY = 2.0


class BadUrl(ValueError):
    """A rosbridge URL the app cannot use; the message tells why."""


def check_url(url: str) -> str:
    """Return ``url`` stripped, or raise :class:`BadUrl` saying what is wrong with it."""
    url = url.strip()
    if not url:
        raise BadUrl("enter a rosbridge URL such as ws://192.168.1.10:9090")
    parsed = urlparse(url)
    if parsed.scheme not in ("ws", "wss"):
        raise BadUrl(f"{url!r}: the URL must start with ws:// or wss://")
    if not parsed.hostname:
        raise BadUrl(f"{url!r}: the URL has no host name")
    if not _host_ok(parsed.hostname):
        raise BadUrl(f"{parsed.hostname!r} is not a host name or an IP address")
    try:
        parsed.port  # noqa: B018 - raises on a bad port
    except ValueError:
        raise BadUrl(f"{url!r}: the port is not a number between 0 and 65535") from None
    return url


#: what the side panel lists: {"topics" | "services" | "actions": [(name, type)]}, and for a Foxglove
#: robot "notes": {"actions": what its protocol cannot do}
Catalog = dict[str, Any]
_LABEL = re.compile(r"^[A-Za-z0-9_]([A-Za-z0-9_-]{0,61}[A-Za-z0-9_])?$")
EMPTY_CATALOG: Catalog = {"topics": [], "services": []}


def _host_ok(host: str) -> bool:
    try:
        ipaddress.ip_address(host)
        return True
    except ValueError:
        pass
    labels = host[:-1].split(".") if host.endswith(".") else host.split(".")
    return len(host) <= 253 and all(_LABEL.match(label) for label in labels)


@dataclass(frozen=True)
class LinkSettings:
    """How to reach one robot securely: TLS files (paths) and the rosauth secret (None: no auth)."""

    ca_file: str | None = None
    client_cert: str | None = None
    client_key: str | None = None
    secret: str | None = None

    def client_options(self, url: str) -> dict[str, Any]:
        return {"ca_file": self.ca_file or None, "client_cert": self.client_cert or None,
                "client_key": self.client_key or None, "auth": rosauth(self.secret, url) if self.secret else None}


def as_state(state: ConnectionState | str) -> ConnectionState:
    """``ConnectionState.CONNECTED`` as it is; its value ``"connected"`` as the member."""
    return state if isinstance(state, ConnectionState) else ConnectionState(str(state).lower())


class RobotConnection:
    """The app's connection to one robot: owns the bridge thread and the current client; safe to drive
    from the GUI thread. (Not the bridge's :class:`rcon_core.bridge.linkbase.Link`, one WebSocket
    connection's frames out; this holds a client across reconnects and robots.)"""

    def __init__(self, bridge_thread: BridgeThread | None = None) -> None:
        self.thread = bridge_thread or BridgeThread()
        self._own_thread = bridge_thread is None
        if self._own_thread:
            self.thread.start()
        self._client: BridgeClient | None = None
        self.url: str | None = None
        self.state_box = LatestValue()
        self.catalog_box = LatestValue()
        self.error_box = LatestValue()
        self.failure_box = LatestValue()
        #: the URL of a link whose robot answered a call (so it goes into the URL history)
        self.answered_box = LatestValue()
        #: why the robot's bridge holds this link's commands now (a sentence), None when it does not
        #: (``rcon_core/bridge/held.py``: a service call unanswered on a server that runs one at a time)
        self.held_box = LatestValue()
        self._catalog_task: asyncio.Task | None = None
        self._catalog_wake: asyncio.Event | None = None
        #: what the catalogue lists are waiting for, for their empty text (written on the bridge thread):
        #: "offline" (no robot), "connecting", "listing" (connected, first listing under way), "listed",
        #: "lost" (the link dropped; reconnecting)
        self.catalog_state = "offline"
        self._generation = 0
        self._listeners: list[Callable[[BridgeClient | None], None]] = []
        #: the robot's safety envelope, given to every client this link makes (``set_envelope``)
        self.envelope: Envelope | None = None
        #: why a robot at a URL may be sent nothing (its view-only mark, worded by the window: see
        #: ``view_only.py``), asked for each new client before it connects and by :meth:`apply_guard`
        self.guard_for: Callable[[str], str | None] | None = None
        self.state_box.put(ConnectionState.CLOSED)
        #: the robot's protocol when forced (``--protocol``); None: found per URL (``link_detect.py``)
        self.protocol: str | None = None
        self.finder = ProtocolFinder(self.thread)
        self.finding = False  # connect_to is waiting for the URL's protocol

    @property
    def client(self) -> BridgeClient | None:
        """The current client (a robot link of either protocol).  While the URL's protocol is being found,
        the answer is taken here on the thread that called :meth:`connect_to` (the GUI thread), at its first
        look after the answer came (or when the finder's wake runs), so a switched client starts there."""
        if self.finding:
            self.finder.take()
        return self._client

    @client.setter
    def client(self, client: BridgeClient | None) -> None:
        self._client = client

    # ------------------------------------------------------------------------------------- GUI side
    def set_envelope(self, envelope: Envelope | None) -> None:
        """Hold every motion command of this link to ``envelope`` (the robot's; None: no limit), now and on
        every later client (``rcon_core/bridge/envelope.py``)."""
        self.envelope = envelope
        if self.client is not None:
            self.client.envelope = envelope

    def on_client_changed(self, fn: Callable[[BridgeClient | None], None]) -> None:
        """``fn(client)`` is called (on the GUI thread, from :meth:`connect_to`) when the client changes."""
        self._listeners.append(fn)

    def connect_to(self, url: str, settings: LinkSettings | None = None) -> None:
        """Close any current client and connect to ``url`` (with automatic reconnection), over the
        protocol the robot speaks (``self.protocol``, else found: ``link_detect.py``)."""
        url = check_url(url)
        self.disconnect()
        self._generation += 1
        gen = self._generation
        protocol = self.protocol or self.finder.known.get(url)
        if protocol is None:  # start as rosbridge; a robot that picks a Foxglove subprotocol is switched
            self.finding = True
            options = (settings or LinkSettings()).client_options(url)
            self.finder.find(url, options, gen, lambda: self._generation, self._adopt, settings)
        self._start(url, settings, protocol or "rosbridge", gen)

    def _adopt(self, gen: int, protocol: str, settings: LinkSettings | None) -> None:
        """The URL's protocol was found (on this thread): a robot speaking Foxglove gets a Foxglove client in
        place of the rosbridge one started meanwhile (which never connected: the server refused it)."""
        self.finding = False
        current = self._client
        if gen != self._generation or self.url is None or current is None:
            return
        if getattr(current, "protocol", "rosbridge") == protocol:
            return
        url = self.url
        self._client = None
        self._generation += 1  # the rosbridge client's late events (its CLOSED) are not this link's any more
        self.thread.run(self._close(current))
        self._start(url, settings, protocol, self._generation)

    def _start(self, url: str, settings: LinkSettings | None, protocol: str, gen: int) -> None:
        from rcon_core.link import make_client

        client = make_client(url, protocol, reconnect=True, **(settings or LinkSettings()).client_options(url))
        client.envelope = self.envelope  # before anything can publish through it (either protocol)
        self._guard(client, url)  # a view-only robot's link refuses from its first frame on
        self.client, self.url = client, url
        self.catalog_state = "connecting"
        self.state_box.put(ConnectionState.CONNECTING)
        self.thread.call(self._wire, client, gen)
        for fn in self._listeners:
            fn(client)

    def disconnect(self) -> None:
        """Close the current client, if any (returns at once; the close runs on the bridge thread)."""
        client, self.client = self.client, None
        self._generation += 1
        self.failure_box.put(None)
        self.held_box.put(None)
        self.catalog_box.put(EMPTY_CATALOG)
        self.finding = False
        self.catalog_state = "offline"
        if client is None:
            return
        for fn in self._listeners:
            fn(None)
        self.thread.run(self._close(client))
        self.state_box.put(ConnectionState.CLOSED)

    def apply_guard(self) -> None:
        """The robot's view-only mark changed: its current client refuses (or stops refusing) at once."""
        client = self.client
        if client is not None and self.url is not None:
            self._guard(client, self.url)

    def _guard(self, client: BridgeClient, url: str) -> None:
        why: str | None = None
        if self.guard_for is not None:
            try:
                why = self.guard_for(url)
            except Exception:  # noqa: BLE001 - the mark's wording failed: refuse rather than send
                log.exception("view-only mark of %s could not be read; the link sends nothing", url)
                why = f"the view-only mark of {url} could not be read"
        client.guard.set_view_only(why)

    def protocol_text(self) -> str:
        """Which protocol and server the current client speaks to, for the connection bar ("" for rosbridge,
        the default; a Foxglove link names its server, encodings and what it cannot do)."""
        client = self.client
        describe = getattr(client, "describe", None)
        if client is None or describe is None or getattr(client, "protocol", "rosbridge") != "foxglove":
            return ""
        try:
            info = describe()
        except Exception:
            return ""
        return (f"Foxglove WebSocket · {info.get('server') or 'server'} · {', '.join(info.get('encodings') or [])}"
                " · no actions, no rosauth")

    @property
    def latency(self) -> float | None:
        client = self.client
        return getattr(client, "latency", None) if client is not None else None

    def shutdown(self, timeout: float = 2.0) -> None:
        """Close the client and, if this link started it, stop the bridge thread."""
        client, self.client = self.client, None
        if client is not None:
            try:
                self.thread.run(self._close(client)).result(timeout)
            except Exception:
                log.debug("close on shutdown failed", exc_info=True)
        if self._own_thread:
            stop = getattr(self.thread, "stop", None)
            if stop is not None:
                stop()

    # ---------------------------------------------------------------------------- bridge-thread side
    def _wire(self, client: BridgeClient, gen: int) -> None:
        def on_state(state: Any) -> None:
            if gen == self._generation:
                state = as_state(state)
                self.state_box.put(state)
                if state is ConnectionState.CONNECTED:
                    self.failure_box.put(None)
                    if self.catalog_state != "listed":
                        self.catalog_state = "listing"
                    self._start_catalog(client, gen)
                elif state in (ConnectionState.RECONNECTING, ConnectionState.CLOSED):
                    # the robot's topics are no longer known to be there: the lists empty until it is back
                    self.catalog_state = "lost"
                    self.catalog_box.put(EMPTY_CATALOG)

        def on_failure(failure: Any) -> None:
            if gen == self._generation:
                self.failure_box.put(failure)

        def on_held(held: Any) -> None:
            if gen == self._generation:
                self.held_box.put(held.sentence() if held is not None else None)

        client.add_state_listener(on_state)
        client.add_failure_listener(on_failure)
        held = getattr(getattr(client, "session", None), "held", None)  # rosbridge only (bridge/held.py)
        if held is not None:
            held.add_listener(on_held)
        asyncio.ensure_future(self._connect(client, gen))

    async def _connect(self, client: BridgeClient, gen: int) -> None:
        try:
            await client.connect()
        except Exception as exc:  # with reconnect=True the client keeps trying on its own
            if gen == self._generation and client.failure is None:  # else failure_box says why, in words
                self.error_box.put(f"could not connect: {exc}")
            return
        if gen == self._generation:
            self.state_box.put(as_state(client.state))
            self._start_catalog(client, gen)
        if getattr(client, "protocol", "rosbridge") != "foxglove":  # Foxglove: no rosauth; serverInfo answered
            try:  # the robot answers a call: it accepted the link (and the auth op, if any)
                await confirm_auth(client)
            except Exception:  # refused: the client reports it as a fatal failure
                return
        if gen == self._generation:
            self.answered_box.put(client.url)

    def _start_catalog(self, client: BridgeClient, gen: int) -> None:
        if self._catalog_task is not None and not self._catalog_task.done():
            if self._catalog_wake is not None:
                self._catalog_wake.set()  # (re)connected: list now, not at the end of the pause
            return
        self._catalog_wake = asyncio.Event()
        self._catalog_task = asyncio.ensure_future(self._catalog_loop(client, gen, self._catalog_wake))

    async def _catalog_loop(self, client: BridgeClient, gen: int, wake: asyncio.Event) -> None:
        """List the robot now and then (see the module docstring); service types learned on one connection
        are kept until it drops."""
        loop = asyncio.get_running_loop()
        known: dict[str, str] = {}
        connects = -1
        last: Catalog | None = None
        while gen == self._generation:
            started = loop.time()
            wake.clear()
            if client.state is ConnectionState.CONNECTED:
                if client.stats["connects"] != connects:  # another connection: learn the types again
                    connects, last = client.stats["connects"], None
                    known.clear()
                shown = _Partial(known)
                publisher = asyncio.ensure_future(self._publish_partial(client, gen, shown))
                try:
                    catalog = await fetch_catalog(client, known, shown.listed)
                    if gen == self._generation and client.state is ConnectionState.CONNECTED:
                        self.catalog_state = "listed"
                        if catalog != last:
                            last = catalog
                            self.catalog_box.put(catalog)
                except Exception as exc:
                    log.debug("catalogue refresh failed: %s", exc)
                finally:
                    publisher.cancel()
            pause = max(CATALOG_PERIOD, CATALOG_SHARE * (loop.time() - started))
            try:
                await asyncio.wait_for(wake.wait(), pause)
            except TimeoutError:
                pass

    async def _publish_partial(self, client: BridgeClient, gen: int, shown: _Partial) -> None:
        """While a long listing goes on, publish what it has every ``CATALOG_PROGRESS_EVERY`` seconds (the
        names, with the types known so far), made a slice at a time so the loop keeps turning."""
        while True:
            await asyncio.sleep(CATALOG_PROGRESS_EVERY)
            if shown.names is None:
                continue
            services: list[tuple[str, str]] = []
            names, known = shown.names, shown.known
            for i in range(0, len(names), 10_000):
                services += [(n, known.get(n, "")) for n in names[i:i + 10_000]]
                await asyncio.sleep(0)
            if gen == self._generation and client.state is ConnectionState.CONNECTED:
                self.catalog_box.put({"topics": shown.topics, "services": services, "actions": []})

    async def _close(self, client: BridgeClient) -> None:
        if self._catalog_task is not None:
            self._catalog_task.cancel()
            self._catalog_task = None
        try:
            await client.close()
        except Exception:
            log.debug("close failed", exc_info=True)

    def refresh_catalog(self) -> None:
        """Fetch topics and services now (results arrive in ``catalog_box``)."""
        client = self.client
        if client is None:
            return

        async def once() -> None:
            try:
                catalog = await fetch_catalog(client)
            except Exception as exc:
                self.error_box.put(f"could not list topics: {exc}")
                return
            if client is self.client:
                self.catalog_box.put(catalog)

        self.thread.run(once())


async def fetch_catalog(client: BridgeClient, known: dict[str, str] | None = None,
                        listed: Callable[[list[tuple[str, str]], list[str]], None] | None = None) -> Catalog:
    """``{"topics": [(name, type)], "services": [(name, type)], "actions": [(name, type)]}`` from the link's
    catalogue (rosapi on rosbridge; actions only from a ROS 2 robot: ``/rosapi/action_servers``), and for a
    Foxglove robot ``"notes"``: what its protocol cannot do (``{"actions": sentence}``), shown in the list.
    ``known``: service types learned before (only new services are asked; updated in place as the answers
    come); ``listed(topics, service names)``: called once both lists are known, before the services' types
    are asked."""
    api = client.rosapi
    pairs = _pairs(await api.topics())
    await asyncio.sleep(0)  # a long list: timers and other links get a turn between the steps
    topics = sorted(pairs)
    await asyncio.sleep(0)
    with_types = getattr(api, "services_with_types", None)
    if with_types is None:
        services = sorted(_pairs(await api.services()))
    elif known is None:
        services = sorted(_pairs(await with_types()))
    else:
        def names_known(names: list[str]) -> None:
            if listed is not None:
                listed(topics, names)

        services = list((await with_types(known, names_known)).items())  # str to str, in name order
    await asyncio.sleep(0)
    catalog: Catalog = {"topics": topics, "services": services, "actions": sorted(await _actions(client))}
    if getattr(client, "protocol", "rosbridge") == "foxglove":  # what the protocol cannot do, where one looks
        from rcon_core.foxglove import CANNOT

        catalog["notes"] = {"actions": CANNOT["actions"][:1].upper() + CANNOT["actions"][1:] + "."}
    return catalog


class _Partial:
    """What a listing under way knows: the topics and service names once listed, the types as they come."""

    def __init__(self, known: dict[str, str]) -> None:
        self.known = known
        self.topics: list[tuple[str, str]] = []
        self.names: list[str] | None = None

    def listed(self, topics: list[tuple[str, str]], names: list[str]) -> None:
        self.topics, self.names = topics, names


async def _actions(client: BridgeClient) -> list[tuple[str, str]]:
    """The robot's ROS 2 action servers with their types; none from a ROS 1 robot or an old rosapi."""
    detect = getattr(client, "detect_ros", None)
    listing = getattr(client.rosapi, "action_servers_with_types", None)
    if detect is None or listing is None:
        return []
    try:
        if (await detect()).version != 2:
            return []
        return _pairs(await listing())
    except Exception as exc:  # a rosapi without action_servers: no actions, said in the log
        log.debug("action servers not listed: %s", exc)
        return []


def _pairs(answer: Any) -> list[tuple[str, str]]:
    """Accept the shapes a rosapi helper may return: pairs, a mapping, or the raw rosapi dict."""
    if isinstance(answer, dict):
        if "topics" in answer or "services" in answer:
            names = answer.get("topics") or answer.get("services") or []
            types = answer.get("types") or [""] * len(names)
            return list(zip(names, types, strict=False))
        pairs = list(answer.items())  # Rosapi's mappings are str to str already: no copy per item
        if all(type(k) is str and type(v) is str for k, v in pairs):
            return pairs
        return [(str(k), str(v)) for k, v in pairs]
    out = []
    for item in answer or []:
        if isinstance(item, str):
            out.append((item, ""))
        elif isinstance(item, (tuple, list)) and len(item) >= 2:
            out.append((str(item[0]), str(item[1])))
        else:
            name = getattr(item, "name", None)
            if name is not None:
                out.append((str(name), str(getattr(item, "type", ""))))
    return out


class _Dropped:
    """The handle an offline port hands out: publishing drops the message, ending does nothing."""

    def publish(self, _msg: Any) -> None:
        pass

    def unsubscribe(self) -> None:
        pass

    def unadvertise(self) -> None:
        pass


class OfflinePort:
    """A widget's port while the app is not connected: nothing reaches a robot, calls fail clearly."""

    def subscribe(self, *_a: Any, **_k: Any) -> _Dropped:
        return _Dropped()

    def advertise(self, *_a: Any, **_k: Any) -> _Dropped:
        return _Dropped()

    def advertise_service(self, *_a: Any, **_k: Any) -> _Dropped:
        return _Dropped()

    async def call_service(self, *_a: Any, **_k: Any) -> Any:
        raise RuntimeError("not connected to a robot")

    def send_action_goal(self, *_a: Any, **_k: Any) -> Any:
        raise RuntimeError("not connected to a robot")

    def close(self) -> None:
        pass


class OfflineClient:
    """Stands in for a BridgeClient while there is none: the canvas runtime still builds and runs the
    widgets (so they show, with LINK DOWN), and they talk to nobody."""

    state = ConnectionState.CLOSED

    def node(self, _node_id: str) -> OfflinePort:
        return OfflinePort()


OFFLINE = OfflineClient()
