"""The connection shell both robot links are built on (``rcon_core/link/connection.py``): the backoff schedule,
a third protocol getting reconnect, state, failure reporting, release and close from it alone, the state a
closed client says when it connects again (both protocols), and the import order the shell needs."""

from __future__ import annotations

import asyncio
import gc
import subprocess
import sys
import weakref
from typing import Any

import pytest

from rcon_core.bridge import BridgeClient
from rcon_core.bridge.errors import AuthRefusedError
from rcon_core.bridge.guard import LinkGuard
from rcon_core.bridge.nodes import Node
from rcon_core.bridge.reasons import Failure
from rcon_core.foxglove import FoxgloveClient
from rcon_core.foxglove.ws import FoxgloveReceiver
from rcon_core.link import ConnectionShell, ConnectionState
from rcon_core.link.connection import backoff
from rcon_core.loopback import StallProxy
from rcon_core.testing import until

# ------------------------------------------------------------------------------------------- the schedule


def test_backoff_doubles_from_the_least_wait_up_to_its_cap():
    highest = backoff(0.25, 10.0, uniform=lambda low, high: high)
    assert [next(highest) for _ in range(9)] == [0.25, 0.5, 1.0, 2.0, 4.0, 8.0, 10.0, 10.0, 10.0]
    lowest = backoff(0.25, 10.0, uniform=lambda low, high: low)
    assert {next(lowest) for _ in range(9)} == {0.125}


def test_backoff_draws_each_wait_within_its_bounds():
    drawn = backoff(0.05, 0.2)
    waits = [next(drawn) for _ in range(200)]
    ceilings = [0.05, 0.1, 0.2] + [0.2] * 197
    assert all(0.025 <= w <= c for w, c in zip(waits, ceilings, strict=True))
    assert max(waits[3:]) > 0.1  # the cap is reached, not the first ceiling kept


# ------------------------------------------------------------------------------------- a third protocol


class _Session:
    """What the shell reads of a protocol's state (``connection.LinkSession``)."""

    def __init__(self, url: str) -> None:
        self.guard = LinkGuard(url)
        self.envelope = None
        self.nodes: dict[str, Node] = {}
        self.stale: list[Any] = []

    def stale_in_queue(self, pub: Any) -> None:
        self.stale.append(pub)


class Quiet(ConnectionShell):
    """A protocol that sends nothing and keeps the text it is sent: all it writes is its four hooks."""

    protocol = "quiet"

    def __init__(self, url: str, refuse_after: bool = False, **options: Any) -> None:
        super().__init__(url, **options)
        self.session = _Session(url)
        self.texts: list[str] = []
        self.ups: list[Any] = []
        self.downs = 0
        self.refuse_after = refuse_after

    def _receiver(self) -> FoxgloveReceiver:
        return FoxgloveReceiver(self.texts.append, lambda raw: None, lambda exc: None)

    async def _link_up(self, link: Any) -> None:
        self.ups.append(weakref.ref(link))
        link.receiver.start()
        self._up()

    def _link_down(self, link: Any) -> None:
        self.downs += 1

    def _check_end(self, link: Any, seconds_open: float) -> None:
        if self.refuse_after:
            raise AuthRefusedError("the robot said no")


async def test_a_third_protocol_gets_reconnect_state_release_and_close_from_the_shell(sim, transport):
    async with StallProxy("127.0.0.1", sim.port) as proxy:
        link = Quiet(proxy.url, backoff_min=0.02, backoff_max=0.05)
        states: list[ConnectionState] = []
        link.add_state_listener(states.append)
        assert link.state is ConnectionState.CLOSED and not link.connected
        await link.connect(timeout=10)
        assert states == [ConnectionState.CONNECTING, ConnectionState.CONNECTED]
        assert link.connected and link.link is not None and link.link.name == transport
        assert link.node("pad").id == "pad" and link.node("pad").id == "pad#2"  # the interface's part too

        proxy.cut()
        await until(lambda: link.stats.connects == 2 and link.state is ConnectionState.CONNECTED,
                    what="the reconnect")
        assert states == [ConnectionState.CONNECTING, ConnectionState.CONNECTED, ConnectionState.RECONNECTING,
                          ConnectionState.CONNECTED]
        assert link.downs == 1
        gc.collect()  # the test's own frames may hold it for a moment; the shell must not
        await until(lambda: link.ups[0]() is None, what="the lost link released")
        assert link.last_error is not None and link.last_error.__traceback__ is None

        await link.close()
        assert states[-1] is ConnectionState.CLOSED and link.downs == 2 and link.link is None
        await link.close()  # twice is harmless
        assert states.count(ConnectionState.CLOSED) == 1


