"""Who waits when the CPU is short: thread priorities and the GIL's switch interval (no Qt).

Decision: who waits when the CPU is short
    On a two-core tablet with several robots streaming, more threads want the CPU than there are cores:
    the GUI thread (painting), the bridge thread (reading frames, and timing and writing the teleop pad's
    commands), and the workers that decode camera frames (one per image widget).  Left at the same
    priority, the scheduler shares the cores evenly, and a command or a repaint waits behind a JPEG decode.
    A frame decode that waits costs little (the latest frame wins, an older one is dropped); a late command
    or a late paint is what the operator feels.  So:

    * bulk work runs on threads that call :func:`lower_this_thread` first: they get whatever CPU the GUI
      and the link leave.  Measured with ``python benchmarks/bench_app.py --robots 3`` on a busy two-core
      machine (runs alternated, so both saw the same load): GUI frame p95 36-180 ms -> 17-53 ms, values
      publish-to-painted p99 276-743 ms -> 60-158 ms (five runs each) with the decode workers (and the
      sim's camera threads) lowered.  The sim's camera threads do the same (on a real robot the camera
      drivers are other processes than rosbridge; here they share one, and the loop that receives
      commands comes first).
    * the threads that serve the operator and the robot -- the GUI thread, the bridge thread, the sim's
      loop -- call :func:`raise_this_thread`: as soon as one wakes (a frame arrived, a command is due, a
      paint is due) it gets a core, instead of waiting for a busy thread's slice to end.
    * :func:`favour_latency` (the app's and ``rcon sim``'s entry points) also shortens the GIL's switch
      interval to :data:`SWITCH_INTERVAL`: a thread that wakes while another holds the GIL asks for it
      after that long instead of CPython's 5 ms.  What delays a teleop command is mostly that wait: the
      GUI thread holds the GIL about 40 % of the time with a 3-robot fleet canvas
      (``py-spy record --gil``), and a command due while it paints waits for it to let go; the bridge
      loop's own work before the command's timer adds little (``benchmarks/wake_probes.py``: a plain
      thread sleeping to the same schedule is late by about as much as the loop's timer).

Linux: lowering raises the calling thread's nice value (``os.setpriority`` on the thread's id: Linux
schedules threads as tasks; no privilege is needed to lower one's own priority).  Raising cannot lower the
nice value without privilege; it asks for a short scheduling slice instead (``sched_setattr``, SCHED_OTHER
kept, no privilege needed): Linux's EEVDF scheduler (6.6 on; a short slice preempts on wake-up since 6.12)
gives such a thread an early deadline whenever it wakes, so it runs before a busy thread whose slice is
not over, while its share of the CPU stays what it was.  Threads it starts do not inherit the short slice
(``SCHED_FLAG_RESET_ON_FORK``).  Older kernels accept and ignore the request.  Windows: lowered threads
get ``THREAD_PRIORITY_BELOW_NORMAL``, raised ones ``THREAD_PRIORITY_ABOVE_NORMAL`` (both within the
process's class, allowed to any process).  macOS: the utility and the user-interactive quality of service
(``setpriority`` would change the whole process).  Nothing here raises: a thread the OS refuses runs as
it is.
"""

from __future__ import annotations

import contextlib
import ctypes
import logging
import os
import platform
import sys
import threading

log = logging.getLogger(__name__)

#: the nice value background threads get on Linux (0 normal .. 19 lowest), with SCHED_BATCH
BACKGROUND_NICE = 5
#: the scheduling slice a raised thread asks for on Linux (ns; the kernel's default is 0.7-3 ms)
LATENCY_SLICE_NS = 300_000
#: the GIL's switch interval in a process that serves an operator or a robot (s; CPython's default 0.005)
SWITCH_INTERVAL = 0.001

_THREAD_PRIORITY_BELOW_NORMAL = -1
_THREAD_PRIORITY_ABOVE_NORMAL = 1
_QOS_CLASS_USER_INTERACTIVE = 0x21
_QOS_CLASS_UTILITY = 0x11
_SCHED_FLAG_RESET_ON_FORK = 0x01
_SCHED_RESET_ON_FORK = 0x40000000  # or'ed into the policy sched_getscheduler reports
#: sched_setattr's system call number by machine (Linux)
_SYS_SCHED_SETATTR = {"x86_64": 314, "amd64": 314, "aarch64": 274, "arm64": 274, "i686": 351, "i386": 351,
                      "armv7l": 380, "armv8l": 380, "riscv64": 274, "ppc64le": 355, "s390x": 345}


class _SchedAttr(ctypes.Structure):
    _fields_ = [("size", ctypes.c_uint32), ("sched_policy", ctypes.c_uint32), ("sched_flags", ctypes.c_uint64),
                ("sched_nice", ctypes.c_int32), ("sched_priority", ctypes.c_uint32),
                ("sched_runtime", ctypes.c_uint64), ("sched_deadline", ctypes.c_uint64),
                ("sched_period", ctypes.c_uint64), ("sched_util_min", ctypes.c_uint32),
                ("sched_util_max", ctypes.c_uint32)]


