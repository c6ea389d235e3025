"""pytest fixtures for the embedded simulated robot (loaded by the root conftest; usable by plugins).

- ``sim``: an async fixture giving a started :class:`~rcon_core.sim.SimServer` on a free loopback port,
  stopped cleanly afterwards; ``sim_ros2``: the same in ROS 2 flavour.
- ``client``: a ``BridgeClient`` connected to ``sim`` (no reconnect); :func:`connected` for other options.
- ``plugins``: the installed widget plugins (entry points), one manager per test module.
- ``threaded_client``: a client on its own loop thread, connected to ``sim_thread`` (for Qt tests).
- ``sim_thread``: a SimServer running on its own loop in a daemon thread, for sync code (roslibpy, Qt).
- ``sim_url``: the ``ws://`` URL of a threaded sim (usable from sync and async tests alike).
- ``transport``: runs a test once per WebSocket transport the client has (``picows``, ``websockets``): every
  ``BridgeClient`` the test makes uses it (``RCON_TRANSPORT``); a module opts in with
  ``pytestmark = pytest.mark.usefixtures("transport")``.
- ``sim_fleet``: several robots (one workspace, several links): ``sims = await sim_fleet(3)`` gives
  started SimServers on the test's loop, each on its own free loopback port; ``sim_fleet_threads(3)``
  the same running in threads, for sync code (Qt).

Both run the sim with ``rate_scale=2.0`` so streams arrive quickly in tests, and with the message and
service types every installed widget plugin contributes (``rcon_register_types``), so a lab's widget
is tested on its own type with no extra step.

A package loads these fixtures with ``pytest_plugins = ["rcon_core.testing"]`` in its ``conftest.py``.
:func:`until` (async) and :func:`until_sync` (threads, Qt) wait for a condition without sleeping a fixed
time, the one pair every test uses; :func:`flushed` (and :func:`flushed_sync`) is the barrier before asserting
that a client sent nothing (a marker sent after it through the same client reaches the sim); :class:`ManualClock` is a clock (and a
timer loop) that moves only when the test advances it, so rates are tested without the wall clock.

View tests: :class:`RecordingPort` (a port that reaches no robot: it records publishes and calls, answers
calls as scripted and delivers the messages a test plays), :func:`widget_state`
(a state as a running model gives it), :func:`build_view` and :func:`grab_view` (``View(model)`` refreshed
with a state, rendered to a ``QImage`` and optionally a PNG). Only these import Qt, when called.
"""

from __future__ import annotations

import asyncio
import itertools
import time
from collections.abc import AsyncIterator, Callable, Iterator
from contextlib import asynccontextmanager
from typing import Any

import pytest
import pytest_asyncio

from rcon_core.bridge import BridgeClient
from rcon_core.sim import SimServer

TEST_RATE_SCALE = 2.0


async def until(predicate: Callable[[], Any], timeout: float = 10.0, what: str = "condition") -> Any:
    """Wait (polling every 10 ms on the running loop) until ``predicate()`` is truthy and return its value;
    fail the test with an ``AssertionError`` naming ``what`` after ``timeout`` s. The one copy every test
    uses (core and plugins alike): a test waits for a condition, never a fixed time."""
    deadline = time.monotonic() + timeout
    while True:
        got = predicate()
        if got:
            return got
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout} s waiting for {what}")
        await asyncio.sleep(0.01)


def until_sync(predicate: Callable[[], Any], timeout: float = 10.0, what: str = "condition",
               qtbot: Any = None) -> Any:
    """:func:`until` for sync code (threads, Qt): wait until ``predicate()`` is truthy and return its value;
    fail with an ``AssertionError`` naming ``what`` after ``timeout`` s. Between polls it sleeps 10 ms, or,
    given a Qt test's ``qtbot``, runs the Qt event loop for 20 ms so events keep flowing."""
    deadline = time.monotonic() + timeout
    while True:
        got = predicate()
        if got:
            return got
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout} s waiting for {what}")
        if qtbot is None:
            time.sleep(0.01)
        else:
            qtbot.wait(20)


def qt_flushed(qtbot: Any = None, timeout: float = 10.0) -> None:
    """A barrier for Qt: every event posted before the call (layouts, updates, queued signals, and the
    events those post in turn) has been handled. Two zero-time single-shot timers posted one after the other
    have run; the test then asserts, say, that a widget did *not* move, without a fixed wait. (Without a
    ``qtbot``, Qt's own ``QTest.qWait`` runs the event loop meanwhile.)"""
    from qtpy import QtCore

    if qtbot is None:
        from qtpy.QtTest import QTest

        qtbot = type("_QtWait", (), {"wait": staticmethod(QTest.qWait)})()

    for _ in range(2):
        ran: list[int] = []

        def mark(ran: list[int] = ran) -> None:
            ran.append(1)

        QtCore.QTimer.singleShot(0, mark)
        until_sync(ran.__len__, timeout, "Qt's pending events", qtbot=qtbot)


