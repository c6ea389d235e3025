"""pytest fixtures for the embedded simulated robot (loaded by the root conftest; usable by plugins).

- ``sim``: an async fixture giving a started :class:`~rcon_core.sim.SimServer` on a free loopback port,
  stopped cleanly afterwards.
- ``sim_thread``: a SimServer running on its own loop in a daemon thread, for sync code (roslibpy, Qt).
- ``sim_url``: the ``ws://`` URL of a threaded sim (usable from sync and async tests alike).

Both run the sim with ``rate_scale=2.0`` so streams arrive quickly in tests, and with the message and
service types every installed widget plugin contributes (``rcon_register_types``), so a lab's widget
is tested on its own type with no extra step.

A package loads these fixtures with ``pytest_plugins = ["rcon_core.testing"]`` in its ``conftest.py``.
:func:`until` waits for a condition without sleeping a fixed time.
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