def _linux_slice(slice_ns: int) -> bool:
    """Set the calling thread's scheduling slice (0: the kernel's default), its policy and nice kept; the
    threads it starts get the defaults (SCHED_FLAG_RESET_ON_FORK: once set, only a privileged process may
    clear it again, so it is always passed)."""
    number = _SYS_SCHED_SETATTR.get(platform.machine().lower())
    if number is None:
        return False
    tid = threading.get_native_id()
    attr = _SchedAttr(size=ctypes.sizeof(_SchedAttr), sched_policy=os.sched_getscheduler(tid) & ~_SCHED_RESET_ON_FORK,
                      sched_flags=_SCHED_FLAG_RESET_ON_FORK,
                      sched_nice=os.getpriority(os.PRIO_PROCESS, tid), sched_runtime=slice_ns)
    libc = ctypes.CDLL(None, use_errno=True)
    return bool(libc.syscall(number, tid, ctypes.byref(attr), 0) == 0)


def _mac_qos(qos: int) -> bool:
    libc = ctypes.CDLL(None)
    return bool(libc.pthread_set_qos_class_self_np(qos, 0) == 0)


def lower_this_thread(nice: int = BACKGROUND_NICE) -> bool:
    """Give the calling thread a lower scheduling priority (see the module docstring); True when done."""
    try:
        if sys.platform.startswith("linux"):
            tid = threading.get_native_id()
            with contextlib.suppress(OSError):  # a kernel without SCHED_BATCH: the nice value alone
                os.sched_setscheduler(tid, os.SCHED_BATCH | _SCHED_RESET_ON_FORK, os.sched_param(0))
            current = os.getpriority(os.PRIO_PROCESS, tid)
            os.setpriority(os.PRIO_PROCESS, tid, max(current, nice))
            _linux_slice(0)  # the default slice, should it have been raised
            return True
        if sys.platform == "win32":
            kernel32 = ctypes.windll.kernel32  # type: ignore[attr-defined]
            return bool(kernel32.SetThreadPriority(kernel32.GetCurrentThread(), _THREAD_PRIORITY_BELOW_NORMAL))
        if sys.platform == "darwin":
            return _mac_qos(_QOS_CLASS_UTILITY)
    except (OSError, AttributeError, ValueError) as exc:
        log.debug("could not lower the priority of %s: %s", threading.current_thread().name, exc)
    return False


def raise_this_thread() -> bool:
    """Ask the OS to run the calling thread as soon as it wakes, as far as an unprivileged process may
    (see the module docstring); True when the OS took the request."""
    try:
        if sys.platform.startswith("linux"):
            return _linux_slice(LATENCY_SLICE_NS)
        if sys.platform == "win32":
            kernel32 = ctypes.windll.kernel32  # type: ignore[attr-defined]
            return bool(kernel32.SetThreadPriority(kernel32.GetCurrentThread(), _THREAD_PRIORITY_ABOVE_NORMAL))
        if sys.platform == "darwin":
            return _mac_qos(_QOS_CLASS_USER_INTERACTIVE)
    except (OSError, AttributeError, ValueError) as exc:
        log.debug("could not raise the priority of %s: %s", threading.current_thread().name, exc)
    return False


def favour_latency() -> bool:
    """The policy of a process that serves an operator or a robot, called by its main thread (the app's GUI
    thread, ``rcon sim``'s loop): the GIL's switch interval becomes :data:`SWITCH_INTERVAL` and the calling
    thread is raised (:func:`raise_this_thread`). True when the thread was raised."""
    sys.setswitchinterval(SWITCH_INTERVAL)
    return raise_this_thread()


def name_this_thread(name: str) -> bool:
    """Give the calling thread its name at the OS level too (Linux: the first 15 bytes, what ``top -H``,
    ``ps -L`` and ``/proc/<pid>/task/<tid>/comm`` show; Python before 3.14 leaves every thread "python"),
    so a person or a benchmark can tell the recorder's writer from the bridge thread. True when done."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL(None)
        return bool(libc.prctl(15, ctypes.c_char_p(name.encode()[:15]), 0, 0, 0) == 0)  # PR_SET_NAME
    except (OSError, AttributeError, ValueError):
        return False


def thread_nice(native_id: int) -> int | None:
    """The nice value of thread ``native_id`` of this process (Linux), else None; for tests and diagnostics."""
    if not sys.platform.startswith("linux"):
        return None
    try:
        return os.getpriority(os.PRIO_PROCESS, native_id)
    except OSError:
        return None


def thread_slice_ns(native_id: int) -> int | None:
    """The scheduling slice of thread ``native_id`` of this process (Linux with EEVDF), else None; for tests
    and diagnostics."""
    try:
        with open(f"/proc/self/task/{native_id}/sched") as f:
            for line in f:
                if line.startswith("se.slice"):
                    return int(line.split(":")[1])
    except (OSError, ValueError):
        pass
    return None
