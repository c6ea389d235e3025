"""BridgeThread (the loop in a daemon thread) and the LatestValue mailbox."""

from __future__ import annotations

import asyncio
import threading

import pytest
from replay_server import ScriptedServer

from rcon_core.bridge import BridgeClient
from rcon_core.bridge.threaded import BridgeThread, LatestValue
from rcon_core.testing import until_sync

pytestmark = pytest.mark.usefixtures("transport")  # every test runs on each transport


def test_run_and_call_cross_threads():
    bt = BridgeThread().start()
    try:
        async def where():
            await asyncio.sleep(0)
            return threading.current_thread().name

        assert bt.run(where()).result(5) == "rcon-bridge"
        assert bt.call(lambda a, b: (a + b, threading.current_thread().name), 2, 3).result(5) == (5, "rcon-bridge")

        def boom():
            raise KeyError("x")

        with pytest.raises(KeyError):
            bt.call(boom).result(5)
        with pytest.raises(RuntimeError, match="already started"):
            bt.start()
    finally:
        bt.stop()
    assert not bt.running
    with pytest.raises(RuntimeError, match="not running"):
        bt.call(print)


def test_stop_cancels_pending_tasks():
    cancelled = threading.Event()

    async def forever():
        try:
            await asyncio.sleep(3600)
        except asyncio.CancelledError:
            cancelled.set()
            raise

    with BridgeThread() as bt:
        bt.run(forever())
        bt.call(lambda: None).result(5)
    assert cancelled.wait(5)


def test_latest_value_wins_and_counts_drops():
    woken = []
    box = LatestValue(on_put=lambda: woken.append(1))
    assert box.take() == (False, None) and not box
    box.put(1)
    box.put(2)
    box.put(3)
    assert box.peek() == (True, 3)
    assert box.take() == (True, 3)
    assert box.take() == (False, None)
    assert box.seq == 3 and box.dropped == 2 and len(woken) == 3
    box.put(None)  # None is a value like any other
    assert box.take() == (True, None)


def test_latest_value_is_thread_safe():
    box = LatestValue()
    taken = []
    done = threading.Event()

    def consumer():
        while not done.is_set() or box:
            ok, v = box.take()
            if ok:
                taken.append(v)

    t = threading.Thread(target=consumer)
    t.start()
    for i in range(20000):
        box.put(i)
    done.set()
    t.join(10)
    assert taken == sorted(taken) and taken[-1] == 19999
    assert len(taken) + box.dropped == 20000


def test_client_on_the_thread_feeds_a_mailbox_decoded():
    """The GUI pattern: the client runs on the bridge thread, the GUI thread only takes finished dicts."""
    with BridgeThread() as bt:
        server = ScriptedServer()
        bt.run(server.start()).result(5)
        box = LatestValue()
        threads = set()

        def on_msg(msg):
            threads.add(threading.current_thread().name)
            box.put(msg)

        async def setup():
            c = BridgeClient(server.url)
            await c.connect(timeout=5)
            c.node("gui").subscribe("/rec/str", on_msg)
            return c

        client = bt.run(setup()).result(5)
        ok, msg = until_sync(lambda: (got := box.take())[0] and got, what="the message in the box")
        assert ok and "café" in msg["data"]
        assert threads == {"rcon-bridge"}
        bt.run(client.close()).result(5)
        bt.run(server.stop()).result(5)


def test_the_bridge_thread_runs_uvloop_where_installed_and_asyncio_when_told(monkeypatch):
    import sys

    fast = pytest.importorskip("winloop" if sys.platform == "win32" else "uvloop")
    with BridgeThread() as bt:
        assert isinstance(bt.loop, fast.Loop)
    monkeypatch.setenv("RCON_EVENT_LOOP", "asyncio")
    with BridgeThread() as bt:
        assert type(bt.loop).__module__.startswith("asyncio")
