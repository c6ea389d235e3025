"""The collector policy (``rcon_core/gcpolicy.py``): what a settle freezes and frees, when it runs, and that
the app's window and the sim ask for it at the documented moments."""

from __future__ import annotations

import asyncio
import gc
import time
import weakref
from pathlib import Path

import pytest

from rcon_core.gcpolicy import CollectorPolicy, keep_settled
from rcon_core.testing import ManualClock, until


class Node:
    def __init__(self) -> None:
        self.other: Node | None = None


def cycle() -> weakref.ref[Node]:
    """A two-object reference cycle, held only by ``keep`` (clear it to make the cycle garbage)."""
    a, b = Node(), Node()
    a.other, b.other = b, a
    keep.append(a)
    return weakref.ref(a)


keep: list[Node] = []


@pytest.fixture(autouse=True)
def unfrozen():
    """Every test leaves the process's collector as it found it (nothing frozen)."""
    yield
    keep.clear()
    gc.unfreeze()
    gc.collect()


def test_a_settle_freezes_what_is_alive_and_refcounting_still_frees_it():
    ref = weakref.ref(obj := Node())
    before = gc.get_freeze_count()
    CollectorPolicy().settle()
    assert gc.get_freeze_count() > before
    del obj  # frozen objects are still freed the moment nothing refers to them
    assert ref() is None


def test_cyclic_garbage_among_frozen_objects_waits_for_a_full_settle():
    policy = CollectorPolicy()
    ref = cycle()
    policy.settle()  # the cycle is alive (``keep``): frozen
    keep.clear()  # now it is garbage, but only a cycle: reference counting cannot free it
    gc.collect()
    assert ref() is not None, "a light collection walks only what was made since the freeze"
    policy.settle()
    assert ref() is not None
    policy.settle(full=True)
    assert ref() is None
    assert (policy.settles, policy.full_settles, len(policy.pauses_ms)) == (3, 1, 3)


def test_cyclic_garbage_made_after_a_settle_is_collected_as_usual():
    policy = CollectorPolicy()
    policy.settle()
    ref = cycle()
    keep.clear()
    gc.collect()
    assert ref() is None


def test_when_it_settles():
    clock = ManualClock()
    policy = CollectorPolicy(every=60.0, clock=clock)
    assert not policy.poll() and policy.due is None
    policy.soon(5.0)
    policy.soon(2.0, full=True)  # the earliest wins; a full request stays full
    assert policy.due == clock() + 2.0
    clock.advance(1.9)
    assert not policy.poll()
    clock.advance(0.2)
    assert policy.poll() and (policy.settles, policy.full_settles) == (1, 1) and policy.due is None
    clock.advance(59.0)
    assert not policy.poll()
    clock.advance(1.5)  # the period, counted from the last settle
    assert policy.poll() and (policy.settles, policy.full_settles) == (2, 1)


def test_keep_settled_settles_fully_at_once_then_lightly_on_its_period():
    policy = CollectorPolicy(every=0.01)

    async def run() -> None:
        task = asyncio.get_running_loop().create_task(keep_settled(policy))
        await until(lambda: policy.settles >= 3, what="three settles")
        task.cancel()

    asyncio.run(asyncio.wait_for(run(), 10))
    assert policy.full_settles == 1 and policy.settles >= 3


# -- the app's window --------------------------------------------------------------------------------------


@pytest.mark.usefixtures("qapp")
def test_the_window_settles_after_start_a_canvas_switch_and_a_robot_connecting(qtbot, tmp_path: Path, plugins,
                                                                               sim_url: str):
    from rcon_core.app.config import AppConfig
    from rcon_core.app.main_window import SETTLE_AFTER_CONNECT, MainWindow
    from rcon_core.bridge import ConnectionState

    policy = CollectorPolicy()
    win = MainWindow(AppConfig(tmp_path / "cfg"), plugins, collector=policy)
    qtbot.addWidget(win)
    win.show()
    try:
        qtbot.waitUntil(lambda: policy.full_settles == 1, timeout=10_000)  # once built and shown
        win.new_canvas()  # shows the new canvas: widgets of the old one were dropped
        qtbot.waitUntil(lambda: policy.full_settles == 2, timeout=10_000)
        settles = policy.settles
        win.connect_to(sim_url)
        qtbot.waitUntil(lambda: win.connection.state is ConnectionState.CONNECTED, timeout=10_000)
        assert policy.due is not None and policy.due - time.monotonic() > SETTLE_AFTER_CONNECT - 1.0
        assert policy.settles == settles  # not at once: the catalogue arrives first
    finally:
        win.shutdown()


@pytest.mark.usefixtures("qapp")
def test_a_window_without_a_policy_leaves_the_collector_alone(qtbot, tmp_path: Path, plugins):
    from rcon_core.app.config import AppConfig
    from rcon_core.app.main_window import MainWindow

    frozen = gc.get_freeze_count()
    win = MainWindow(AppConfig(tmp_path / "cfg"), plugins)
    qtbot.addWidget(win)
    ticks: list[float] = []
    win.clock.add(ticks.append)  # after any poll the window registered: a policy's would run first
    win.show()
    shown = time.monotonic()
    try:
        win.new_canvas()  # another canvas: the moment a policy is asked for a full settle at once
        switched = time.monotonic()
        # the frame clock ran past the moments a policy's settles would come (1 s after start, at once
        # after a canvas switch): a settle would have happened on those ticks
        qtbot.waitUntil(lambda: len(ticks) >= 2 and ticks[-1] >= max(shown + 1.0, switched), timeout=10_000)
        assert win.collector is None and gc.get_freeze_count() == frozen
    finally:
        win.shutdown()