#: the topic :func:`flushed` sends its markers on
FLUSH_TOPIC = "/rcon_test/flushed"
_flush_ids = itertools.count(1)


async def flushed(client: Any, sim: SimServer, timeout: float = 10.0) -> None:
    """A barrier for "nothing was sent": publish a marker through ``client`` (again every poll until one
    arrives) and wait until ``sim`` has it. Everything ``client`` wrote before it has reached the sim by then
    (one connection, frames in order), so a test asserts what did *not* arrive without sleeping first::

        model.press()                     # refused: nothing may go out
        await flushed(client, sim)
        assert sim.published("/speed_limit") == []

    Run it on the client's loop (:func:`flushed_sync` for a client on a ``BridgeThread``)."""
    token = f"flush-{next(_flush_ids)}"
    node = client.node("rcon_test_flush")
    pub = node.advertise(FLUSH_TOPIC, "std_msgs/String")

    def arrived() -> bool:
        if any(m.get("data") == token for m in sim.published(FLUSH_TOPIC)):
            return True
        pub.publish({"data": token})
        return False

    try:
        await until(arrived, timeout, f"a marker sent through the client reaching the sim ({token})")
    finally:
        node.close()


def flushed_sync(thread: Any, client: Any, sim: SimServer, timeout: float = 10.0, qtbot: Any = None) -> None:
    """:func:`flushed` for a client on a ``BridgeThread`` (``thread``), waited on from sync code (a Qt test
    passes its ``qtbot`` so events keep flowing)."""
    done = thread.run(flushed(client, sim, timeout))
    until_sync(done.done, timeout + 5.0, "the marker barrier", qtbot=qtbot)
    done.result()


class ManualClock:
    """A clock that moves only when the test says so, for deterministic rate tests.

    Call it for the time (``clock()``: as ``time.monotonic``, for a model's or limiter's ``clock=``); it also
    has the part of an asyncio loop a periodic timer uses (``time()``, ``call_at``, ``call_later``, each
    returning a handle with ``cancel()``), so a ``LoopTicker`` or a ``RateLimiter``'s ``schedule`` can run on
    it. :meth:`advance` moves the time forward and runs every call that falls due, in time order, each seeing
    its own due time as now.
    """

    def __init__(self, now: float = 100.0) -> None:
        self.now = now
        self._calls: list[_ManualCall] = []

    def __call__(self) -> float:
        return self.now

    def time(self) -> float:
        return self.now

    def call_at(self, when: float, fn: Callable[..., Any], *args: Any) -> _ManualCall:
        call = _ManualCall(when, fn, args)
        self._calls.append(call)
        return call

    def call_later(self, delay: float, fn: Callable[..., Any], *args: Any) -> _ManualCall:
        return self.call_at(self.now + max(0.0, delay), fn, *args)

    @property
    def pending(self) -> int:
        """How many scheduled calls are still waiting."""
        return sum(1 for c in self._calls if not c.cancelled)

    def advance(self, seconds: float) -> None:
        """Move the time ``seconds`` forward, running the calls due on the way (and those they schedule)."""
        end = self.now + seconds
        while True:
            self._calls = [c for c in self._calls if not c.cancelled]
            due = [c for c in self._calls if c.when <= end]
            if not due:
                break
            call = min(due, key=lambda c: c.when)
            self._calls.remove(call)
            self.now = max(self.now, call.when)
            call.fn(*call.args)
        self.now = end


class _ManualCall:
    def __init__(self, when: float, fn: Callable[..., Any], args: tuple[Any, ...]) -> None:
        self.when, self.fn, self.args = when, fn, args
        self.cancelled = False

    def cancel(self) -> None:
        self.cancelled = True

def _have_picows() -> bool:
    from rcon_core.bridge.transport import available

    return "picows" in available()


@pytest.fixture(params=[pytest.param("picows", marks=pytest.mark.skipif(not _have_picows(),
                                                                        reason="picows is not installed")),
                        "websockets"])
def transport(request: Any, monkeypatch: Any) -> str:
    """The transport every ``BridgeClient`` of this test uses (``RCON_TRANSPORT``), once per transport."""
    monkeypatch.setenv("RCON_TRANSPORT", request.param)
    return str(request.param)


