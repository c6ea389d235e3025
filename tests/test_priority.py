"""Background threads at a lower OS priority (``rcon_core/priority.py``): the image widget's decode worker
and the sim's camera threads run below the GUI and bridge threads; the threads that serve the operator and
the link keep theirs."""

from __future__ import annotations

import asyncio
import os
import sys
import threading

import pytest

from rcon_core.priority import BACKGROUND_NICE, lower_this_thread, thread_nice
from rcon_core.testing import until

linux = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="thread nice values are Linux's")


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


@linux
def test_lowering_a_thread_leaves_the_others_alone():
    mine = thread_nice(threading.get_native_id())
    done, nice = in_thread(lower_this_thread)
    assert done and nice == max(mine, BACKGROUND_NICE)
    assert thread_nice(threading.get_native_id()) == mine  # the calling thread (and process) unchanged
    assert os.getpriority(os.PRIO_PROCESS, 0) == mine


@linux
def test_a_thread_already_lower_is_not_raised():
    def twice() -> bool:
        lower_this_thread(15)
        return lower_this_thread(5)

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
    cameras = [thread_nice(t.native_id) for t in threading.enumerate() if t.name.startswith("sim-camera")]
    assert cameras and all(v is not None and v >= BACKGROUND_NICE for v in cameras), cameras
    loop_nice = thread_nice(sim_thread.run_sync(threading.get_native_id))
    assert loop_nice is not None and loop_nice < BACKGROUND_NICE