async def test_a_third_protocol_reports_failed_attempts_in_words_with_the_next_one():
    proxy = await StallProxy("127.0.0.1", 9).start()  # nothing listens behind it: every attempt is reset
    proxy.refuse(True)
    link = Quiet(proxy.url, backoff_min=0.05, backoff_max=0.1)
    failures: list[Failure] = []
    link.add_failure_listener(failures.append)
    try:
        with pytest.raises(TimeoutError, match="not connected"):
            await link.connect(timeout=0.5)
        assert link.state is ConnectionState.CONNECTING  # still the first connect's attempts
        assert failures and all(not f.fatal and f.retry_at is not None for f in failures)
        assert link.failure is failures[-1]
        with pytest.raises(TimeoutError):  # while it is trying, a caller waits (within its own time)
            await asyncio.wait_for(link.wait_connected(), 0.05)
    finally:
        await link.close()
        await proxy.stop()
    assert link.state is ConnectionState.CLOSED


async def test_a_protocol_gives_up_when_its_lost_link_must_not_be_reopened(sim):
    async with StallProxy("127.0.0.1", sim.port) as proxy:
        link = Quiet(proxy.url, refuse_after=True, backoff_min=0.02, backoff_max=0.05)
        await link.connect(timeout=10)
        proxy.cut()
        await until(lambda: link.state is ConnectionState.CLOSED, what="gave up")
        assert link.failure is not None and link.failure.fatal and link.failure.reason == "robot refused authentication"
        assert link.stats.connects == 1 and proxy.connections == 1
        await link.close()


# ---------------------------------------------------------------------- connecting again after close()


async def _connect_again_to_a_robot_gone(client: Any, proxy: StallProxy) -> list[ConnectionState]:
    await client.connect(timeout=10)
    await client.close()
    proxy.refuse(True)
    states: list[ConnectionState] = []
    client.add_state_listener(states.append)
    with pytest.raises(TimeoutError):
        await client.connect(timeout=0.5)
    await client.close()
    return states


async def test_a_closed_rosbridge_client_connecting_again_says_connecting(sim, transport):
    async with StallProxy("127.0.0.1", sim.port) as proxy:
        client = BridgeClient(proxy.url, backoff_min=0.02, backoff_max=0.05)
        states = await _connect_again_to_a_robot_gone(client, proxy)
    assert states == [ConnectionState.CONNECTING, ConnectionState.CLOSED]


async def test_a_closed_foxglove_client_connecting_again_says_connecting(fox, transport):
    """It said RECONNECTING from its second attempt on, as if a link of this connect() had been lost."""
    async with StallProxy("127.0.0.1", fox.port) as proxy:
        client = FoxgloveClient(proxy.url, backoff_min=0.02, backoff_max=0.05)
        states = await _connect_again_to_a_robot_gone(client, proxy)
    assert states == [ConnectionState.CONNECTING, ConnectionState.CLOSED]


# ------------------------------------------------------------------------------------------ import order

ENTRIES = ["rcon_core.link", "rcon_core.link.connection", "rcon_core.link.iface", "rcon_core.bridge",
           "rcon_core.bridge.client", "rcon_core.bridge.reasons", "rcon_core.foxglove", "rcon_core.foxglove.client",
           "rcon_core.foxglove.ws", "rcon_core.canvas.runtime"]


@pytest.mark.parametrize("module", ENTRIES)
def test_each_entry_module_imports_first_in_a_fresh_interpreter(module):
    """``bridge/client.py`` builds on ``link/connection.py``, which uses bridge modules: whichever a program
    imports first, the package imports settle (``rcon_core/link/__init__.py`` says how)."""
    proc = subprocess.run([sys.executable, "-c", f"import {module}"], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr[-2000:]