@pytest_asyncio.fixture
async def sim() -> AsyncIterator[SimServer]:
    """A started SimServer on a free loopback port (the test's event loop)."""
    server = SimServer(host="127.0.0.1", port=0, rate_scale=TEST_RATE_SCALE, plugin_types=True)
    await server.start()
    try:
        yield server
    finally:
        await server.stop()


@pytest.fixture(scope="module")
def plugins() -> Any:
    """A ``PluginManager`` holding every widget plugin installed through the entry points, as the app loads
    them (a module that needs other plugins defines its own ``plugins``)."""
    from rcon_core.plugins import PluginManager

    pm = PluginManager(environ={})
    pm.load_entry_points()
    return pm


def widget_catalog(*plugins: Any, names: list[str] | None = None) -> Any:
    """A widget catalog (a ``PluginManager``) holding only ``plugins`` (plugin modules or objects with
    ``rcon_*`` hooks), no entry point: a unit test sees exactly what it registered, as npe2's test manager
    does. Give it to a model as ``context=WidgetContext(widget_catalog(my_plugin))``::

        from rcon_widgets_std import plugin as std
        catalog = widget_catalog(std)                  # only the standard kinds
    """
    from rcon_core.plugins import PluginManager

    pm = PluginManager(environ={})
    for i, plugin in enumerate(plugins):
        pm.register(plugin, name=names[i] if names else None)
    return pm


@asynccontextmanager
async def connected(url: str, *, timeout: float = 10.0, **options: Any) -> AsyncIterator[BridgeClient]:
    """``async with connected(sim.url, call_timeout=5) as client:`` a :class:`BridgeClient` on ``url``
    (``options`` as it takes them), connected within ``timeout`` s, and closed afterwards."""
    client = BridgeClient(url, **options)
    await client.connect(timeout=timeout)
    try:
        yield client
    finally:
        await client.close()


@pytest_asyncio.fixture
async def client(sim: SimServer) -> AsyncIterator[BridgeClient]:
    """A :class:`BridgeClient` connected to ``sim``, without reconnecting (a module that needs other options
    defines its own ``client``, usually with :func:`connected`)."""
    async with connected(sim.url, reconnect=False) as c:
        yield c


@pytest_asyncio.fixture
async def sim_ros2() -> AsyncIterator[SimServer]:
    """A started SimServer in ROS 2 flavour (rosbridge 2.x: actions, parameters, CDR) on a free loopback
    port, its streams four times the real rates."""
    server = SimServer(host="127.0.0.1", port=0, ros2=True, rate_scale=4.0)
    await server.start()
    try:
        yield server
    finally:
        await server.stop()


@pytest_asyncio.fixture
async def sim_fleet() -> AsyncIterator[Callable[[int], Any]]:
    """``await sim_fleet(n, **options)``: n started SimServers on free loopback ports (the test's loop;
    ``options`` as SimServer takes them, e.g. ``auth_secret``), stopped after the test (one already stopped
    by the test, to drop its link, is fine)."""
    started: list[SimServer] = []

    async def make(n: int, **options: Any) -> list[SimServer]:
        out = []
        for _ in range(n):
            server = SimServer(host="127.0.0.1", port=0, rate_scale=TEST_RATE_SCALE, plugin_types=True, **options)
            await server.start()
            started.append(server)
            out.append(server)
        return out

    try:
        yield make
    finally:
        for server in started:
            await server.stop()


@pytest.fixture
def sim_fleet_threads() -> Iterator[Callable[[int], list[SimServer]]]:
    """``sim_fleet_threads(n)``: n SimServers, each running in its own thread on its own free port."""
    import contextlib

    with contextlib.ExitStack() as stack:
        def make(n: int) -> list[SimServer]:
            return [stack.enter_context(SimServer.in_thread(host="127.0.0.1", port=0, rate_scale=TEST_RATE_SCALE,
                                                            plugin_types=True)) for _ in range(n)]

        yield make


@pytest.fixture
def sim_thread() -> Iterator[SimServer]:
    """A SimServer on a free loopback port, running in a background thread."""
    with SimServer.in_thread(host="127.0.0.1", port=0, rate_scale=TEST_RATE_SCALE,
                             plugin_types=True) as server:
        yield server


@pytest.fixture
def sim_url(sim_thread: SimServer) -> str:
    """The WebSocket URL of ``sim_thread``."""
    return sim_thread.url


