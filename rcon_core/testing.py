"""pytest fixtures for the embedded simulated robot (loaded by the root conftest; usable by plugins).

- ``sim``: an async fixture giving a started :class:`~rcon_core.sim.SimServer` on a free loopback port,
  stopped cleanly afterwards.
- ``sim_thread``: a SimServer running on its own loop in a daemon thread, for sync code (roslibpy, Qt).
- ``sim_url``: the ``ws://`` URL of a threaded sim (usable from sync and async tests alike).
- ``sim_fleet``: several robots (one workspace, several links): ``sims = await sim_fleet(3)`` gives
  started SimServers on the test's loop, each on its own free loopback port; ``sim_fleet_threads(3)``
  the same running in threads, for sync code (Qt).

Both run the sim with ``rate_scale=2.0`` so streams arrive quickly in tests, and with the message and
service types every installed widget plugin contributes (``rcon_register_types``), so a lab's widget
is tested on its own type with no extra step.

A package loads these fixtures with ``pytest_plugins = ["rcon_core.testing"]`` in its ``conftest.py``.
:func:`until` waits for a condition without sleeping a fixed time.

View tests: :class:`RecordingPort` (a port that reaches no robot and records publishes), :func:`widget_state`
(a state as a running model gives it), :func:`build_view` and :func:`grab_view` (``View(model)`` refreshed
with a state, rendered to a ``QImage`` and optionally a PNG). Only these import Qt, when called.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import AsyncIterator, Callable, Iterator
from typing import Any

import pytest
import pytest_asyncio

from rcon_core.sim import SimServer

TEST_RATE_SCALE = 2.0


async def until(predicate: Callable[[], Any], timeout: float = 10.0, what: str = "condition") -> None:
    """Wait (polling every 10 ms) until ``predicate()`` is true; fail the test after ``timeout`` s."""
    deadline = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout} s waiting for {what}")
        await asyncio.sleep(0.01)


@pytest_asyncio.fixture
async def sim() -> AsyncIterator[SimServer]:
    """A started SimServer on a free loopback port (the test's event loop)."""
    server = SimServer(host="127.0.0.1", port=0, rate_scale=TEST_RATE_SCALE, plugin_types=True)
    await server.start()
    try:
        yield server
    finally:
        await server.stop()


@pytest_asyncio.fixture
async def sim_fleet() -> AsyncIterator[Callable[[int], Any]]:
    """``await sim_fleet(n)``: n started SimServers on free loopback ports (the test's loop), stopped after
    the test (one already stopped by the test, to drop its link, is fine)."""
    started: list[SimServer] = []

    async def make(n: int) -> list[SimServer]:
        out = []
        for _ in range(n):
            server = SimServer(host="127.0.0.1", port=0, rate_scale=TEST_RATE_SCALE, plugin_types=True)
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


# ------------------------------------------------------------------------------------- view harness
class _Handle:
    def __init__(self, on_publish: Callable[[dict[str, Any]], None] | None = None) -> None:
        self._on_publish = on_publish

    def publish(self, msg: dict[str, Any]) -> bool:
        if self._on_publish is not None:
            self._on_publish(msg)
        return True

    def unsubscribe(self) -> None:
        pass

    def unadvertise(self) -> None:
        pass


class RecordingPort:
    """A bridge port that reaches no robot: subscriptions stay silent, publishes and calls are recorded
    (``published``: (topic, msg); ``calls``: (service, args)), so a model can be built for a view test."""

    def __init__(self) -> None:
        self.published: list[tuple[str, dict[str, Any]]] = []
        self.calls: list[tuple[str, Any]] = []

    def subscribe(self, topic: str, callback: Callable[[dict[str, Any]], Any], **options: Any) -> _Handle:
        return _Handle()

    def advertise(self, topic: str, type: str, **options: Any) -> _Handle:
        return _Handle(lambda msg: self.published.append((topic, msg)))

    def advertise_service(self, name: str, type: str, handler: Callable[[dict[str, Any]], Any]) -> _Handle:
        return _Handle()

    async def call_service(self, name: str, args: Any = None, timeout: float | None = None) -> dict[str, Any]:
        self.calls.append((name, args))
        return {}

    def close(self) -> None:
        pass


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
    refresh = getattr(view, "refresh", None)
    if refresh is not None:
        refresh(state if state is not None else model.state)
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
