"""Who waits when the CPU is short (``rcon_core/priority.py``): the image widget's decode worker and the
sim's camera threads run below the GUI and bridge threads; the threads that serve the operator and the
link -- the bridge thread, the sim's loop, the thread that calls ``favour_latency`` -- are raised (on Linux
a short scheduling slice, which threads they start do not inherit), and ``favour_latency`` shortens the
GIL's switch interval."""

from __future__ import annotations

import asyncio
import os
import sys
import threading

import pytest

from rcon_core.priority import (
    BACKGROUND_NICE,
    LATENCY_SLICE_NS,
    SWITCH_INTERVAL,
    favour_latency,
    lower_this_thread,
    raise_this_thread,
    thread_nice,
    thread_slice_ns,
)
from rcon_core.testing import until, until_sync

linux = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="thread nice values are Linux's")
#: the scheduler reports each thread's slice (Linux's EEVDF, 6.6 on): what raising a thread changes there
eevdf = pytest.mark.skipif(not sys.platform.startswith("linux") or thread_slice_ns(threading.get_native_id()) is None,
                           reason="no EEVDF scheduler here: a raised thread's slice cannot be seen")


def in_thread(fn):
    """Run ``fn`` on a new thread; (its result, the thread's nice value afterwards as the OS reports it)."""
    out = {}

    def run() -> None:
        out["result"] = fn()
        out["nice"] = thread_nice(threading.get_native_id())

    t = threading.Thread(target=run)
    t.start()
    t.join(10)
    return out["result"], out["nice"]


def policy_of(native_id: int) -> int:
    return os.sched_getscheduler(native_id) & ~os.SCHED_RESET_ON_FORK


@linux
def test_lowering_a_thread_leaves_the_others_alone():
    mine = thread_nice(threading.get_native_id())
    out: dict = {}

    def lower() -> bool:
        out["policy"] = (lower_this_thread(), policy_of(threading.get_native_id()))
        return out["policy"][0]

    done, nice = in_thread(lower)
    assert done and nice == max(mine, BACKGROUND_NICE)
    # a batch thread: it never preempts the GUI or the bridge thread when it wakes, yet is not so low that
    # it sits on the GIL for long while a busier thread has its core (see the module docstring)
    assert out["policy"][1] == os.SCHED_BATCH
    assert policy_of(threading.get_native_id()) == os.SCHED_OTHER
    assert thread_nice(threading.get_native_id()) == mine  # the calling thread (and process) unchanged
    assert os.getpriority(os.PRIO_PROCESS, 0) == mine


@linux
def test_a_thread_already_lower_is_not_raised():
    def twice() -> bool:
        lower_this_thread(15)
        return lower_this_thread(3)

    done, nice = in_thread(twice)
    assert done and nice == 15


@linux
def test_the_image_decode_worker_runs_in_the_background():
    from rcon_widgets_sensors.slots import SlotWorker

    seen: list[int | None] = []
    worker = SlotWorker("decode-test", lambda _item: seen.append(thread_nice(threading.get_native_id())))
    try:
        worker.submit(1)
        asyncio.run(until(lambda: seen, what="the worker handled the item"))
    finally:
        worker.close()
    assert seen[0] is not None and seen[0] >= BACKGROUND_NICE
    assert thread_nice(threading.get_native_id()) < BACKGROUND_NICE


@linux
def test_the_recorders_writer_runs_in_the_background(tmp_path):
    """The recorder's writer (compressing and writing a camera's frames: more CPU than receiving them) runs
    below the thread that receives: on a 2-core machine beside a robot's process it had preempted the
    receiving thread about 40 times a second (``rcon record`` of a 120 Hz camera), now about once."""
    from rcon_core.record.writer import McapSink

    sink = McapSink(str(tmp_path / "run.mcap"), "ros1")
    try:
        thread = sink._thread
        until_sync(lambda: thread.native_id is not None and thread_nice(thread.native_id) == max(
            thread_nice(threading.get_native_id()) or 0, BACKGROUND_NICE), what="the writer lowered")
        assert policy_of(thread.native_id) == os.SCHED_BATCH
        assert thread_nice(threading.get_native_id()) < BACKGROUND_NICE  # the caller's thread unchanged
    finally:
        sink.close()


@linux
def test_the_sims_camera_threads_run_below_its_loop(sim_thread):
    """The camera threads of a sim (a client subscribes, so frames are drawn) are lowered; its loop is not."""
    from rcon_core.bridge import BridgeClient

    async def look() -> None:
        async with BridgeClient(sim_thread.url, reconnect=False) as client:
            got = asyncio.Event()
            client.node("t").subscribe("/camera/rear/image_raw/compressed", lambda _msg: got.set(),
                                       type="sensor_msgs/CompressedImage")
            await asyncio.wait_for(got.wait(), 10)

    asyncio.run(look())
    # a camera thread just started may not have its native id yet (threading sets it as the thread begins)
    threads = [t for t in threading.enumerate() if t.name.startswith("sim-camera")]
    until_sync(lambda: all(t.native_id is not None or not t.is_alive() for t in threads),
               what="the camera threads running")
    cameras = [thread_nice(t.native_id) for t in threads if t.native_id is not None]
    assert cameras and all(v is not None and v >= BACKGROUND_NICE for v in cameras), cameras
    loop_nice = thread_nice(sim_thread.run_sync(threading.get_native_id))
    assert loop_nice is not None and loop_nice < BACKGROUND_NICE


