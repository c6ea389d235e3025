"""pytest fixtures for the embedded simulated robot (loaded by the root conftest; usable by plugins).

- ``sim``: an async fixture giving a started :class:`~rcon_core.sim.SimServer` on a free loopback port,
  stopped cleanly afterwards.
- ``sim_thread``: a SimServer running on its own loop in a daemon thread, for sync code (roslibpy, Qt).
- ``sim_url``: the ``ws://`` URL of a threaded sim (usable from sync and async tests alike).

Both run the sim with ``rate_scale=2.0`` so streams arrive quickly in tests.
"""

from __future__ import annotations

from collections.abc import AsyncIterator, Iterator

import pytest
import pytest_asyncio

from rcon_core.sim import SimServer

TEST_RATE_SCALE = 2.0


@pytest_asyncio.fixture
async def sim() -> AsyncIterator[SimServer]:
    """A started SimServer on a free loopback port (the test's event loop)."""
    server = SimServer(host="127.0.0.1", port=0, rate_scale=TEST_RATE_SCALE)
    await server.start()
    try:
        yield server
    finally:
        await server.stop()


@pytest.fixture
def sim_thread() -> Iterator[SimServer]:
    """A SimServer on a free loopback port, running in a background thread."""
    with SimServer.in_thread(host="127.0.0.1", port=0, rate_scale=TEST_RATE_SCALE) as server:
        yield server


@pytest.fixture
def sim_url(sim_thread: SimServer) -> str:
    """The WebSocket URL of ``sim_thread``."""
    return sim_thread.url