@pytest.fixture
def threaded_client(sim_thread: SimServer) -> Iterator[tuple[Any, BridgeClient]]:
    """``(bridge_thread, client)``: a ``BridgeThread`` running a client connected to ``sim_thread``, as the
    app runs its link (models get ``dispatch=bridge_thread.call``); closed and stopped afterwards."""
    from rcon_core.bridge.threaded import BridgeThread

    bt = BridgeThread().start()
    c = BridgeClient(sim_thread.url, reconnect=False)
    try:
        bt.run(c.connect()).result(10)
        yield bt, c
        bt.run(c.close()).result(10)
    finally:
        bt.stop()


# ------------------------------------------------------------------------------------- view harness
class _Handle:
    def __init__(self, on_publish: Callable[[dict[str, Any]], None] | None = None,
                 on_end: Callable[[], None] | None = None) -> None:
        self._on_publish = on_publish
        self._on_end = on_end

    def publish(self, msg: dict[str, Any]) -> bool:
        if self._on_publish is not None:
            self._on_publish(msg)
        return True

    def unsubscribe(self) -> None:
        if self._on_end is not None:
            self._on_end()
            self._on_end = None

    def unadvertise(self) -> None:
        pass


class RecordingPort:
    """A bridge port that reaches no robot: publishes and calls are recorded (``published``: (topic, msg);
    ``calls``: (service, args)), so a model can be built for a view test. Subscriptions hear what the test
    plays with :meth:`deliver` (as the bridge would deliver it: an exception in ``on_message`` becomes the
    widget's error). Service calls answer what the test scripts with :meth:`answer` (else ``{}``)::

        port = RecordingPort()
        port.answer("/pump/set", {"success": True, "message": "on"}, {"success": False, "message": "dry"})
        port.answer("/pump/set", lambda args: {"success": args["on"], "message": ""})   # computed
        port.answer("/dock", TimeoutError("no answer"))                                # raised by the call
    """

    #: a complete port (``rcon_core.plugins.api.Port``): a test may set these to play the app's port
    view_only: str | None = None
    envelope: Any = None
    widget_id: str | None = None
    composes = False

    def __init__(self) -> None:
        self.published: list[tuple[str, dict[str, Any]]] = []
        self.calls: list[tuple[str, Any]] = []
        #: action goals the model tried to send: (action, type, goal)
        self.goals: list[tuple[str, str, Any]] = []
        #: how often the model said it has something new to show (``changed()``)
        self.changes = 0
        self.link: Any = id(self)
        self._answers: dict[str, list[Any]] = {}
        self._subscribers: dict[str, list[Callable[[dict[str, Any]], Any]]] = {}

    def deliver(self, topic: str, msg: dict[str, Any]) -> int:
        """Hand ``msg`` to every subscription on ``topic`` now, on this thread; returns how many heard it."""
        callbacks = list(self._subscribers.get(topic, ()))
        for callback in callbacks:
            callback(msg)
        return len(callbacks)

    def answer(self, service: str, *answers: Any) -> None:
        """Script the answers of ``service``, played one per call in order; the last one repeats. An answer
        is a response dict, a function of the request that returns one, or an exception to raise."""
        if not answers:
            raise ValueError("answer() needs at least one answer")
        self._answers[service] = list(answers)

    def subscribe(self, topic: str, callback: Callable[[dict[str, Any]], Any], **options: Any) -> _Handle:
        self._subscribers.setdefault(topic, []).append(callback)
        return _Handle(on_end=lambda: self._subscribers[topic].remove(callback))

    def advertise(self, topic: str, type: str, **options: Any) -> _Handle:
        return _Handle(lambda msg: self.published.append((topic, msg)))

    def advertise_service(self, name: str, type: str, handler: Callable[[dict[str, Any]], Any]) -> _Handle:
        return _Handle()

    async def call_service(self, name: str, args: Any = None, timeout: float | None = None) -> dict[str, Any]:
        self.calls.append((name, args))
        queue = self._answers.get(name)
        if not queue:
            return {}
        answer = queue.pop(0) if len(queue) > 1 else queue[0]
        if isinstance(answer, BaseException):
            raise answer
        if callable(answer):
            answer = answer(args)
        return dict(answer)

    def send_action_goal(self, action: str, action_type: str, args: Any = None, feedback: Any = None,
                         **options: Any) -> Any:
        """Recorded in :attr:`goals`; no robot answers, so it raises after recording."""
        self.goals.append((action, action_type, args))
        raise RuntimeError("a RecordingPort sends no action goals (it reaches no robot)")

    def changed(self) -> None:
        self.changes += 1

    def close(self) -> None:
        pass


