"""Background threads at a lower OS priority than the ones that serve the operator and the robot (no Qt).

Decision: who waits when the CPU is short
    On a two-core tablet with several robots streaming, more threads want the CPU than there are cores:
    the GUI thread (painting), the bridge thread (reading frames, and timing the teleop pad's commands),
    and the workers that decode camera frames (one per image widget).  Left at the same priority, the
    scheduler shares the cores evenly, and a command or a repaint waits behind a JPEG decode.  A frame
    decode that waits costs little (the latest frame wins, an older one is dropped); a late command or a
    late paint is what the operator feels.  So bulk work runs on threads that call
    :func:`lower_this_thread` first: they get whatever CPU the GUI and the link leave.

    Measured with ``python benchmarks/bench_app.py --robots 3`` on a busy two-core machine (runs
    alternated, so both saw the same load): GUI frame p95 36-180 ms -> 17-53 ms, values publish-to-painted
    p99 276-743 ms -> 60-158 ms (five runs each) with the decode workers (and the sim's camera threads) lowered.

    The sim's camera threads do the same (on a real robot the camera drivers are other processes than
    rosbridge; here they share one, and the loop that receives commands comes first).

Linux: the calling thread's nice value is raised (``os.setpriority`` on the thread's id: Linux schedules
threads as tasks); no privilege is needed to lower one's own priority.  Windows: the calling thread's
priority becomes ``THREAD_PRIORITY_BELOW_NORMAL``.  Elsewhere (macOS: ``setpriority`` would lower the
whole process) nothing is done.  It never raises: a thread that cannot be lowered runs as it is.
"""

from __future__ import annotations

import logging
import os
import sys
import threading

log = logging.getLogger(__name__)

#: the nice value background threads get on Linux (0 normal .. 19 lowest)
BACKGROUND_NICE = 10
_THREAD_PRIORITY_BELOW_NORMAL = -1


def lower_this_thread(nice: int = BACKGROUND_NICE) -> bool:
    """Give the calling thread a lower scheduling priority (see the module docstring); True when done."""
    try:
        if sys.platform.startswith("linux"):
            tid = threading.get_native_id()
            current = os.getpriority(os.PRIO_PROCESS, tid)
            os.setpriority(os.PRIO_PROCESS, tid, max(current, nice))
            return True
        if sys.platform == "win32":
            import ctypes

            kernel32 = ctypes.windll.kernel32  # type: ignore[attr-defined]
            return bool(kernel32.SetThreadPriority(kernel32.GetCurrentThread(), _THREAD_PRIORITY_BELOW_NORMAL))
    except (OSError, AttributeError, ValueError) as exc:
        log.debug("could not lower the priority of %s: %s", threading.current_thread().name, exc)
    return False


def thread_nice(native_id: int) -> int | None:
    """The nice value of thread ``native_id`` of this process (Linux), else None; for tests and diagnostics."""
    if not sys.platform.startswith("linux"):
        return None
    try:
        return os.getpriority(os.PRIO_PROCESS, native_id)
    except OSError:
        return None