def slice_of_thread_started_by(fn) -> tuple[bool, int | None, int | None]:
    """On a new thread: ``fn()``, then (its result, that thread's slice, the slice of a thread it starts)."""
    out: dict = {}

    def child() -> None:
        out["child"] = thread_slice_ns(threading.get_native_id())

    def run() -> None:
        out["result"] = fn()
        out["own"] = thread_slice_ns(threading.get_native_id())
        t = threading.Thread(target=child)
        t.start()
        t.join(10)

    t = threading.Thread(target=run)
    t.start()
    t.join(10)
    return out["result"], out["own"], out["child"]


def default_slice() -> int | None:
    """The slice a plain new thread gets. Not the test's own thread's: earlier tests in the same process
    (the app's, whose GUI thread is this one) may have raised it; a thread it starts is not raised."""
    _done, own, _child = slice_of_thread_started_by(lambda: True)
    return own


@eevdf
def test_a_raised_thread_asks_for_a_short_slice_its_threads_do_not_inherit():
    default = default_slice()
    mine = thread_slice_ns(threading.get_native_id())
    done, own, child = slice_of_thread_started_by(raise_this_thread)
    assert done and own == LATENCY_SLICE_NS != default
    assert child == default  # a worker started by the bridge thread is not raised with it
    assert thread_slice_ns(threading.get_native_id()) == mine  # the caller's own thread unchanged


@eevdf
def test_lowering_a_raised_thread_gives_it_the_default_slice_again():
    default = default_slice()

    def raise_then_lower() -> bool:
        raise_this_thread()
        return lower_this_thread()

    def check() -> bool:
        done = raise_then_lower()
        return done and policy_of(threading.get_native_id()) == os.SCHED_BATCH

    done, own, _child = slice_of_thread_started_by(check)
    assert done and own == default


@eevdf
def test_the_bridge_thread_and_the_sims_loop_are_raised(sim_thread):
    from rcon_core.bridge.threaded import BridgeThread

    with BridgeThread() as bt:
        bridge = bt.call(threading.get_native_id).result(5)
        assert thread_slice_ns(bridge) == LATENCY_SLICE_NS
    assert thread_slice_ns(sim_thread.run_sync(threading.get_native_id)) == LATENCY_SLICE_NS


@linux
def test_an_image_worker_started_on_the_raised_bridge_thread_runs_in_the_background():
    """The image widget starts its decode worker from the bridge loop (its first frame): the worker is
    lowered, and does not keep the bridge thread's short slice."""
    from rcon_widgets_sensors.slots import SlotWorker

    from rcon_core.bridge.threaded import BridgeThread

    seen: list[tuple[int | None, int | None]] = []
    with BridgeThread() as bt:
        worker = bt.call(lambda: SlotWorker("decode-test", lambda _item: seen.append(
            (thread_nice(threading.get_native_id()), thread_slice_ns(threading.get_native_id()))))).result(5)
        try:
            worker.submit(1)
            asyncio.run(until(lambda: seen, what="the worker handled the item"))
        finally:
            worker.close()
    nice, slice_ns = seen[0]
    assert nice is not None and nice >= BACKGROUND_NICE
    assert slice_ns is None or slice_ns != LATENCY_SLICE_NS


def test_favour_latency_shortens_the_gil_switch_interval():
    before = sys.getswitchinterval()

    def run() -> bool:
        return favour_latency()

    try:
        done, own, _child = slice_of_thread_started_by(run)
        assert sys.getswitchinterval() == pytest.approx(SWITCH_INTERVAL)
        assert SWITCH_INTERVAL < 0.005  # shorter than CPython's default
        if own is not None:  # Linux with EEVDF: the calling thread raised
            assert done and own == LATENCY_SLICE_NS
    finally:
        sys.setswitchinterval(before)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="OS thread names: Linux")
def test_a_thread_named_at_the_os_level_shows_its_name_to_top_and_the_benchmarks() -> None:
    import threading

    from rcon_core.priority import name_this_thread

    seen: list[str] = []

    def run() -> None:
        assert name_this_thread("rcon-a-long-thread-name")
        with open(f"/proc/self/task/{threading.get_native_id()}/comm") as f:
            seen.append(f.read().strip())

    t = threading.Thread(target=run)
    t.start()
    t.join()
    assert seen == ["rcon-a-long-thr"]  # the kernel keeps 15 bytes