def check_conformance(spec: Any, *, catalog: Any = None, types: Any = None, view: bool = True) -> None:
    """Check one widget kind against the widget API (``rcon_core.plugins.api``), as
    ``tests/test_plugin_conformance.py`` checks every installed kind: raises ``AssertionError`` saying what
    does not conform. For each role: the model is a ``WidgetModel`` built as the runtime builds it, unbound
    (it must say what it lacks, start, stop and take focus loss and link state without a robot); the
    settings round-trip through a layout's dict; the view (``view=True``, needs a QApplication) builds
    offscreen as ``View(model)`` and takes ``refresh(state)``. A lab's package runs it in its own tests::

        from rcon_core.testing import check_conformance
        def test_conforms(qapp):
            check_conformance(plugin.SPEC)
    """
    from rcon_core.msgs import TypeRegistry
    from rcon_core.plugins import Binding, WidgetContext, WidgetModel
    from rcon_core.plugins.api import Port, WidgetView, check_api_version

    check_api_version(spec.api_version, spec.kind, spec.package)
    model_cls = spec.load_model()
    assert isinstance(model_cls, type) and issubclass(model_cls, WidgetModel), (
        f"{spec.kind}: the model {model_cls!r} is not a WidgetModel")
    settings = spec.make_settings({})
    stored = spec.settings_to_dict(settings)
    assert spec.settings_to_dict(spec.make_settings(stored)) == stored, f"{spec.kind}: settings do not round-trip"
    types = types if types is not None else TypeRegistry.standard()
    for role in sorted(spec.roles):
        model = model_cls(spec.make_settings({}), Binding("", "", role), RecordingPort(), types=types,
                          context=WidgetContext(catalog))
        assert isinstance(model.port, Port)
        problems = model.problems()
        assert problems and all(isinstance(p, str) and p for p in problems), (
            f"{spec.kind} ({role}): an unbound widget must say what it lacks, got {problems!r}")
        model.start()
        model.on_focus_lost()
        model.set_link(False)
        assert model.state.running and model.state.link_down, f"{spec.kind} ({role}): start/set_link"
        if view:
            built = build_view(spec.load_view(), model)
            try:
                refreshes: WidgetView = built
                assert isinstance(refreshes, WidgetView), f"{spec.kind}: its view has no refresh(state)"
                refreshes.refresh(widget_state(None, seq=model.state.seq + 1))
            finally:
                built.deleteLater()  # a QWidget (build_view returns Any)
        model.stop()
        assert not model.state.running, f"{spec.kind} ({role}): stop"


def widget_state(value: Any = None, **fields: Any) -> Any:
    """A :class:`~rcon_core.plugins.WidgetState` as a running model with one value would give it."""
    from rcon_core.plugins import WidgetState

    base: dict[str, Any] = {"value": value, "count": 1 if value is not None else 0, "age": 0.0,
                            "running": True, "seq": 1}
    base.update(fields)
    return WidgetState(**base)


def build_view(view_cls: Any, model: Any, state: Any = None, *, size: tuple[int, int] = (320, 160)) -> Any:
    """``view_cls(model)`` sized ``size`` and refreshed with ``state`` (default ``model.state``), as the app
    builds it. Needs a QApplication (pytest-qt's ``qapp``; one is made if there is none)."""
    from qtpy import QtWidgets  # Qt only here: the fixtures above stay importable without it

    if QtWidgets.QApplication.instance() is None:
        QtWidgets.QApplication([])
    view = view_cls(model)
    view.resize(*size)
    from rcon_core.plugins.api import WidgetView

    if isinstance(view, WidgetView):  # a view without refresh() reads model.state when it paints
        view.refresh(state if state is not None else model.state)
    return view


def grab_view(view_cls: Any, model: Any, state: Any = None, *, size: tuple[int, int] = (320, 160),
              path: Any = None) -> Any:
    """Build the view (:func:`build_view`), render it to a ``QImage`` and, given ``path``, save it as PNG.

    ::

        model = GripperModel(GripperSettings(), Binding("/gripper", "lab_msgs/Gripper"), RecordingPort())
        image = grab_view(GripperView, model, widget_state((0.5, True)), path=tmp_path / "gripper.png")
    """
    view = build_view(view_cls, model, state, size=size)
    try:
        image = view.grab().toImage()
        if path is not None and not image.save(str(path), "PNG"):
            raise OSError(f"could not write {path}")
        return image
    finally:
        view.deleteLater()
